//! Observers that only read a run: the metrics every run is scored by, with Hudson's modelled
//! error ([`metrics`]), Gill's zone metric with its Monte Carlo ([`zone`]) and its
//! along-path error profile ([`profile`]), Nams's link tally and Table 7 metrics
//! ([`link_tally`]), and the across-run statistics they are summarised with ([`stats`]).

pub mod link_tally;
pub mod metrics;
pub mod profile;
pub mod stats;
pub mod zone;

#[cfg(test)]
mod peer_run_tests;
#[cfg(test)]
mod run_tests;
