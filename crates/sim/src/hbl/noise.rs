//! Noise sources of the HBL world (digest §5.4–§5.5): the compass-bias map, the acoustic range
//! error mixture, and buoy drift. Each draws from its own seeded stream; draws are made in a
//! fixed pattern whatever the configuration, so MSBL, HBL One and HBL Two runs with the same
//! seed see the same noise (common random numbers).

use super::config::{Acoustic, Buoy, Drift};
use coopnav_core::rem_euclid;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Stream ids of one run, one per noise source.
pub mod stream {
    pub const AUV_INIT: u64 = 1;
    pub const SHIP_INIT: u64 = 2;
    pub const BUOY: u64 = 3;
    pub const SPEED: u64 = 4;
    pub const COMPASS_MAP: u64 = 5;
    pub const COMPASS_WHITE: u64 = 6;
    pub const YAW_RATE: u64 = 7;
    pub const SLOTS: u64 = 8;
    pub const CLOCK: u64 = 9;
    pub const LOG: u64 = 10;
}

pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

/// Compass bias per integer compass degree (rad): a random walk over heading with N(0, step)
/// increments, or i.i.d. values (digest §10 A12).
#[derive(Debug, Clone)]
pub struct CompassBias {
    table: Vec<f64>,
}

impl CompassBias {
    pub fn draw(step_deg: f64, iid: bool, rng: &mut ChaCha8Rng) -> Self {
        let step = step_deg.to_radians();
        let mut acc = 0.0;
        let table = (0..360)
            .map(|_| {
                let d = normal(rng) * step;
                if iid {
                    d
                } else {
                    acc += d;
                    acc
                }
            })
            .collect();
        CompassBias { table }
    }
    /// Bias at a math-convention heading (rad), looked up at the rounded compass degree.
    pub fn at(&self, psi: f64) -> f64 {
        let compass = rem_euclid(90.0 - psi.to_degrees(), 360.0);
        self.table[(compass.round() as usize) % 360]
    }
}

/// The fate of one acoustic message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reception {
    Dropped,
    /// Received, with this range error (m, positive = long).
    Received(f64),
}

/// Draws a message's fate: always two uniforms, whatever the outcome.
pub fn draw_reception(a: &Acoustic, rng: &mut ChaCha8Rng) -> Reception {
    let (u, m): (f64, f64) = (rng.gen(), rng.gen());
    let slight = (1.0 - m) * a.slight_max_m; // (0, max]
    if u < a.p_slightly_long {
        Reception::Received(slight)
    } else if u < a.p_slightly_long + a.p_slightly_short {
        Reception::Received(-slight)
    } else if u < a.p_slightly_long + a.p_slightly_short + a.p_outlier {
        Reception::Received(a.outlier_min_m + m * (a.outlier_max_m - a.outlier_min_m))
    } else {
        Reception::Dropped
    }
}

/// A buoy's true trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BuoyMotion {
    Linear { p0: [f64; 2], v: [f64; 2] },
    Circular { centre: [f64; 2], radius: f64, phase0: f64, omega: f64 },
}

/// Gill's Lake Pend Oreille drift statistics (digest §5.5): speed ~ N(mean, sd) clipped at zero,
/// a uniform direction, and a circle of `circular_radius` with odds `circular_fraction`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LakeDrift {
    pub mean_m_s: f64,
    pub sd_m_s: f64,
    pub circular_fraction: f64,
    pub circular_radius_m: f64,
}

impl BuoyMotion {
    /// Draws initial position and drift; always the same number of draws.
    pub fn draw(b: &Buoy, rng: &mut ChaCha8Rng) -> Self {
        let (ux, uy): (f64, f64) = (rng.gen(), rng.gen());
        let p0 = b.fixed.unwrap_or([
            b.region_x[0] + ux * (b.region_x[1] - b.region_x[0]),
            b.region_y[0] + uy * (b.region_y[1] - b.region_y[0]),
        ]);
        let lake = LakeDrift {
            mean_m_s: b.drift_mean,
            sd_m_s: b.drift_sd,
            circular_fraction: b.circular_fraction,
            circular_radius_m: b.circular_radius,
        };
        let drifting = BuoyMotion::lake(p0, &lake, rng);
        match b.drift {
            Drift::None => BuoyMotion::moored(p0),
            Drift::Lake => drifting,
        }
    }

    pub fn moored(p0: [f64; 2]) -> Self {
        BuoyMotion::Linear { p0, v: [0.0, 0.0] }
    }

    /// A drift from `p0` drawn from the lake statistics; always the same number of draws.
    pub fn lake(p0: [f64; 2], s: &LakeDrift, rng: &mut ChaCha8Rng) -> Self {
        let speed = (s.mean_m_s + s.sd_m_s * normal(rng)).max(0.0);
        let (dir, kind, sense): (f64, f64, f64) = (rng.gen::<f64>() * TAU, rng.gen(), rng.gen());
        if speed == 0.0 {
            return BuoyMotion::moored(p0);
        }
        if kind < s.circular_fraction {
            // The buoy starts on a circle whose tangent is the drift direction.
            let radius = s.circular_radius_m;
            let sign = if sense < 0.5 { 1.0 } else { -1.0 };
            let to_centre = dir + sign * std::f64::consts::FRAC_PI_2;
            let centre = [p0[0] + radius * to_centre.cos(), p0[1] + radius * to_centre.sin()];
            let phase0 = (p0[1] - centre[1]).atan2(p0[0] - centre[0]);
            BuoyMotion::Circular { centre, radius, phase0, omega: sign * speed / radius }
        } else {
            BuoyMotion::Linear { p0, v: [speed * dir.cos(), speed * dir.sin()] }
        }
    }
    pub fn at(&self, t: f64) -> [f64; 2] {
        match *self {
            BuoyMotion::Linear { p0, v } => [p0[0] + v[0] * t, p0[1] + v[1] * t],
            BuoyMotion::Circular { centre, radius, phase0, omega } => {
                let a = phase0 + omega * t;
                [centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::config::Sensors;
    use super::*;
    use coopnav_core::SeedStream;

    #[test]
    fn reception_mixture_matches_the_thesis_shares() {
        let a = Acoustic::default();
        let mut rng = SeedStream::new(5).rng(1);
        let n = 40_000;
        let (mut long, mut short, mut out, mut drop) = (0, 0, 0, 0);
        for _ in 0..n {
            match draw_reception(&a, &mut rng) {
                Reception::Dropped => drop += 1,
                Reception::Received(e) if e >= 5.0 => {
                    assert!(e <= 10.0);
                    out += 1
                }
                Reception::Received(e) if e > 0.0 => {
                    assert!(e <= 0.2);
                    long += 1
                }
                Reception::Received(e) => {
                    assert!((-0.2..0.0).contains(&e));
                    short += 1
                }
            }
        }
        let share = |k: i32| k as f64 / n as f64;
        assert!((share(long) - 0.50).abs() < 0.015);
        assert!((share(short) - 0.35).abs() < 0.015);
        assert!((share(out) - 0.05).abs() < 0.006);
        assert!((share(drop) - 0.10).abs() < 0.008);
    }

    /// The filter's default range noise is derived from this mean square, so check it against
    /// the sampler itself (mean of e² over received messages, within 4 standard errors).
    #[test]
    fn received_mean_square_matches_the_sampler() {
        for a in [Acoustic::default(), Acoustic { p_outlier: 0.0, p_slightly_long: 0.55, ..Acoustic::default() }] {
            let mut rng = SeedStream::new(11).rng(2);
            let sq: Vec<f64> = (0..200_000)
                .filter_map(|_| match draw_reception(&a, &mut rng) {
                    Reception::Received(e) => Some(e * e),
                    Reception::Dropped => None,
                })
                .collect();
            let n = sq.len() as f64;
            let mean = sq.iter().sum::<f64>() / n;
            let se = (sq.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            let analytic = a.received_error_mean_square();
            assert!((mean - analytic).abs() < 4.0 * se + 1e-12, "sampled {mean} vs analytic {analytic} (se {se})");
        }
    }

    #[test]
    fn drift_speed_and_circle() {
        let b = Buoy { drift_mean: 0.1, drift_sd: 0.0, circular_fraction: 1.0, ..Buoy::default() };
        let m = BuoyMotion::draw(&b, &mut SeedStream::new(3).rng(3));
        let (p0, p1) = (m.at(0.0), m.at(1.0));
        assert!(((p1[0] - p0[0]).hypot(p1[1] - p0[1]) - 0.1).abs() < 1e-4);
        let still = Buoy { drift: Drift::None, fixed: Some([5.0, 6.0]), ..Buoy::default() };
        assert_eq!(BuoyMotion::draw(&still, &mut SeedStream::new(3).rng(3)).at(100.0), [5.0, 6.0]);
    }

    #[test]
    fn compass_map_is_continuous_for_a_walk() {
        let s = Sensors::default();
        let m = CompassBias::draw(s.compass_bias_step_deg, s.compass_bias_iid, &mut SeedStream::new(9).rng(5));
        let d = (m.at(0.0) - m.at(0.0175)).abs();
        assert!(d < 0.047f64.to_radians() * 5.0);
    }
}
