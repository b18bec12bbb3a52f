//! The Nams (2014) experiment on the one engine: two IVER2s fly lawnmower missions over a
//! bathymetry grid while exchanging Nams's frame 0 (tracking header and status) in a TDMA network;
//! each vehicle's rate policy decides, every own slot, whether and at which WHOI rate to transmit,
//! fed by its packet-success tracker and its shadow estimate of the collaborator (the engine's
//! `comms.status_format = "nams_frame0"`). Scenarios 1–4 (mission size × ambient noise) ×
//! behaviours × seeded repetitions run in parallel ([`batch`], each cell an engine scenario from
//! [`setup`]); metrics are those of the thesis's Table 7 ([`metrics`]).

pub use crate::batch::nams::{run_experiment, Cell, ExperimentResult, ExperimentTl};
pub use crate::observe::link_tally::{LinkTally, RunMetrics};
pub use crate::scenario::nams::{Behaviour, ExperimentConfig, Scenario};
