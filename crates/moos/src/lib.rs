//! coopnav-moos: the bridge between coopnav and the MOOS-IvP tools marine-robotics users already run
//! (alogview, pMarineViewer, the alog grep/clip utilities).
//!
//! It owns the `.alog` text format (reading and writing, [`alog`]), a run as those tools see it
//! ([`run`]: vehicle tracks, acoustic pulses, planned legs) and its export as an alog
//! ([`export`]), MOOS mission files for a planned CNA path ([`mission`]), the interactive replay page built from an alog ([`replay`]), and the one colour of each vehicle in every drawn output ([`palette`]). It knows nothing about simulators or filters: callers fill in a [`RunLog`] from
//! their own records.

pub mod alog;
pub mod export;
pub mod mission;
pub mod palette;
pub mod replay;
pub mod run;

pub use alog::{read_alog, read_alog_file, Alog, AlogEntry, AlogError, AlogWriter};
pub use export::{write_run_alog, write_run_alog_with, ExportError, Posting};
pub use mission::{mission_files, MissionFiles, MissionSpec, Waypoint};
pub use run::{Leg, Pulse, PulseKind, Role, RunLog, Sample, Vehicle, SIMULATED_LOG_START};
