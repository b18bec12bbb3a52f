//! Named, configurable models the engine plugs in, each a `#[serde(tag = "kind")]` spec with its
//! parameters and its own validation: the acoustic channel's truth side ([`channel`]), the comms
//! schedule ([`schedule`]) and what a vehicle does after its mission ([`finish`]).

pub mod channel;
pub mod finish;
pub mod schedule;
