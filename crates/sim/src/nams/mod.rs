//! The Nams (2014) mission simulator: two IVER2s fly lawnmower missions over a bathymetry grid
//! while exchanging packets in a TDMA network; each vehicle's rate policy decides, every own slot,
//! whether and at which WHOI rate to transmit, fed by its packet-success tracker and its shadow
//! estimate of the collaborator. Scenarios 1–4 (mission size × ambient noise) × behaviours ×
//! seeded repetitions run in parallel; metrics are those of the thesis's Table 7.

pub mod batch;
pub mod metrics;
pub mod prepare;
pub mod scenario;
pub mod world;

pub use batch::{run_experiment, Cell, ExperimentResult};
pub use metrics::{LinkTally, RunMetrics};
pub use scenario::{Behaviour, ExperimentConfig, Scenario};
