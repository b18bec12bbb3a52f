//! coopnav-plan: the CNA path planner of Hudson (2012).
//!
//! It owns the survey-AUV position-error model, the CNA motion options, the distance penalties,
//! the exact look-ahead tree search and the survey-track predictors. It does not simulate a world:
//! `coopnav-sim` drives it step by step.

pub mod predict;
