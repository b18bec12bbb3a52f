//! The codec workloads both benchmarks time (criterion's `benches/codec.rs` and
//! `coopnav bench acomms`), written once so the two measure the same thing: a steady tracked
//! frame 0 and a two-vehicle tracker exchange.

use crate::status::{Frame0, NextWaypoint, StatusMessage};
use crate::tracker::{MaskWidth, Tracker};
use crate::{Rate, Reception};
use coopnav_core::{Heading, Vec3};

/// Every reception of the workloads: all 7 frames of a 3-frame packet heard.
const HEARD: Reception = Reception { frames: 7, n_frames: 3 };

/// A frame 0 from a tracker holding 3 unconfirmed receptions, with the usual status message.
pub fn sample_frame0() -> Frame0 {
    let mut tr = Tracker::new(0, 2, MaskWidth::Narrow, 11);
    for k in [1u64, 3, 5] {
        tr.on_receive(k, 1, HEARD, None);
    }
    let header = tr.on_transmit(6, Rate::R1);
    Frame0 {
        header,
        status: StatusMessage {
            pos: Vec3::new(123.4, 456.7, 28.2),
            heading: Heading::from_radians(0.7),
            speed: 1.54,
            next: NextWaypoint::Id(7),
        },
    }
}

/// Two vehicles' trackers exchanging packets that are always heard.
pub struct TrackerExchange {
    a: Tracker,
    b: Tracker,
    slot: u64,
}

impl Default for TrackerExchange {
    fn default() -> Self {
        TrackerExchange {
            a: Tracker::new(0, 2, MaskWidth::Narrow, 11),
            b: Tracker::new(1, 2, MaskWidth::Narrow, 11),
            slot: 0,
        }
    }
}

impl TrackerExchange {
    /// One transmit and one receive by each vehicle.
    pub fn step(&mut self) {
        let k = self.slot;
        let h = self.a.on_transmit(k, Rate::R1);
        self.b.on_receive(k, 0, HEARD, Some(&h));
        let h = self.b.on_transmit(k + 1, Rate::R1);
        self.a.on_receive(k + 1, 1, HEARD, Some(&h));
        self.slot += 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sample_frame_round_trips_and_carries_its_receptions() {
        let f = sample_frame0();
        let bytes = f.encode(MaskWidth::Narrow, 64).unwrap();
        let back = Frame0::decode(&bytes, MaskWidth::Narrow).unwrap();
        assert_eq!(back.header.entries.len(), f.header.entries.len());
        assert!(!f.header.entries.is_empty(), "the tracker reports its receptions");
    }
}
