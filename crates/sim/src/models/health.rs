//! Filter health judged against the truth, so that a finite but wrong filter is not called
//! healthy: NEES of the horizontal position every second, NIS of every range update, and a
//! divergence flag when the NEES stays above its 99.9 % chi-square bound for a sustained window.

use super::metrics::FilterHealth;
use coopnav_nav::Recoveries;
use serde::{Deserialize, Serialize};

/// χ²(2) quantile: −2 ln(1 − p) (closed form for two degrees of freedom).
fn chi2_2(p: f64) -> f64 {
    -2.0 * (1.0 - p).ln()
}
/// χ²(1) 95 % quantile.
const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// The `[health]` table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Health {
    /// A filter whose NEES stays above the 99.9 % bound this long (s) is flagged as diverged.
    /// Invented default: one minute, two CNA cycles at τ = 30 s.
    pub divergence_window_s: f64,
}

impl Default for Health {
    fn default() -> Self {
        Health { divergence_window_s: 60.0 }
    }
}

/// Horizontal-position NEES eᵀ P⁻¹ e of the error (ex, ey) under covariance [[a, b], [b, d]].
pub fn nees_2d(ex: f64, ey: f64, a: f64, b: f64, d: f64) -> f64 {
    let det = a * d - b * b;
    if det > 0.0 {
        (d * ex * ex - 2.0 * b * ex * ey + a * ey * ey) / det
    } else {
        f64::INFINITY
    }
}

/// Running sums of one filter's consistency.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    samples: u64,
    error_sq: f64,
    sigma: f64,
    sigma_sq: f64,
    nees: f64,
    nees_in_95: u64,
    nis: f64,
    nis_n: u64,
    nis_in_95: u64,
    above_since: Option<f64>,
    diverged_at: Option<f64>,
    recoveries: Recoveries,
}

impl Tally {
    /// One sample at `t`: true error, the filter's 1-σ and the NEES.
    pub fn sample(&mut self, spec: &Health, t: f64, error: f64, sigma: f64, nees: f64) {
        self.samples += 1;
        self.error_sq += error * error;
        self.sigma += sigma;
        self.sigma_sq += sigma * sigma;
        self.nees += nees.min(1e12);
        self.nees_in_95 += u64::from(nees <= chi2_2(0.95));
        if nees > chi2_2(0.999) {
            let since = *self.above_since.get_or_insert(t);
            if t - since >= spec.divergence_window_s && self.diverged_at.is_none() {
                self.diverged_at = Some(t);
            }
        } else {
            self.above_since = None;
        }
    }

    pub fn nis(&mut self, nis: f64) {
        self.nis += nis;
        self.nis_n += 1;
        self.nis_in_95 += u64::from(nis <= CHI2_1_95);
    }

    /// The filter's own recoveries ([`Recoveries`]) over the run, as it ended.
    pub fn recovered(&mut self, recoveries: Recoveries) {
        self.recoveries = recoveries;
    }

    pub fn summary(&self) -> FilterHealth {
        let n = self.samples.max(1) as f64;
        let per_nis = |v: f64| (self.nis_n > 0).then(|| v / self.nis_n as f64);
        FilterHealth {
            sigma_mean: self.sigma / n,
            error_to_sigma: (self.error_sq / self.sigma_sq.max(1e-300)).sqrt(),
            nees_mean: self.nees / n,
            nees_in_95: self.nees_in_95 as f64 / n,
            nis_mean: per_nis(self.nis),
            nis_in_95: per_nis(self.nis_in_95 as f64),
            diverged_at_s: self.diverged_at,
            recoveries: self.recoveries.count,
            recovered_first_s: self.recoveries.first_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_and_the_sustained_window() {
        assert!((chi2_2(0.95) - 5.991).abs() < 1e-3 && (chi2_2(0.999) - 13.816).abs() < 1e-3);
        assert!((nees_2d(2.0, 0.0, 4.0, 0.0, 1.0) - 1.0).abs() < 1e-12);
        let spec = Health { divergence_window_s: 10.0 };
        let mut t = Tally::default();
        // Above the bound for 9 s, back inside, then 10 s above: flagged at the second run's end.
        for s in 0..9 {
            t.sample(&spec, s as f64, 1.0, 0.1, 50.0);
        }
        t.sample(&spec, 9.0, 1.0, 1.0, 1.0);
        assert_eq!(t.summary().diverged_at_s, None);
        for s in 10..=20 {
            t.sample(&spec, s as f64, 1.0, 0.1, 50.0);
        }
        assert_eq!(t.summary().diverged_at_s, Some(20.0));
        assert!((t.summary().nees_in_95 - 1.0 / 21.0).abs() < 1e-12);
    }
}
