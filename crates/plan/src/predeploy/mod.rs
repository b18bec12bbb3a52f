//! Pre-deployment planning (Hudson §4.1): the survey AUVs' tracks are known a priori, and the
//! planner is stepped over the whole mission to produce the CNA's waypoints, the modelled errors
//! and the metrics. The mission, the runner and the metrics (the scenario files and track CSVs that
//! build a mission are `coopnav_sim::scenario::plan` and `::tracks`, its run directory
//! `coopnav_sim::output::plan`).

pub mod metrics;
pub mod runner;

pub use metrics::{StepRecord, Summary};
pub use runner::{run, step_count, RunError, RunResult, TrackForecast};

use crate::{CnaPose, PlannerConfig};
use coopnav_core::Track;

/// A validated, ready-to-run pre-deployment mission.
#[derive(Debug, Clone)]
pub struct Mission {
    pub planner: PlannerConfig,
    pub cna: CnaPose,
    pub names: Vec<String>,
    pub tracks: Vec<Track>,
    pub sigma0: Vec<f64>,
    pub eps0: Vec<f64>,
    pub start_time: f64,
    pub end_time: f64,
}
