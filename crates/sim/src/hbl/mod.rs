//! The Gill (2013) hybrid-baseline tools on the mission engine: Gill's zone metric as an engine
//! observer with its Monte Carlo ([`zone`], what `coopnav reproduce gill-*` and `coopnav hbl
//! montecarlo` run), the buoy-location grid ([`grid`]), coefficient tuning over engine Monte
//! Carlos ([`tune`]), a recorded pass with its post-processing log ([`record`], `coopnav hbl
//! simulate`), and the noise models the engine draws from ([`noise`]). The filters themselves
//! live in `coopnav_nav`.

pub use crate::observe::profile::ProfileBin;
pub use crate::output::record::{PassRecorder, PassRow};
