//! The closed-loop mission simulator: one deterministic fast-time loop in which the CNA's policy
//! (the underway look-ahead planner or a baseline), the survey AUVs' OWTT navigation filters and
//! the acoustic link act on each other, judged on the survey AUVs' *true* navigation error.
//!
//! [`scenario`] reads the TOML file, [`crate::engine::run`] runs one mission, [`mc`] compares policies
//! over seeded Monte Carlo runs, and [`output`] writes a run directory with plots and a report.

pub use crate::batch::mc::{
    compare, comparison_table, monte_carlo, monte_carlo_grid, monte_carlo_until, Comparison, PolicySummary,
};
pub use crate::engine::{run, run_traced, Faults, PhaseClock, RunResult, Timing};
pub use crate::policy::planner::{ErrorTracker, PlannerPolicy, PlannerStats};
pub use crate::policy::registry::{Policy, PolicyError, PolicySpec, POLICY_NAMES};
pub use crate::scenario::world::{BeforeFirstReport, Scenario, ScenarioError, EXAMPLE};

#[cfg(test)]
mod tests;
