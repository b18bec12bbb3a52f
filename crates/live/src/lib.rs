//! coopnav-live: coopnav's filters as live processes on LCM, for a vehicle's backseat.
//!
//! - [`auv`]: a survey AUV's OWTT navigator ([`AuvNavigator`]) as a pure message → filter →
//!   message machine, with no socket: LCM payloads in, `auv_estimate_t` payloads out. The tests
//!   drive it directly;
//! - [`cna`]: the CNA's planner ([`CnaPlanner`]): the policy the scenario names, run by
//!   coopnav-sim's own code on the CNA's fix and the statuses its modem received, a command and a
//!   decision record every τ;
//! - [`sitl`]: software in the loop, in lockstep or free running: the engine as the world, the
//!   CNA's decisions taken by a `coopnav live cna` child on the bus, and with live AUVs every
//!   survey AUV navigated by a `coopnav live auv` child;
//! - [`import`]: a live navigator's LCM log as a post-processing log, and the live processes'
//!   logs together as a run's alog (`coopnav live import`);
//! - [`world`]: the LCM messages a CNA receives in a simulated mission, published or recorded;
//! - [`run`]: the process loop around them on coopnav-lcm's UDP multicast transport ([`run_auv`]),
//!   with its LCM log, its stop conditions (a stop flag set on SIGINT/SIGTERM, a duration, an idle
//!   time) and its one-line summary.
//!
//! A separate crate so that coopnav-nav does not depend on coopnav-lcm: the filter stays a pure
//! library, and only this crate knows the wire.

pub mod auv;
pub mod cna;
pub mod import;
pub mod run;
pub mod sitl;
pub mod synthetic;
pub mod world;

pub use auv::{AuvNavigator, Channels, Counts, LiveConfig, LiveError, Published, Start};
pub use cna::{CnaChannels, CnaCounts, CnaPlanner, Outgoing};
pub use run::{run_auv, run_cna, ClockSource, CnaRunSummary, RunOptions, RunSummary, StopReason};
