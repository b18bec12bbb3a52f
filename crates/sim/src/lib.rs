//! coopnav-sim: the fast-time world that joins the planner, the navigation filters and the
//! acoustic link.
//!
//! It owns scenario files, the world loop, metrics, Monte Carlo and the experiments that
//! reproduce the theses' tables (see [`experiments`]).

pub mod experiments;
pub mod nams;
pub mod output;
pub mod plot;
pub mod policy;
pub mod report;
pub mod scenario_file;
pub mod predeploy;
pub mod hbl;
pub mod closed_loop;
