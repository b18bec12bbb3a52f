//! Observers that only read a run: Gill's zone metric with its Monte Carlo ([`zone`]) and its
//! along-path error profile ([`profile`]), Nams's link tally and Table 7 metrics
//! ([`link_tally`]), and the across-run statistics they are summarised with ([`stats`]).

pub mod link_tally;
pub mod profile;
pub mod stats;
pub mod zone;
