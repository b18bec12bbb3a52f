//! The OWTT range measurement: r = c·τ from top-of-second timing (eq. 3), the transponder's
//! position at transmit time, and the range-dependent noise σ²_r = τ²σ_c² + c²σ_τ² (Gill 2013,
//! §2.2.1, whose labels are swapped; this is the dimensionally consistent form:
//! docs/models.md#gill-range-noise).

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::Vec3;
use serde::{Deserialize, Serialize};

/// One received range, independent of who sent it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeMeasurement {
    /// Measured range (m) = assumed sound speed × travel time.
    pub range: f64,
    /// Travel time τ (s): modem receive time minus the top-of-second transmit time.
    pub travel_time: f64,
    /// Where the transponder was when it transmitted (x east, y north, z depth), as best known.
    pub transponder: Vec3,
}

impl RangeMeasurement {
    /// The range a receiver computes from its clock: τ = t_rx − t_tx, r = c·τ.
    pub fn from_timing(t_tx: f64, t_rx: f64, sound_speed: f64, transponder: Vec3) -> Self {
        let travel_time = t_rx - t_tx;
        RangeMeasurement { range: sound_speed * travel_time, travel_time, transponder }
    }
}

/// Range noise model. Reconstructed: docs/models.md#gill-range-noise (the thesis keeps R^A at unpublished
/// MSBL values). Defaults: σ_c = 3 m/s, c = 1500 m/s, and σ_τ = 1.2 ms, so that c·σ_τ = 1.80 m is
/// the RMS error of a received range under the thesis's acoustic mixture (Gill 2013, §2.4.1: 85 % within
/// 0.2 m, 5 % 5–10 m long; `coopnav_sim::models::noise::Acoustic::received_error_mean_square`,
/// whose test pins this value). A σ_τ of 0.1 ms (0.15 m) would ignore the outliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RangeNoise {
    /// Sound-speed SD (m/s): the term that grows with range.
    pub sigma_sound_speed: f64,
    /// Timing SD (s): multipath and detection jitter, the source of the outliers.
    pub sigma_time: f64,
    /// Assumed sound speed (m/s).
    pub sound_speed: f64,
    /// Floor added to the variance (m²), so a zero-length range still has noise.
    pub floor: f64,
}

impl Default for RangeNoise {
    fn default() -> Self {
        RangeNoise { sigma_sound_speed: 3.0, sigma_time: 1.2e-3, sound_speed: 1500.0, floor: 0.0 }
    }
}

impl RangeNoise {
    /// σ²_r for travel time τ.
    pub fn variance(&self, travel_time: f64) -> f64 {
        let t = travel_time.abs();
        t * t * self.sigma_sound_speed.powi(2) + (self.sound_speed * self.sigma_time).powi(2) + self.floor
    }
}

impl CheckFields for RangeNoise {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.non_negative(&format!("{prefix}sigma_sound_speed"), self.sigma_sound_speed);
        p.non_negative(&format!("{prefix}sigma_time"), self.sigma_time);
        p.positive(&format!("{prefix}sound_speed"), self.sound_speed);
        p.non_negative(&format!("{prefix}floor"), self.floor);
        let all_finite =
            [self.sigma_sound_speed, self.sigma_time, self.sound_speed, self.floor].iter().all(|v| v.is_finite());
        if all_finite && self.variance(0.0) <= 0.0 {
            p.push(
                format!("{prefix}sigma_time or {prefix}floor"),
                "0",
                "one of them > 0 (a zero-length range needs noise)",
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_grows_with_travel_time() {
        let n = RangeNoise { sigma_time: 1e-4, ..RangeNoise::default() };
        assert!((n.variance(0.0) - 0.0225).abs() < 1e-12);
        assert!((n.variance(0.2) - (0.36 + 0.0225)).abs() < 1e-12);
        assert!(n.variance(0.5) > n.variance(0.2));
    }

    #[test]
    fn timing_gives_range() {
        let m = RangeMeasurement::from_timing(10.0, 10.1, 1500.0, Vec3::zeros());
        assert!((m.range - 150.0).abs() < 1e-9 && (m.travel_time - 0.1).abs() < 1e-12);
    }
}
