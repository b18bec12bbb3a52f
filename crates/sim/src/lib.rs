//! coopnav-sim: the fast-time world that joins the planner, the navigation filters and the
//! acoustic link.
//!
//! It owns scenario files, the mission [`engine`] and the [`models`] it plugs in, metrics, Monte
//! Carlo and the experiments that reproduce the theses' tables (see [`experiments`]).

pub mod batch;
pub mod engine;
pub mod experiments;
pub mod models;
pub mod observe;
pub mod output;
pub mod policy;
pub mod scenario;
