//! Pre-deployment planning (Hudson §4.1): the survey AUVs' tracks are known a priori, and the
//! planner is stepped over the whole mission to produce the CNA's waypoints, the modelled errors
//! and the metrics. Scenario files, track CSVs, the runner, metrics and the run directory.

pub mod metrics;
pub mod runner;

pub use crate::scenario::plan::{Mission, Scenario, ScenarioError, EXAMPLE};
pub use metrics::{StepRecord, Summary};
pub use runner::{run, step_count, RunError, RunResult, TrackForecast};
