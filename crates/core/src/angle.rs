//! Angle newtypes. Mixing degrees with radians, or a math heading (0 = east, counter-clockwise)
//! with a compass heading (0 = north, clockwise), is a classic marine-robotics bug, so each has
//! its own type and the only conversion between the two heading conventions lives here.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Wraps an angle in radians to (-π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
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
        CompassDeg((90.0 - h.0.to_degrees()).rem_euclid(360.0))
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
