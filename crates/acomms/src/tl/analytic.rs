//! Analytic transmission loss: TL = k·10·log10(d) + α(f)·d, with Thorp's absorption α
//! (Nams 2014, eq. 11, whose body is lost: reconstructed, docs/models.md#nams-transmission-loss;
//! k = 1.5 is the value of the thesis's reference 5, 2 is spherical spreading). The thesis calls it
//! "overly generic".

use super::{TlError, TransmissionLoss};
use coopnav_core::Vec3;
use serde::{Deserialize, Serialize};

/// Spreading + Thorp absorption.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Thorp {
    /// Spreading factor k (1 cylindrical, 1.5 practical, 2 spherical).
    pub k: f64,
    pub freq_hz: f64,
}

impl Default for Thorp {
    fn default() -> Self {
        Thorp { k: 1.5, freq_hz: 25_000.0 }
    }
}

impl Thorp {
    /// Thorp absorption, dB/km, f in kHz.
    pub fn alpha_db_per_km(freq_hz: f64) -> f64 {
        let f2 = (freq_hz / 1000.0).powi(2);
        0.11 * f2 / (1.0 + f2) + 44.0 * f2 / (4100.0 + f2) + 2.75e-4 * f2 + 0.003
    }
    /// TL at slant distance `d` m (distances under 1 m count as 1 m).
    pub fn at_distance(&self, d: f64) -> f64 {
        let d = d.max(1.0);
        self.k * 10.0 * d.log10() + Self::alpha_db_per_km(self.freq_hz) * d / 1000.0
    }
}

impl TransmissionLoss for Thorp {
    fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
        let d = (rx - src).norm();
        if !d.is_finite() {
            return Err(TlError::Invalid(format!("non-finite positions {src:?} → {rx:?}")));
        }
        Ok(self.at_distance(d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_thorp_reference_values() {
        let t = Thorp::default();
        assert!((Thorp::alpha_db_per_km(25_000.0) - 6.105).abs() < 0.01);
        for (d, tl) in [(100.0, 30.6), (500.0, 43.5), (1000.0, 51.1), (2000.0, 61.7), (2800.0, 68.8)] {
            assert!((t.at_distance(d) - tl).abs() < 0.1, "{d}: {}", t.at_distance(d));
        }
        let a = Vec3::new(0.0, 0.0, 10.0);
        assert!((t.tl(&a, &Vec3::new(300.0, 400.0, 10.0)).unwrap() - t.at_distance(500.0)).abs() < 1e-12);
        assert!(t.tl(&a, &Vec3::new(f64::NAN, 0.0, 0.0)).is_err());
    }
}
