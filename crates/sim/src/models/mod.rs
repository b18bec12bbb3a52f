//! Named, configurable models the engine plugs in, each a `#[serde(tag = "kind")]` spec with its
//! parameters and its own validation: transponder buoys ([`buoy`]), ships on a fixed track
//! ([`ship`]), the acoustic channel's truth side ([`channel`]), the 13-bit mini-packet
//! ([`minipacket`]), the comms schedule ([`schedule`]), what a vehicle does after its mission ([`finish`]) and what the
//! survey AUVs' filters assume ([`filter`]), the transmission loss ([`tl_spec`], built for a run by [`tl`]) and when an AUV CNA
//! surfaces for a GPS fix ([`surfacing`]), how the CNA navigates ([`cna_navigation`]), a survey AUV's own lawnmower ([`mower`]) and what its
//! status carries to whom ([`peer`]), the noise every vehicle draws ([`noise`]), filter health
//! judged against the truth ([`health`]) and the per-run metrics a run reports ([`metrics`]).

pub mod buoy;
pub mod channel;
pub mod cna_navigation;
pub mod filter;
pub mod finish;
pub mod health;
pub mod metrics;
pub mod minipacket;
pub mod mower;
pub mod noise;
pub mod peer;
pub mod schedule;
pub mod ship;
pub mod surfacing;
pub mod tl;
pub mod tl_spec;
