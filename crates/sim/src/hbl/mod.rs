//! The Gill (2013) hybrid-baseline tools: Gill's zone metric as an engine observer with its Monte
//! Carlo ([`zone`], what `coopnav reproduce gill-*` runs), the buoy-location grid over either
//! world ([`grid`]); and the older HBL world loop ([`world`]: truth simulation of an AUV passing
//! counter-course under a ship with an off-path buoy, Monte Carlo with common random numbers,
//! coefficient tuning and the log writer for the post-processing pipeline) that `coopnav hbl …`
//! and `bench hbl` still run. The filters themselves live in `coopnav_nav`.

pub mod config;
pub mod grid;
pub mod log_format;
pub mod mc;
pub mod noise;
pub mod plot;
pub mod profile;
pub mod tune;
pub mod world;
pub mod zone;

pub use config::{ConfigError, Scenario};
pub use mc::{monte_carlo, monte_carlo_profiled, welch_95, McError, McResult, McSummary, Stats, WelchCi};
pub use profile::{error_profile, ProfileBin};
pub use world::{run, RunMetrics, Trace, TraceRow};
