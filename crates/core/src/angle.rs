//! Angle newtypes. Mixing degrees with radians, or a math heading (0 = east, counter-clockwise)
//! with a compass heading (0 = north, clockwise), is a classic marine-robotics bug, so each has
//! its own type and the only conversion between the two heading conventions lives here.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Wraps an angle in radians to (-π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let w = rem_euclid(a, TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

/// `a.rem_euclid(m)` for m > 0, bit for bit, without the remainder routine (a software loop,
/// and angles are wrapped several times per vehicle and step) when |a| < 2m: below m the
/// remainder is `a` itself, below 2m it is a ∓ m, exact by Sterbenz's lemma and carrying the
/// sign of `a` as the remainder does (−m gives −0).
pub fn rem_euclid(a: f64, m: f64) -> f64 {
    let r = if a.abs() < m {
        a
    } else if a.abs() < 2.0 * m {
        (a - m.copysign(a)).copysign(a)
    } else {
        a % m
    };
    if r < 0.0 {
        r + m
    } else {
        r
    }
}

/// An angle in radians (the internal unit).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Radians(pub f64);

/// An angle in degrees (files and screens only).
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Degrees(pub f64);

impl From<Degrees> for Radians {
    fn from(d: Degrees) -> Self {
        Radians(d.0.to_radians())
    }
}

impl From<Radians> for Degrees {
    fn from(r: Radians) -> Self {
        Degrees(r.0.to_degrees())
    }
}

/// A heading in the internal math convention: radians, 0 = east (+x), counter-clockwise,
/// always wrapped to (-π, π].
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Heading(f64);

impl Heading {
    pub fn from_radians(r: f64) -> Self {
        Heading(wrap_pi(r))
    }
    pub fn radians(self) -> f64 {
        self.0
    }
    /// Unit vector (east, north) of travel.
    pub fn unit(self) -> (f64, f64) {
        (self.0.cos(), self.0.sin())
    }
    /// Heading turned by `delta` radians (positive = counter-clockwise).
    pub fn turned(self, delta: f64) -> Self {
        Heading::from_radians(self.0 + delta)
    }
    /// Smallest signed turn from `self` to `other`, in (-π, π].
    pub fn turn_to(self, other: Heading) -> f64 {
        wrap_pi(other.0 - self.0)
    }
}

/// A compass heading in degrees: 0 = north, 90 = east, clockwise, in [0, 360).
/// This is what MOOS-IvP, NMEA and people use.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CompassDeg(pub f64);

impl From<Heading> for CompassDeg {
    fn from(h: Heading) -> Self {
        CompassDeg(rem_euclid(90.0 - h.0.to_degrees(), 360.0))
    }
}

impl From<CompassDeg> for Heading {
    fn from(c: CompassDeg) -> Self {
        Heading::from_radians((90.0 - c.0).to_radians())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The fast path agrees bit for bit with `f64::rem_euclid` (signed zeros included) on the
    /// boundaries of its branches, on special values and on random angles of every size.
    #[test]
    fn rem_euclid_equals_the_standard_remainder_bit_for_bit() {
        let same = |a: f64, m: f64| {
            let (fast, std) = (rem_euclid(a, m), a.rem_euclid(m));
            assert!(fast.to_bits() == std.to_bits() || (fast.is_nan() && std.is_nan()), "{a} mod {m}: {fast} vs {std}");
        };
        let special = [0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, f64::MIN_POSITIVE, 1e-300, 1e300];
        for m in [TAU, 360.0, 3600.0, 0.1] {
            for base in [m, 2.0 * m, 3.0 * m, 0.5 * m] {
                for v in [base, base.next_up(), base.next_down()] {
                    same(v, m);
                    same(-v, m);
                }
            }
            special.iter().for_each(|&a| same(a, m));
        }
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let unit = (state >> 11) as f64 / (1u64 << 53) as f64;
            let scale = [1.0, 10.0, 1e3, 1e6][(state & 3) as usize];
            same((unit - 0.5) * 4.0 * TAU * scale, TAU);
            same((unit - 0.5) * 1440.0 * scale, 360.0);
        }
    }

    #[test]
    fn compass_cardinal_points() {
        let east = Heading::from_radians(0.0);
        let north = Heading::from_radians(PI / 2.0);
        assert!((CompassDeg::from(east).0 - 90.0).abs() < 1e-12);
        assert!(CompassDeg::from(north).0.abs() < 1e-12);
        let west: Heading = CompassDeg(270.0).into();
        assert!((west.radians().abs() - PI).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn wrap_stays_in_range(a in -1e4f64..1e4) {
            let w = wrap_pi(a);
            prop_assert!(w > -PI - 1e-12 && w <= PI + 1e-12);
            prop_assert!(((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-6);
        }

        #[test]
        fn compass_round_trip(c in 0.0f64..359.999) {
            let back = CompassDeg::from(Heading::from(CompassDeg(c)));
            prop_assert!((back.0 - c).abs() < 1e-9);
        }
    }
}
