//! coopnav-sim: the fast-time world that joins the planner, the navigation filters and the
//! acoustic link.
//!
//! It owns scenario files ([`scenario`]), the mission [`engine`] and the [`models`] it plugs in,
//! the CNA policies ([`policy`]), the observers that score a run ([`observe`]), Monte Carlo and
//! sweeps ([`batch`]), run directories, plots and exports ([`output`]) and the experiments that
//! reproduce the theses' tables (see [`experiments`]). Bottom up: `scenario` and `models`, then
//! `policy` and the `engine` that runs it, then `observe`, then `batch`, `output` and
//! `experiments`; no module imports one above it.

pub mod batch;
pub mod engine;
pub mod experiments;
pub mod models;
pub mod observe;
pub mod output;
pub mod policy;
pub mod scenario;
