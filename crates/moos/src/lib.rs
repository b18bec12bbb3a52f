//! coopnav-moos: the bridge between coopnav and the MOOS-IvP tools marine-robotics users already run
//! (alogview, pMarineViewer, the alog grep/clip utilities).
//!
//! It owns the `.alog` text format (reading and writing, [`alog`]). It knows nothing about
//! simulators or filters: callers turn their own records into alog entries and back.

pub mod alog;

pub use alog::{read_alog, read_alog_file, Alog, AlogEntry, AlogError, AlogWriter};
