//! coopnav-sim: the fast-time world that joins the planner, the navigation filters and the
//! acoustic link.
//!
//! It owns scenario files, the world loop, metrics, Monte Carlo and the experiments that
//! reproduce the theses' tables (see [`experiments`]).

pub mod closed_loop;
pub mod experiments;
pub mod hbl;
pub mod nams;
pub mod output;
pub mod plot;
pub mod policy;
pub mod predeploy;
pub mod report;
pub mod scenario_file;
pub mod work;
