//! coopnav-plan: the CNA path planner of Hudson (2012).
//!
//! It owns the survey-AUV position-error model, the CNA motion options, the distance penalties,
//! the exact look-ahead tree search and the survey-track predictors. It does not simulate a world:
//! `coopnav-sim` drives it step by step.

//!
//! Entry points: [`LookAheadPlanner`] (a [`Planner`]) configured by [`PlannerConfig`], fed each
//! τ with the CNA pose, the AUVs' modelled errors ([`AuvError`]) and an [`AuvForecast`].
//! [`predeploy`] steps it over a whole pre-deployment mission whose survey tracks are known a
//! priori.

pub mod auto;
mod brute;
mod cost_model;
pub mod current_states;
pub mod error_model;
pub mod estimator;
pub mod horizon;
pub mod motion;
pub mod penalty;
pub mod planner;
pub mod predeploy;
pub mod predict;
mod search;
pub mod spec;
#[cfg(test)]
mod tests;
mod tree;
pub mod true_error;
pub mod workload;

pub use error_model::{AuvError, BearingMode, CostMode, ErrorModel};
pub use estimator::{
    expected_posterior, Aggregate, AuvEstimate, BiasTable, EstimatorSpec, LinkModel, LinkTable, RangeNoise,
};
pub use horizon::{GoalTerm, HorizonSpec};
pub use motion::{CnaKind, CnaPose, MotionConfig, MotionOption};
pub use penalty::{
    Doubling, NoPenalty, Penalty, PenaltyCase, PenaltyFn, PenaltyPair, ScaledViolation, SideTerm, Violation,
};
pub use planner::{
    Algorithm, AuvForecast, CostSpec, CurrentInput, Deadline, Decision, DistanceLimits, FnForecast, LookAheadPlanner,
    PlanInput, Planner, PlannerConfig, SearchConfig, SurveyInput,
};
pub use spec::{EstimatorCost, HudsonCost, PenaltySpec, PlannerCost, PlannerSpec, Platform, SearchSpec, TreeSpec};
pub use true_error::{TrueError, TruthInput, TruthSpec};

use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
pub enum PlanError {
    /// Every bad setting at once, each named as in `PlannerConfig` (`motion.tau`).
    #[error("invalid planner settings: {0}")]
    Invalid(#[from] coopnav_core::validation::InvalidFields),
    #[error("invalid planner input: {0}")]
    Input(String),
    #[error("no survey-AUV forecast at t = {t} s: the survey data has ended")]
    NoForecast { t: f64 },
    #[error("the decision deadline passed before even one look-ahead level was searched")]
    Deadline,
}

/// What a search finds: the best level-0 option, the minimum path cost and the nodes evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SearchOutcome {
    pub root_option: usize,
    pub value: f64,
    pub nodes: u64,
}
