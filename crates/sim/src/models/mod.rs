//! Named, configurable models the engine plugs in, each a `#[serde(tag = "kind")]` spec with its
//! parameters and its own validation: transponder buoys ([`buoy`]), the acoustic channel's truth side ([`channel`]), the comms
//! schedule ([`schedule`]), what a vehicle does after its mission ([`finish`]) and what the
//! survey AUVs' filters assume ([`filter`]), and the transmission loss ([`tl`]).

pub mod buoy;
pub mod channel;
pub mod filter;
pub mod finish;
pub mod schedule;
pub mod tl;
