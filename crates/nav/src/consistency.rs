//! What keeps an AUV filter's range updates consistent when its prior is wide or its geometry
//! poor, an extension of Gill 2013, §2.2.1 (whose EKF linearises each range once and checks
//! nothing): the sigma-point statistics of a range over the position prior ([`sigma_point_range`],
//! behind `range_update = { kind = "unscented" }`), and the windowed NIS test that says the filter
//! has left its bounds ([`RangeHealth`], [`NisWindow`]). Why and which values:
//! docs/models.md#range-consistency.

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::Vec3;
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// n + κ of the unscented transform over the 2-D position (n = 2, κ = 1): the choice n + κ = 3
/// matches a Gaussian's fourth moment along each axis (Julier & Uhlmann 1997), which is what
/// the variance of a range's curvature term (quadratic in the cross-range error) depends on.
const N_PLUS_KAPPA: f64 = 3.0;

/// A range's statistics over a Gaussian position prior (mean `mean`, covariance `p`, horizontal,
/// east/north), by the unscented transform: the predicted range z̄, the statistically linearised
/// row H (∂z̄ by regression, Cov(p, z) = P H ᵀ) and the variance Ω the linear row leaves
/// unexplained (the curvature's spread: Var z = H P Hᵀ + Ω). The update with H and range variance
/// R + Ω is the unscented Kalman update (the regression form of Särkkä 2013, ch. 5); with a
/// transponder far off it is the EKF, overhead it moves the mean little (the range says how far,
/// not which way). None when `p` is not positive definite.
pub fn sigma_point_range(
    mean: Vector2<f64>,
    p: Matrix2<f64>,
    transponder: &Vec3,
    auv_depth: Option<f64>,
) -> Option<SigmaRange> {
    let l = p.cholesky()?.l();
    let spread = N_PLUS_KAPPA.sqrt();
    let dz = auv_depth.map_or(0.0, |z| z - transponder.z);
    let range = |at: Vector2<f64>| (at.x - transponder.x).hypot(at.y - transponder.y).hypot(dz);
    let (w0, wi) = ((N_PLUS_KAPPA - 2.0) / N_PLUS_KAPPA, 0.5 / N_PLUS_KAPPA);
    let offsets = [l.column(0) * spread, -l.column(0) * spread, l.column(1) * spread, -l.column(1) * spread];
    let z0 = range(mean);
    let zs = offsets.map(|d| range(mean + d));
    let z_mean = w0 * z0 + wi * zs.iter().sum::<f64>();
    let mut p_zz = w0 * (z0 - z_mean).powi(2);
    let mut p_pz = Vector2::zeros();
    for (d, z) in offsets.iter().zip(zs) {
        p_zz += wi * (z - z_mean).powi(2);
        p_pz += d * (wi * (z - z_mean));
    }
    let h = p.cholesky()?.solve(&p_pz);
    // Non-negative for positive weights (the residual of a weighted regression); kept so in rounding.
    let unexplained = (p_zz - h.dot(&p_pz)).max(0.0);
    Some(SigmaRange { predicted: z_mean, h: [h.x, h.y], unexplained })
}

/// What [`sigma_point_range`] finds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmaRange {
    /// The mean range over the prior, m.
    pub predicted: f64,
    /// The regression row over (E, N).
    pub h: [f64; 2],
    /// The range variance the row leaves unexplained, m².
    pub unexplained: f64,
}

/// The filter's own health check on its ranges, for a vehicle without truth (invented
/// parameters, docs/models.md#range-consistency). For a consistent filter a range's NIS is χ²(1)
/// and exceeds its 99 % quantile, 6.63, one time in a hundred; when more than half of the last
/// `window` ranges (gated ones included) exceed it, the filter has left its bounds: a majority,
/// not a sum, so that the channel's long outliers (Gill's 5.6 %, each a NIS up to about 25) do not
/// trip it. It then recovers: its horizontal position variance is raised by the mean excess
/// innovation² − S of the ranges that exceeded, the current states' variance back to their
/// prior, and the range that tripped the test is applied without the gate, relinearised about the
/// wider prior.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RangeHealth {
    /// Ranges in the window (≥ 1). Default 5: a consistent filter trips it with probability
    /// 10 C 3 · 0.01³ ≈ 10⁻⁵ per window, and about 2·10⁻³ among 5.6 % outliers; a lock-out of
    /// gated ranges trips it on its third.
    pub window: u32,
}

impl Default for RangeHealth {
    fn default() -> Self {
        RangeHealth { window: 5 }
    }
}

/// χ²(1) 99 % quantile: a range's NIS above it counts against the filter.
pub const NIS_99: f64 = 6.634_896_601_021_214;

impl RangeHealth {
    /// Ranges above [`NIS_99`] among the last `window` that trip the check: more than half.
    pub fn majority(&self) -> usize {
        self.window.max(1) as usize / 2 + 1
    }
}

impl CheckFields for RangeHealth {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if self.window == 0 {
            p.push(format!("{prefix}window"), "0", "a whole number >= 1");
        }
    }
}

/// The last ranges' NIS, innovations² and innovation variances ([`RangeHealth`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NisWindow {
    /// (NIS, y², S) of each range, oldest first, at most `window` of them.
    recent: std::collections::VecDeque<(f64, f64, f64)>,
}

impl NisWindow {
    /// Adds a range's innovation `y` and variance `s`; returns the horizontal variance (m²) to add
    /// when the window has just left its bound (the window is then emptied), else None.
    pub fn push(&mut self, health: &RangeHealth, y: f64, s: f64) -> Option<f64> {
        if !(y.is_finite() && s > 0.0 && s.is_finite()) {
            return None;
        }
        let window = health.window.max(1) as usize;
        if self.recent.len() == window {
            self.recent.pop_front();
        }
        self.recent.push_back((y * y / s, y * y, s));
        let above: Vec<&(f64, f64, f64)> = self.recent.iter().filter(|r| r.0 > NIS_99).collect();
        if above.len() < health.majority() {
            return None;
        }
        let excess = above.iter().map(|r| r.1 - r.2).sum::<f64>() / above.len() as f64;
        self.recent.clear();
        Some(excess)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_consistent_run_and_lone_outliers_never_trip_the_window_and_a_run_of_misses_does() {
        let health = RangeHealth::default();
        let mut w = NisWindow::default();
        // Innovations of one σ each (NIS 1), and every fourth an outlier 10 m long at S = 4 m²
        // (NIS 25): never a majority.
        let ys = (0..60).map(|k| {
            if k % 4 == 3 {
                10.0
            } else if k % 2 == 0 {
                2.0
            } else {
                -2.0
            }
        });
        assert!(ys.into_iter().all(|y| w.push(&health, y, 4.0).is_none()));
        // After an outlier, misses of 30 m at S = 4 m² trip it on the second: three of five above.
        let trips: Vec<Option<f64>> = (0..2).map(|_| w.push(&health, 30.0, 4.0)).collect();
        // The raise is the mean excess y² − S of those three: the outlier's 96, each miss's 896.
        assert_eq!(trips, [None, Some((96.0 + 2.0 * 896.0) / 3.0)]);
        // The window starts again: a lock-out from scratch trips on its third range.
        let trips: Vec<Option<f64>> = (0..3).map(|_| w.push(&health, 30.0, 4.0)).collect();
        assert_eq!(trips, [None, None, Some(896.0)]);
    }

    #[test]
    fn far_off_the_sigma_points_give_the_ekf_and_overhead_they_give_no_direction() {
        let p = Matrix2::new(25.0, 5.0, 5.0, 16.0);
        let far = sigma_point_range(Vector2::new(0.0, 0.0), p, &Vec3::new(30_000.0, 40_000.0, 0.0), None).unwrap();
        assert!(
            (far.predicted - 50_000.0).abs() < 1e-3 && (far.h[0] + 0.6).abs() < 1e-6 && (far.h[1] + 0.8).abs() < 1e-6
        );
        assert!(far.unexplained < 1e-6, "{far:?}");
        // A transponder over the mean: the range's mean is the spread's, its regression on the
        // position zero (every sigma point as far as its mirror), all its variance unexplained.
        let p = Matrix2::new(400.0, 0.0, 0.0, 400.0);
        let over = sigma_point_range(Vector2::new(10.0, 10.0), p, &Vec3::new(10.0, 10.0, 0.0), None).unwrap();
        assert!(over.h[0].abs() < 1e-12 && over.h[1].abs() < 1e-12, "{over:?}");
        assert!((over.predicted - 2.0 / 3.0 * 3f64.sqrt() * 20.0).abs() < 1e-9, "{over:?}");
        assert!(over.unexplained > 100.0);
        // 1 km away with σ = 300 m across the line of sight: the range's curvature term t²/2r has
        // variance σ⁴/2r² = 4050 m² for a Gaussian t, which the linear row cannot explain.
        let p = Matrix2::new(1.0, 0.0, 0.0, 90_000.0);
        let wide = sigma_point_range(Vector2::new(0.0, 0.0), p, &Vec3::new(-1000.0, 0.0, 0.0), None).unwrap();
        assert!((wide.unexplained / 4050.0 - 1.0).abs() < 0.15, "{wide:?}");
        assert!((wide.h[0] - 1.0).abs() < 0.01 && wide.h[1].abs() < 1e-9, "{wide:?}");
        assert!(sigma_point_range(Vector2::zeros(), Matrix2::zeros(), &Vec3::zeros(), None).is_none());
    }
}
