//! What a survey AUV does once its mission is flown, as a real one does: loiter on a circle
//! around its last waypoint, hold station there (propulsion off while inside the radius, back to
//! it when the current pushes it out), or surface (propulsion off, rise, take GPS fixes).
//! Its speed sensor reads what the vehicle really does, so dead reckoning sees the true motion.

use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Finish {
    Loiter {
        radius_m: f64,
    },
    Hold {
        radius_m: f64,
    },
    /// Rises at `ascent_rate_m_s`; at the surface a GPS fix (σ `gps_sd_m` per axis) every second.
    Surface {
        ascent_rate_m_s: f64,
        gps_sd_m: f64,
    },
}

impl Default for Finish {
    fn default() -> Self {
        Finish::Loiter { radius_m: 50.0 }
    }
}

/// What the finished vehicle does this step.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Keep steering the waypoints it has.
    Continue,
    /// Steer these (x, y) waypoints next.
    Steer(Vec<(f64, f64)>),
    /// Propulsion off: it moves with the water only.
    Drift,
    /// Propulsion off and rising at this rate, m/s.
    Ascend(f64),
}

/// Points of the loiter circle (a polygon is what a waypoint controller can fly).
const LOITER_POINTS: usize = 8;

impl Finish {
    /// The action of a vehicle whose waypoints are `done`, believed at `estimate`, whose last
    /// waypoint (its station) is `station`.
    pub fn act(&self, done: bool, estimate: (f64, f64), station: (f64, f64)) -> Action {
        if !done {
            return Action::Continue;
        }
        match *self {
            Finish::Loiter { radius_m } => Action::Steer(
                (0..LOITER_POINTS)
                    .map(|i| {
                        let a = std::f64::consts::TAU * i as f64 / LOITER_POINTS as f64;
                        (station.0 + radius_m * a.cos(), station.1 + radius_m * a.sin())
                    })
                    .collect(),
            ),
            Finish::Hold { radius_m } => {
                let off = (estimate.0 - station.0).hypot(estimate.1 - station.1);
                if off > radius_m {
                    Action::Steer(vec![station])
                } else {
                    Action::Drift
                }
            }
            Finish::Surface { ascent_rate_m_s, .. } => Action::Ascend(ascent_rate_m_s),
        }
    }
}

impl CheckFields for Finish {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let (field, v) = match *self {
            Finish::Loiter { radius_m } | Finish::Hold { radius_m } => ("radius_m", radius_m),
            Finish::Surface { ascent_rate_m_s, gps_sd_m } => {
                if !(gps_sd_m.is_finite() && gps_sd_m > 0.0) {
                    return p.push(format!("{prefix}gps_sd_m"), gps_sd_m.to_string(), "a finite number > 0");
                }
                ("ascent_rate_m_s", ascent_rate_m_s)
            }
        };
        p.check(&format!("{prefix}{field}"), v, |v| v > 0.0 && v <= 1000.0, "0 < value <= 1000");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_behaviour_acts_as_a_real_vehicle() {
        let loiter = Finish::default().act(true, (0.0, 0.0), (10.0, 0.0));
        assert!(matches!(&loiter, Action::Steer(p) if p.len() == 8 && p[0] == (60.0, 0.0)), "{loiter:?}");
        assert_eq!(Finish::default().act(false, (0.0, 0.0), (0.0, 0.0)), Action::Continue);
        let hold = Finish::Hold { radius_m: 20.0 };
        assert_eq!(hold.act(true, (5.0, 5.0), (0.0, 0.0)), Action::Drift);
        assert_eq!(hold.act(true, (30.0, 0.0), (0.0, 0.0)), Action::Steer(vec![(0.0, 0.0)]));
        let surface = Finish::Surface { ascent_rate_m_s: 0.5, gps_sd_m: 3.0 };
        assert_eq!(surface.act(true, (0.0, 0.0), (0.0, 0.0)), Action::Ascend(0.5));
        assert_eq!(surface.act(false, (0.0, 0.0), (0.0, 0.0)), Action::Continue);
        assert!(hold.validate("f.").is_ok());
        assert_eq!(Finish::Hold { radius_m: f64::NAN }.validate("f.").unwrap_err().fields(), ["f.radius_m"]);
    }
}
