//! What a post-processing run says about its own accuracy without truth
//! (docs/models.md#post-quality): the mean NIS of the ranges with its χ² verdict, the accuracy the
//! smoothed track claims (mean and 95th percentile of its horizontal σ), the held-out range
//! residuals of a cross-validation when one was run, and each beacon's residual statistics.

use crate::fieldlog::BeaconId;
use crate::post::{PostResult, RangeResidual};
use crate::post_tune::CrossValidation;
use serde::Serialize;
use std::collections::BTreeMap;

/// Standard normal quantile at 97.5 %: the two-sided 95 % bounds.
const Z_975: f64 = 1.959_964;

/// The mean NIS of n ranges against the two-sided 95 % bounds of χ²(n)/n.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NisCheck {
    /// Ranges the filter saw (applied or gated, not held out).
    pub ranges: usize,
    pub mean: f64,
    pub bounds_95: (f64, f64),
    pub verdict: NisVerdict,
}

/// Where the mean NIS falls against its bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NisVerdict {
    /// Inside the bounds: the filter's predicted innovation spread matches the ranges.
    Consistent,
    /// Above: the innovations are larger than the filter claims (it is overconfident).
    Overconfident,
    /// Below: the innovations are smaller than it claims (it is too cautious).
    Underconfident,
}

impl NisCheck {
    /// The check of `nis` values (None for none).
    pub fn of(nis: &[f64]) -> Option<NisCheck> {
        let n = nis.len();
        if n == 0 {
            return None;
        }
        let mean = nis.iter().sum::<f64>() / n as f64;
        let bounds_95 = (chi2_mean_quantile(n, -Z_975), chi2_mean_quantile(n, Z_975));
        let verdict = if mean > bounds_95.1 {
            NisVerdict::Overconfident
        } else if mean < bounds_95.0 {
            NisVerdict::Underconfident
        } else {
            NisVerdict::Consistent
        };
        Some(NisCheck { ranges: n, mean, bounds_95, verdict })
    }
}

/// The quantile of χ²(n)/n at the standard normal quantile z, by the Wilson–Hilferty cube-root
/// approximation (χ²(n)/n)^(1/3) ≈ N(1 − 2/(9n), 2/(9n)), within 1 % of the exact quantile for
/// n ≥ 5 at 95 % (docs/models.md#post-quality).
fn chi2_mean_quantile(n: usize, z: f64) -> f64 {
    let a = 2.0 / (9.0 * n as f64);
    (1.0 - a + z * a.sqrt()).max(0.0).powi(3)
}

/// The smoothed track's claimed horizontal accuracy √(σ_E² + σ_N²) over its steps (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClaimedAccuracy {
    pub mean_sd_m: f64,
    pub p95_sd_m: f64,
    pub max_sd_m: f64,
}

impl ClaimedAccuracy {
    pub fn of(result: &PostResult) -> Option<ClaimedAccuracy> {
        let mut sd: Vec<f64> = result.samples.iter().map(|s| s.smoothed_sd[0].hypot(s.smoothed_sd[1])).collect();
        if sd.is_empty() {
            return None;
        }
        sd.sort_by(f64::total_cmp);
        let mean_sd_m = sd.iter().sum::<f64>() / sd.len() as f64;
        let p95 = ((0.95 * sd.len() as f64).ceil() as usize).clamp(1, sd.len()) - 1;
        Some(ClaimedAccuracy { mean_sd_m, p95_sd_m: sd[p95], max_sd_m: sd[sd.len() - 1] })
    }
}

/// One beacon's ranges and residuals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BeaconStats {
    pub beacon: BeaconId,
    /// Ranges that reached the filter (applied or gated).
    pub ranges: usize,
    pub applied: usize,
    pub gated: usize,
    /// Mean and RMS of the applied ranges' innovations and smoothed residuals (m): a mean far
    /// from 0 is a bias of that beacon (a fix offset, a timing error).
    pub mean_innovation_m: Option<f64>,
    pub rms_innovation_m: Option<f64>,
    pub mean_smoothed_m: Option<f64>,
    pub rms_smoothed_m: Option<f64>,
    /// Mean NIS of its ranges (1 when consistent).
    pub mean_nis: Option<f64>,
}

impl BeaconStats {
    fn of(beacon: BeaconId, r: &[&RangeResidual]) -> BeaconStats {
        let applied: Vec<&&RangeResidual> = r.iter().filter(|x| x.applied).collect();
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let rms = |v: &[f64]| mean(&v.iter().map(|x| x * x).collect::<Vec<_>>()).map(f64::sqrt);
        let innovations: Vec<f64> = applied.iter().map(|x| x.innovation).collect();
        let smoothed: Vec<f64> = applied.iter().map(|x| x.smoothed).filter(|v| !v.is_nan()).collect();
        BeaconStats {
            beacon,
            ranges: r.len(),
            applied: applied.len(),
            gated: r.len() - applied.len(),
            mean_innovation_m: mean(&innovations),
            rms_innovation_m: rms(&innovations),
            mean_smoothed_m: mean(&smoothed),
            rms_smoothed_m: rms(&smoothed),
            mean_nis: mean(&r.iter().map(|x| x.nis).collect::<Vec<_>>()),
        }
    }
}

/// The run's figures that need no truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quality {
    /// The ranges' NIS before their updates.
    pub nis: Option<NisCheck>,
    pub claimed_accuracy: Option<ClaimedAccuracy>,
    /// The held-out ranges of a cross-validation with the run's values (None when not run).
    pub held_out: Option<CrossValidation>,
    pub beacons: Vec<BeaconStats>,
}

impl Quality {
    pub fn of(result: &PostResult, held_out: Option<CrossValidation>) -> Quality {
        let seen: Vec<&RangeResidual> = result.residuals.iter().filter(|r| !r.held_out).collect();
        let nis: Vec<f64> = seen.iter().map(|r| r.nis).collect();
        let mut by_beacon: BTreeMap<BeaconId, Vec<&RangeResidual>> = BTreeMap::new();
        for r in &seen {
            by_beacon.entry(r.beacon).or_default().push(r);
        }
        Quality {
            nis: NisCheck::of(&nis),
            claimed_accuracy: ClaimedAccuracy::of(result),
            held_out,
            beacons: by_beacon.iter().map(|(b, r)| BeaconStats::of(*b, r)).collect(),
        }
    }

    /// One sentence per figure that says the result is less good than it claims.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(n) = self.nis.filter(|n| n.verdict != NisVerdict::Consistent) {
            let (lo, hi) = n.bounds_95;
            let what = match n.verdict {
                NisVerdict::Overconfident => "the filter claims more accuracy than its ranges show",
                _ => "the filter claims less accuracy than its ranges show",
            };
            w.push(format!(
                "mean NIS {:.2} of {} ranges is outside its 95 % bounds [{lo:.2}, {hi:.2}]: {what}",
                n.mean, n.ranges
            ));
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chi2_bounds_match_the_tables() {
        // χ²(10) at 2.5 % and 97.5 %: 3.247 and 20.483; χ²(50): 32.357 and 71.420.
        for (n, lo, hi) in [(10, 3.247, 20.483), (50, 32.357, 71.420)] {
            let (a, b) = (chi2_mean_quantile(n, -Z_975) * n as f64, chi2_mean_quantile(n, Z_975) * n as f64);
            assert!((a / lo - 1.0).abs() < 0.01 && (b / hi - 1.0).abs() < 0.01, "n {n}: {a} {b}");
        }
    }

    #[test]
    fn the_verdict_follows_the_mean_nis() {
        assert_eq!(NisCheck::of(&[1.0; 40]).unwrap().verdict, NisVerdict::Consistent);
        assert_eq!(NisCheck::of(&[2.0; 40]).unwrap().verdict, NisVerdict::Overconfident);
        assert_eq!(NisCheck::of(&[0.3; 40]).unwrap().verdict, NisVerdict::Underconfident);
        assert!(NisCheck::of(&[]).is_none());
    }
}
