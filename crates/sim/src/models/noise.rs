//! Noise sources of Gill's simulation (Gill 2013, §2.4.1) that the engine's models draw from: the
//! compass-bias map, the acoustic range-error mixture ([`Acoustic`], [`draw_reception`]) and buoy
//! drift. Each draws from the stream it is given in a fixed pattern whatever the configuration,
//! so MSBL, HBL One and HBL Two runs with the same seed see the same noise (common random numbers).

use coopnav_core::rem_euclid;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Gill's range-error mixture of a message (Gill 2013, §2.4.1): uniform "slight" errors up to
/// `slight_max_m` long or short, uniform `outlier_min_m`–`outlier_max_m` outliers, and drops; the
/// four shares sum to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Acoustic {
    pub p_slightly_long: f64,
    pub p_slightly_short: f64,
    pub p_outlier: f64,
    pub p_drop: f64,
    pub slight_max_m: f64,
    pub outlier_min_m: f64,
    pub outlier_max_m: f64,
}

impl Default for Acoustic {
    fn default() -> Self {
        Acoustic {
            p_slightly_long: 0.50,
            p_slightly_short: 0.35,
            p_outlier: 0.05,
            p_drop: 0.10,
            slight_max_m: 0.20,
            outlier_min_m: 5.0,
            outlier_max_m: 10.0,
        }
    }
}

impl Acoustic {
    /// Mean square of the range error of a *received* message under the thesis's mixture
    /// (Gill 2013, §2.4.1, read as uniform "slight" errors and uniform 5–10 m outliers), in m².
    pub fn received_error_mean_square(&self) -> f64 {
        let uniform_sq = |a: f64, b: f64| (a * a + a * b + b * b) / 3.0;
        let received = self.p_slightly_long + self.p_slightly_short + self.p_outlier;
        let sum = (self.p_slightly_long + self.p_slightly_short) * uniform_sq(0.0, self.slight_max_m)
            + self.p_outlier * uniform_sq(self.outlier_min_m, self.outlier_max_m);
        if received > 0.0 {
            sum / received
        } else {
            0.0
        }
    }
}

pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

/// Compass bias per integer compass degree (rad): a random walk over heading with N(0, step)
/// increments, or i.i.d. values (an interpretation: docs/models.md#gill-sensor-noise).
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
    #[inline]
    pub fn at(&self, psi: f64) -> f64 {
        let compass = rem_euclid(90.0 - psi.to_degrees(), 360.0);
        self.table[round_non_negative(compass) % 360]
    }
}

/// `v.round() as usize` for v ≥ 0 (or NaN, 0), without libm's `round` call (the compass bias
/// is looked up for every AUV at every filter step): v − ⌊v⌋ is exact, so the half-way test is.
#[inline]
fn round_non_negative(v: f64) -> usize {
    let whole = v as usize;
    whole + usize::from(v - whole as f64 >= 0.5)
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

/// Gill's Lake Pend Oreille drift statistics (Gill 2013, §2.4.1; docs/models.md#gill-buoy-drift):
/// speed ~ N(mean, sd) clipped at zero,
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
    use super::*;
    use coopnav_core::SeedStream;

    #[test]
    fn compass_degree_rounding_is_libm_round() {
        let halves = (0..=720).map(|k| f64::from(k) * 0.5);
        let near_halves = halves.clone().flat_map(|v| [v.next_down().max(0.0), v.next_up()]);
        let mut rng = SeedStream::new(9).rng(0);
        let uniform = (0..100_000).map(|_| rng.gen::<f64>() * 360.0);
        for v in halves.chain(near_halves).chain(uniform).chain([0.49999999999999994, 359.5, f64::NAN]) {
            assert_eq!(round_non_negative(v), v.round() as usize, "{v:e}");
        }
    }

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
        let lake = LakeDrift { mean_m_s: 0.1, sd_m_s: 0.0, circular_fraction: 1.0, circular_radius_m: 200.0 };
        let m = BuoyMotion::lake([20.0, 65.0], &lake, &mut SeedStream::new(3).rng(3));
        assert!(matches!(m, BuoyMotion::Circular { .. }), "{m:?}");
        let (p0, p1) = (m.at(0.0), m.at(1.0));
        assert!((p0[0] - 20.0).abs() < 1e-9 && (p0[1] - 65.0).abs() < 1e-9, "{p0:?}");
        assert!(((p1[0] - p0[0]).hypot(p1[1] - p0[1]) - 0.1).abs() < 1e-4);
        assert_eq!(BuoyMotion::moored([5.0, 6.0]).at(100.0), [5.0, 6.0]);
    }

    /// The AUV filter's default timing noise is matched to this range-error mixture (see
    /// `coopnav_nav::RangeNoise`); the two defaults must not drift apart.
    #[test]
    fn default_range_noise_matches_the_channel() {
        let rms = Acoustic::default().received_error_mean_square().sqrt();
        let noise = coopnav_nav::AuvParams::default().range_noise;
        let filter = noise.sound_speed * noise.sigma_time;
        assert!((filter - rms).abs() < 0.01 * rms, "filter σ at zero range {filter} m vs channel RMS {rms} m");
    }

    #[test]
    fn compass_map_is_continuous_for_a_walk() {
        // Gill's 0.047° step (Gill 2013, §2.4.1; docs/models.md#gill-sensor-noise).
        let step = 0.047f64.to_radians();
        let m = CompassBias::draw(0.047, false, &mut SeedStream::new(9).rng(5));
        let d = (m.at(0.0) - m.at(0.0175)).abs();
        assert!(d < step * 5.0);
        let rms = |v: &mut dyn Iterator<Item = f64>| {
            let (n, s) = v.fold((0.0, 0.0), |(n, s), x| (n + 1.0, s + x * x));
            (s / n).sqrt()
        };
        // A walk's 359 steps between neighbouring degrees are N(0, step²): their RMS is the step
        // within 15% (four times the 3.7% spread of an RMS of 359 normals); an i.i.d. map's
        // neighbours differ by step·√2, 41% more.
        let steps = rms(&mut m.table.windows(2).map(|w| w[1] - w[0]));
        assert!((steps / step - 1.0).abs() < 0.15, "neighbouring degrees differ by {steps} rad RMS, step {step}");
        // And it wanders: a walk of 360 steps spreads over about √180 steps (below 3 steps with
        // well under a percent's chance); an i.i.d. map stays within one.
        let spread = rms(&mut m.table.iter().copied());
        assert!(spread > 3.0 * step, "the map's RMS is {spread} rad, step {step}");
    }
}
