//! The acoustic channel as the sea plays it (the truth side; what the filters assume is the
//! scenario's `[filter]`, configured apart): packet air time per WHOI rate, the range error the
//! sea adds, travel time along a sound-speed profile, per-vehicle clocks and the collision rule.
//! Defaults make the truth differ from the filter's model as the sea does: Gill's error mixture
//! with outliers instead of the filter's Gaussian, and a layered profile instead of 1500 m/s.

use crate::models::noise::{draw_reception, normal, Acoustic, Reception};
use coopnav_acomms::{Rate, Receiver};
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::Vec3;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Sound speed at which Gill's range errors (m) were measured; converts them to time errors.
const GILL_NOMINAL_SOUND_SPEED: f64 = 1500.0;

/// Time a packet at `rate` occupies the water: the rate table's nominal packet duration (Nams
/// Table 2), which covers all of the rate's frames — the modem always sends whole frames.
pub fn air_time(rate: Rate) -> f64 {
    rate.spec().duration
}

/// Bytes a packet at `rate` can carry (frames × frame bytes).
pub fn capacity(rate: Rate) -> usize {
    rate.spec().packet_bytes()
}

/// The whole `[channel]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Channel {
    pub range_error: RangeError,
    pub sound_speed: SoundSpeed,
    pub clocks: Clocks,
    pub collisions: Collisions,
}

impl Default for Channel {
    fn default() -> Self {
        Channel {
            range_error: RangeError::gill(),
            sound_speed: SoundSpeed::summer(),
            clocks: Clocks::default(),
            collisions: Collisions::default(),
        }
    }
}

/// The range error the sea adds to a decoded broadcast's travel time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RangeError {
    /// The filter's own Gaussian (its `range_noise` variance) plus `extra_sd` metres: the truth
    /// as the filter believes it (for studies that want a matched filter).
    Gaussian { extra_sd: f64 },
    /// Gill's reception mixture (Gill 2013, §2.4.1), conditioned on a decoded packet.
    GillMixture(Mixture),
}

/// Gill's range errors of a decoded packet: slightly long or short by up to `slight_max_m`, or an
/// outlier `outlier_min_m`–`outlier_max_m` long; the shares sum to at most 1, and the rest is a
/// packet decoded without a usable range. Drawn by the HBL world's sampler (two uniforms a draw).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mixture {
    pub p_slightly_long: f64,
    pub p_slightly_short: f64,
    pub p_outlier: f64,
    pub slight_max_m: f64,
    pub outlier_min_m: f64,
    pub outlier_max_m: f64,
}

impl Mixture {
    fn as_acoustic(&self) -> Acoustic {
        Acoustic {
            p_slightly_long: self.p_slightly_long,
            p_slightly_short: self.p_slightly_short,
            p_outlier: self.p_outlier,
            p_drop: (1.0 - self.p_slightly_long - self.p_slightly_short - self.p_outlier).max(0.0),
            slight_max_m: self.slight_max_m,
            outlier_min_m: self.outlier_min_m,
            outlier_max_m: self.outlier_max_m,
            ..Acoustic::default()
        }
    }
}

impl CheckFields for Mixture {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let mut need =
            |field: &str, v: f64, ok: bool, allowed: &str| p.require(&format!("{prefix}{field}"), v, ok, allowed);
        for (field, share) in [
            ("p_slightly_long", self.p_slightly_long),
            ("p_slightly_short", self.p_slightly_short),
            ("p_outlier", self.p_outlier),
        ] {
            need(field, share, (0.0..=1.0).contains(&share), "a probability in [0, 1]");
        }
        let sum = self.p_slightly_long + self.p_slightly_short + self.p_outlier;
        need("p_slightly_long + p_slightly_short + p_outlier", sum, sum <= 1.0 + 1e-9, "a sum <= 1");
        need("slight_max_m", self.slight_max_m, self.slight_max_m >= 0.0, "a finite number >= 0");
        need("outlier_min_m", self.outlier_min_m, self.outlier_min_m >= 0.0, "a finite number >= 0");
        need("outlier_max_m", self.outlier_max_m, self.outlier_max_m >= self.outlier_min_m, ">= outlier_min_m");
    }
}

impl RangeError {
    /// Gill's shares (0.50 / 0.35 / 0.05 of all messages, 0.10 dropped) renormalised to the
    /// decoded ones, since the success model already draws the drops.
    pub fn gill() -> Self {
        let a = Acoustic::default();
        let kept = 1.0 - a.p_drop;
        RangeError::GillMixture(Mixture {
            p_slightly_long: a.p_slightly_long / kept,
            p_slightly_short: a.p_slightly_short / kept,
            p_outlier: a.p_outlier / kept,
            slight_max_m: a.slight_max_m,
            outlier_min_m: a.outlier_min_m,
            outlier_max_m: a.outlier_max_m,
        })
    }

    /// The travel-time error (s) of one decoded range, or None when the range is unusable.
    /// `filter_variance` is the filter's range variance (m²) at this travel time.
    pub fn draw(&self, filter_variance: f64, rng: &mut ChaCha8Rng) -> Option<f64> {
        match self {
            RangeError::Gaussian { extra_sd } => {
                let sd = (filter_variance + extra_sd * extra_sd).sqrt();
                Some(sd * normal(rng) / GILL_NOMINAL_SOUND_SPEED)
            }
            RangeError::GillMixture(m) => match draw_reception(&m.as_acoustic(), rng) {
                Reception::Received(metres) => Some(metres / GILL_NOMINAL_SOUND_SPEED),
                Reception::Dropped => None,
            },
        }
    }
}

impl CheckFields for RangeError {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        match self {
            RangeError::Gaussian { extra_sd } => p.non_negative(&format!("{prefix}extra_sd"), *extra_sd),
            RangeError::GillMixture(m) => m.check_fields(prefix, p),
        }
    }
}

/// Relative difference under which two depths' costs count as a tie
/// ([`SoundSpeed::least_biased_depth`]).
const TIE_TOLERANCE: f64 = 1e-9;

/// The true sound speed. Travel time follows a straight ray between the two depths at the
/// harmonic-mean speed of the layers it crosses (no refraction: an invented simplification, no
/// thesis gives the ray model), so ranges the filters compute at their nominal speed carry the
/// real bias.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SoundSpeed {
    Constant {
        c: f64,
    },
    /// (depth m, speed m/s) points, depth increasing; linear between, constant beyond.
    Profile {
        points: Vec<[f64; 2]>,
    },
}

impl SoundSpeed {
    /// A shallow summer profile: warm mixed layer over a thermocline (invented, typical of
    /// temperate coastal water in summer).
    pub fn summer() -> Self {
        SoundSpeed::Profile { points: vec![[0.0, 1510.0], [10.0, 1509.0], [30.0, 1492.0], [100.0, 1488.0]] }
    }

    /// Speed at depth `z`.
    pub fn at(&self, z: f64) -> f64 {
        match self {
            SoundSpeed::Constant { c } => *c,
            SoundSpeed::Profile { points } => {
                let i = points.partition_point(|p| p[0] <= z);
                match (i.checked_sub(1).and_then(|j| points.get(j)), points.get(i)) {
                    (Some(a), Some(b)) => a[1] + (b[1] - a[1]) * (z - a[0]) / (b[0] - a[0]),
                    (Some(a), None) => a[1],
                    (None, Some(b)) => b[1],
                    (None, None) => GILL_NOMINAL_SOUND_SPEED,
                }
            }
        }
    }

    /// Harmonic-mean speed between depths `z1` and `z2` (the speed at the depth when equal).
    pub fn mean_between(&self, z1: f64, z2: f64) -> f64 {
        let (lo, hi) = (z1.min(z2), z1.max(z2));
        if hi - lo < 1e-6 {
            return self.at(lo);
        }
        let mut knots = vec![lo];
        if let SoundSpeed::Profile { points } = self {
            knots.extend(points.iter().map(|p| p[0]).filter(|&z| z > lo && z < hi));
        }
        knots.push(hi);
        // ∫ dz / c(z) over each linear piece: Δz · ln(c_b / c_a) / (c_b − c_a).
        let slowness: f64 = knots
            .windows(2)
            .map(|w| {
                let (ca, cb) = (self.at(w[0]), self.at(w[1]));
                let dz = w[1] - w[0];
                if (cb - ca).abs() < 1e-9 {
                    dz / ca
                } else {
                    dz * (cb / ca).ln() / (cb - ca)
                }
            })
            .sum();
        (hi - lo) / slowness
    }

    /// The whole-metre depth in `[lo, hi]` from which ranges to `auv_depths` (each rounded to the
    /// metre, every sample weighing the same) carry the least mean-squared scale error
    /// (c̄_filters / c̄_water − 1)² when the filters convert travel times at the harmonic-mean speeds
    /// of `filters` (a constant: the thesis's fixed speed; a cast: `filter.sound_speed`): the fixed
    /// cruise depth a team holding this profile as its CTD cast would pick (an invented rule,
    /// docs/models.md#closed-loop-world). Ties go to the shallowest; `lo` itself when `auv_depths` is empty.
    pub fn least_biased_depth(&self, filters: &SoundSpeed, auv_depths: &[f64], (lo, hi): (f64, f64)) -> f64 {
        let top = lo.ceil().max(0.0) as usize;
        let deepest = auv_depths.iter().fold(hi, |d, &z| d.max(z)).floor().max(top as f64) as usize;
        // Slowness from `top` down to each whole metre, exact over the profiles' linear pieces.
        let slowness = |s: &SoundSpeed| {
            let mut sum = vec![0.0; deepest - top + 1];
            for i in 1..sum.len() {
                let z = (top + i) as f64;
                sum[i] = sum[i - 1] + 1.0 / s.mean_between(z - 1.0, z);
            }
            sum
        };
        let (water, filter) = (slowness(self), slowness(filters));
        let mut weight = vec![0usize; water.len()];
        for &z in auv_depths {
            weight[(z.round().max(top as f64) as usize - top).min(deepest - top)] += 1;
        }
        // c̄_f / c̄_w = (dz / S_f) / (dz / S_w) = S_w / S_f.
        let scale_error = |i: usize, j: usize| match i.abs_diff(j) {
            0 => filters.at((top + i) as f64) / self.at((top + i) as f64) - 1.0,
            _ => (water[i] - water[j]) / (filter[i] - filter[j]) - 1.0,
        };
        let cost =
            |i: usize| weight.iter().enumerate().map(|(j, &w)| w as f64 * scale_error(i, j).powi(2)).sum::<f64>();
        let last = (hi.floor() as usize).clamp(top, deepest) - top;
        let costs: Vec<f64> = (0..=last).map(cost).collect();
        let least = costs.iter().copied().fold(f64::INFINITY, f64::min);
        // Rounding in the running sums must not pick a deeper depth of the same cost.
        let shallowest = costs.iter().position(|&c| c <= least * (1.0 + TIE_TOLERANCE)).unwrap_or(0);
        (top + shallowest) as f64
    }

    /// Slowest speed anywhere (the longest travel time a schedule must allow for).
    pub fn slowest(&self) -> f64 {
        match self {
            SoundSpeed::Constant { c } => *c,
            SoundSpeed::Profile { points } => points.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min),
        }
    }

    /// Travel time from `from` to a receiver at `to(dt)` `dt` seconds after transmission: the
    /// receiver moves during the flight (one fixed-point iteration suffices at vehicle speeds).
    pub fn travel_time(&self, from: Vec3, to: impl Fn(f64) -> Vec3) -> f64 {
        let c = |p: Vec3| self.mean_between(from.z, p.z);
        let first = to(0.0);
        let tt0 = (first - from).norm() / c(first);
        let later = to(tt0);
        (later - from).norm() / c(later)
    }
}

impl CheckFields for SoundSpeed {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let speed_ok = |c: f64| c.is_finite() && (1300.0..=1700.0).contains(&c);
        match self {
            SoundSpeed::Constant { c } if !speed_ok(*c) => {
                p.push(format!("{prefix}c"), c.to_string(), "1300..=1700 m/s")
            }
            SoundSpeed::Constant { .. } => {}
            SoundSpeed::Profile { points } => {
                if points.is_empty() {
                    p.push(format!("{prefix}points"), "[]", "at least one [depth, speed] point");
                }
                for (i, point) in points.iter().enumerate() {
                    let [depth, speed] = *point;
                    if !(depth.is_finite() && depth >= 0.0) {
                        p.push(format!("{prefix}points[{i}][0]"), depth.to_string(), "a depth >= 0 m");
                    }
                    if !speed_ok(speed) {
                        p.push(format!("{prefix}points[{i}][1]"), speed.to_string(), "1300..=1700 m/s");
                    }
                    if i > 0 && !(depth > points[i - 1][0]) {
                        p.push(format!("{prefix}points[{i}][0]"), depth.to_string(), "depths strictly increasing");
                    }
                }
            }
        }
    }
}

/// Each vehicle's clock: a fixed offset ~ N(0, offset_sd_s) and a drift rate ~ N(0, drift_sd_ppm)
/// drawn per run (invented defaults: perfect clocks; Gill's measured drift is 162 ± 203 µs/h,
/// Gill 2013, §2.1.3, about 0.05 ppm). OWTT ranges see the receiver's minus the sender's error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Clocks {
    pub offset_sd_s: f64,
    pub drift_sd_ppm: f64,
}

/// One vehicle's drawn clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clock {
    offset: f64,
    drift: f64,
}

impl Clocks {
    /// Draws one vehicle's clock: always two normals, whatever the configuration.
    pub fn draw(&self, rng: &mut ChaCha8Rng) -> Clock {
        let (a, b) = (normal(rng), normal(rng));
        Clock { offset: self.offset_sd_s * a, drift: self.drift_sd_ppm * 1e-6 * b }
    }
}

impl CheckFields for Clocks {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        for (field, v, max) in [("offset_sd_s", self.offset_sd_s, 1.0), ("drift_sd_ppm", self.drift_sd_ppm, 100.0)] {
            p.check(&format!("{prefix}{field}"), v, |v| (0.0..=max).contains(&v), &format!("0..={max}"));
        }
    }
}

impl Clock {
    /// The clock's error (reading minus true time) at true time `t`, s.
    pub fn error_at(&self, t: f64) -> f64 {
        self.offset + self.drift * t
    }
}

/// Overlapping arrivals at one receiver are lost; with a capture margin, the one stronger than
/// every overlapping arrival by at least that many dB survives (the others are still lost).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Collisions {
    pub capture_margin_db: Option<f64>,
}

impl CheckFields for Collisions {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let Some(m) = self.capture_margin_db {
            p.check(&format!("{prefix}capture_margin_db"), m, |m| m >= 0.0, "a finite number >= 0 dB");
        }
    }
}

/// The receiver type (the success model's Table 5 columns) of a link that ends at a survey AUV
/// (the CNA's broadcast, a buoy's, a mini-packet): the Iver2's.
pub const RECEIVER_AT_SURVEY_AUV: Receiver = Receiver::Iver2;

/// The receiver type of a link that ends at the CNA (a survey AUV's status): the barge's.
pub const RECEIVER_AT_CNA: Receiver = Receiver::Barge;

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::SeedStream;

    #[test]
    fn a_layered_profile_biases_ranges_at_the_nominal_speed() {
        let s = SoundSpeed::summer();
        assert_eq!(s.at(0.0), 1510.0);
        assert_eq!(s.at(20.0), 1500.5);
        assert_eq!(s.at(500.0), 1488.0);
        let mean = s.mean_between(0.0, 20.0);
        assert!(mean > 1500.5 && mean < 1510.0, "{mean}");
        let tt = s.travel_time(Vec3::new(0.0, 0.0, 0.0), |_| Vec3::new(1000.0, 0.0, 20.0));
        // The range a filter computes at 1500 m/s is short of the true 1000.2 m by metres.
        let bias = (1000.0f64.hypot(20.0)) - 1500.0 * tt;
        assert!(bias > 2.0 && bias < 6.0, "{bias}");
        assert_eq!(SoundSpeed::Constant { c: 1480.0 }.mean_between(3.0, 50.0), 1480.0);
    }

    #[test]
    fn the_least_biased_depth_is_the_brute_force_minimum_of_the_mean_squared_scale_error() {
        let (s, filters) = (SoundSpeed::summer(), SoundSpeed::Constant { c: 1500.0 });
        // Written out from `mean_between` at every whole-metre depth, no running sums.
        let brute = |auvs: &[f64], (lo, hi): (usize, usize)| {
            let cost = |z: usize| {
                auvs.iter().map(|&a| (1500.0 / s.mean_between(z as f64, a.round()) - 1.0).powi(2)).sum::<f64>()
            };
            (lo..=hi).fold(lo, |b, z| if cost(z) < cost(b) { z } else { b }) as f64
        };
        let cases: [(&[f64], (usize, usize)); 5] = [
            (&[20.0, 22.4, 37.6], (0, 100)),
            (&[20.0, 40.0, 60.0, 80.0], (0, 100)),
            (&[55.0], (0, 100)),
            (&[55.0], (3, 40)),
            (&[5.2, 7.9, 9.6, 80.0, 80.0], (2, 60)),
        ];
        for (auvs, (lo, hi)) in cases {
            let got = s.least_biased_depth(&filters, auvs, (lo as f64, hi as f64));
            assert_eq!(got, brute(auvs, (lo, hi)), "{auvs:?} in [{lo}, {hi}]");
        }
        // The water is at the filters' speed at 20.6 m: from 20 m to AUVs at 21 m the harmonic
        // mean is within 0.1 m/s of it (|f| 5e-5), from 21 m or 19 m it is 0.35 m/s and 0.5 m/s off.
        assert_eq!(s.least_biased_depth(&filters, &[21.0; 4], (0.0, 100.0)), 20.0);
        // Constant water biases every depth alike: the shallowest allowed.
        assert_eq!(SoundSpeed::Constant { c: 1490.0 }.least_biased_depth(&filters, &[30.0, 70.0], (4.0, 90.0)), 4.0);
        // Filters that convert with a cast of this very water have no bias anywhere: the shallowest.
        assert_eq!(s.least_biased_depth(&s, &[20.0, 80.0], (3.0, 90.0)), 3.0);
    }

    #[test]
    fn the_truth_range_noise_differs_from_the_filters_gaussian() {
        let filter_variance = 0.15f64.powi(2);
        let mut rng = SeedStream::new(3).rng(1);
        let gill: Vec<f64> = (0..20_000).filter_map(|_| RangeError::gill().draw(filter_variance, &mut rng)).collect();
        let gauss: Vec<f64> = (0..20_000)
            .filter_map(|_| RangeError::Gaussian { extra_sd: 0.0 }.draw(filter_variance, &mut rng))
            .collect();
        let metres = |v: &[f64]| v.iter().map(|t| t * 1500.0).collect::<Vec<_>>();
        let (gill, gauss) = (metres(&gill), metres(&gauss));
        let beyond = |v: &[f64], m: f64| v.iter().filter(|e| e.abs() > m).count() as f64 / v.len() as f64;
        // The Gaussian never reaches 5 m at σ = 0.15 m; Gill's mixture does 1 time in 18.
        assert_eq!(beyond(&gauss, 5.0 - 1e-9), 0.0);
        assert!((beyond(&gill, 5.0 - 1e-9) - 0.05 / 0.9).abs() < 0.01);
        let rms = (gauss.iter().map(|e| e * e).sum::<f64>() / gauss.len() as f64).sqrt();
        assert!((rms - 0.15).abs() < 0.01, "{rms}");
    }

    #[test]
    fn air_time_and_capacity_follow_the_rate_table() {
        assert_eq!((air_time(Rate::R0), capacity(Rate::R0)), (3.90, 32));
        assert_eq!((air_time(Rate::R5), capacity(Rate::R5)), (3.04, 2048));
    }
}
