//! The WHOI Micro-Modem rate table (Nams 2014, Table 2, plus the deprecated rates 2 and 3) and the
//! TDMA slot-length rule: 10 s slots, 15 s whenever any vehicle may use rate 5,
//! plus 2 s when the hardware ACK is requested.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A WHOI Micro-Modem rate, 0..=5.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(try_from = "u8", into = "u8")]
pub struct Rate(u8);

#[derive(Debug, Error, PartialEq)]
#[error("WHOI rate {0} does not exist (allowed: 0..=5)")]
pub struct BadRate(pub u8);

/// Modulation of a rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Modulation {
    Fsk,
    Psk,
}

/// One row of the rate table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RateSpec {
    pub rate: Rate,
    pub modulation: Modulation,
    pub frame_bytes: usize,
    pub frames: usize,
    /// Nominal packet duration, s (Table 2; rates 2 and 3 share 1 and 4's).
    pub duration: f64,
    /// Rates 2 and 3: "antiquated and no longer recommended" — never chosen by a policy.
    pub deprecated: bool,
}

impl RateSpec {
    pub fn packet_bytes(&self) -> usize {
        self.frame_bytes * self.frames
    }
}

const TABLE: [(Modulation, usize, usize, f64, bool); 6] = [
    (Modulation::Fsk, 32, 1, 3.90, false),
    (Modulation::Psk, 64, 3, 3.08, false),
    (Modulation::Psk, 64, 3, 3.08, true),
    (Modulation::Psk, 256, 2, 3.15, true),
    (Modulation::Psk, 256, 2, 3.15, false),
    (Modulation::Psk, 256, 8, 3.04, false),
];

impl Rate {
    pub const R0: Rate = Rate(0);
    pub const R1: Rate = Rate(1);
    pub const R4: Rate = Rate(4);
    pub const R5: Rate = Rate(5);

    pub fn new(r: u8) -> Result<Self, BadRate> {
        if r <= 5 {
            Ok(Rate(r))
        } else {
            Err(BadRate(r))
        }
    }
    pub fn index(self) -> u8 {
        self.0
    }
    pub fn spec(self) -> RateSpec {
        let (modulation, frame_bytes, frames, duration, deprecated) = TABLE[self.0 as usize];
        RateSpec { rate: self, modulation, frame_bytes, frames, duration, deprecated }
    }
    /// The rates the thesis uses (0, 1, 4, 5).
    pub fn usable() -> [Rate; 4] {
        [Rate::R0, Rate::R1, Rate::R4, Rate::R5]
    }
}

impl TryFrom<u8> for Rate {
    type Error = BadRate;
    fn try_from(r: u8) -> Result<Self, BadRate> {
        Rate::new(r)
    }
}
impl From<Rate> for u8 {
    fn from(r: Rate) -> u8 {
        r.0
    }
}
impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// TDMA timing: one transmitter per slot, slots owned round-robin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tdma {
    /// Slot length without rate 5, s (thesis: 10 s).
    pub base_slot: f64,
    /// Slot length when rate 5 may be used anywhere in the network, s (thesis: 15 s).
    pub rate5_slot: f64,
    /// Extra time per slot for the hardware ACK mini-packet, s (thesis: 2.0 s).
    pub ack_extra: f64,
}

impl Default for Tdma {
    fn default() -> Self {
        Tdma { base_slot: 10.0, rate5_slot: 15.0, ack_extra: 2.0 }
    }
}

impl Tdma {
    /// Slot length for a network whose vehicles may use `rates`; `ack` adds the ACK time.
    pub fn slot_length(&self, rates: impl IntoIterator<Item = Rate>, ack: bool) -> f64 {
        let base = if rates.into_iter().any(|r| r == Rate::R5) { self.rate5_slot } else { self.base_slot };
        base + if ack { self.ack_extra } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matches_thesis_table_2() {
        let bytes: Vec<usize> = Rate::usable().iter().map(|r| r.spec().packet_bytes()).collect();
        assert_eq!(bytes, vec![32, 192, 512, 2048]);
        assert!(Rate::new(2).unwrap().spec().deprecated && Rate::new(3).unwrap().spec().deprecated);
        assert_eq!(Rate::new(2).unwrap().spec().packet_bytes(), 192);
        assert_eq!(Rate::new(3).unwrap().spec().packet_bytes(), 512);
        assert!(Rate::usable().iter().all(|r| !r.spec().deprecated));
        assert_eq!(Rate::new(6), Err(BadRate(6)));
        assert!(serde_json::from_str::<Rate>("7").is_err());
    }

    #[test]
    fn slot_rule() {
        let t = Tdma::default();
        assert_eq!(t.slot_length([Rate::R0, Rate::R1, Rate::R4], false), 10.0);
        assert_eq!(t.slot_length([Rate::R0, Rate::R5], false), 15.0);
        assert_eq!(t.slot_length([Rate::R1], true), 12.0);
    }
}
