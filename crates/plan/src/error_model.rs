//! The survey-AUV position-error model of Hudson 2012, Ch. 3, eq. (1) (reconstructed after Chitre et
//! al. 2010, whom the thesis follows: docs/models.md#hudson-error-model).
//!
//! Each survey AUV's horizontal error is split along the CNA–AUV line of sight into a radial part
//! σ (reset by every range) and a tangential part ε that grows by α·τ per step and is partly
//! replaced by σ when the bearing rotates:
//! `ε'² = σ²·sin²Δθ + ε²·cos²Δθ + α·τ`.
//! The bearing change is computed from un-normalised line-of-sight vectors, so no trigonometry
//! is needed: `cos²Δθ = (u·v)² / (|u|²|v|²)`.

use coopnav_core::Vec3;
use serde::{Deserialize, Serialize};

/// Which angle the bearing change Δθ is measured in (docs/models.md#hudson-error-model).
///
/// Choose `slant3d` for an AUV CNA: under the horizontal bearing its pitch options only shorten
/// its step, so it scores exactly like an ASC, while the thesis's Sec. 5.3 tables put AUV CNAs on
/// top (that ordering returns with the 3-D bearing, which `coopnav_sim`'s Hudson reproductions
/// use for Sec. 5.3). The default stays horizontal because Table 6.1's 2.22 m floor needs it
/// (docs/models.md#hudson-error-model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum BearingMode {
    /// θ = atan2(Δy, Δx): the horizontal bearing (default; fits the thesis's 2.22 m floor).
    #[default]
    Horizontal,
    /// Angle between successive 3-D line-of-sight vectors (depth matters: AUV CNAs).
    Slant3d,
}

/// What the per-AUV cost term is (docs/models.md#hudson-error-model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum CostMode {
    /// σ² + ε² (default).
    #[default]
    Total,
    /// ε² only (sensitivity runs).
    TangentialOnly,
}

/// The error-model parameters shared by all survey AUVs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorModel {
    /// Velocity-estimate error α, m²/s (Table 5.1: 0.1).
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    #[serde(default)]
    pub bearing: BearingMode,
    #[serde(default)]
    pub cost: CostMode,
}

fn default_alpha() -> f64 {
    0.1
}

impl Default for ErrorModel {
    fn default() -> Self {
        ErrorModel { alpha: default_alpha(), bearing: BearingMode::default(), cost: CostMode::default() }
    }
}

/// One survey AUV's modelled error after a range: variances and the line of sight it was taken on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AuvError {
    /// Radial variance σ², m² (constant per AUV unless an external update overwrites it).
    pub sigma2: f64,
    /// Tangential variance ε², m².
    pub eps2: f64,
    /// Un-normalised line of sight CNA → AUV in the bearing frame (z zeroed for `Horizontal`).
    pub los: [f64; 3],
}

impl AuvError {
    /// Total error e = √(σ² + ε²), metres (docs/models.md#hudson-metrics).
    pub fn total(&self) -> f64 {
        (self.sigma2 + self.eps2).sqrt()
    }
}

impl ErrorModel {
    /// Line of sight from `cna` to `auv` in the bearing frame of this model.
    #[inline]
    pub fn los(&self, cna: [f64; 3], auv: [f64; 3]) -> [f64; 3] {
        let dz = match self.bearing {
            BearingMode::Horizontal => 0.0,
            BearingMode::Slant3d => auv[2] - cna[2],
        };
        [auv[0] - cna[0], auv[1] - cna[1], dz]
    }

    /// Error state at planning start: σ₀, ε₀ (Table 5.1: 1 m each) and the initial bearing
    /// (docs/models.md#hudson-start).
    pub fn initial(&self, sigma0: f64, eps0: f64, cna: &Vec3, auv: &Vec3) -> AuvError {
        AuvError { sigma2: sigma0 * sigma0, eps2: eps0 * eps0, los: self.los(to_arr(cna), to_arr(auv)) }
    }

    /// Per-AUV cost term (eq. 3).
    #[inline]
    pub fn cost_term(&self, sigma2: f64, eps2: f64) -> f64 {
        match self.cost {
            CostMode::Total => sigma2 + eps2,
            CostMode::TangentialOnly => eps2,
        }
    }

    /// The error after one step of `tau` seconds ending with a range on `los_new`.
    pub fn step(&self, prev: &AuvError, los_new: [f64; 3], tau: f64) -> AuvError {
        let (eps2, los) = tangential_update(prev.sigma2, prev.eps2, &prev.los, los_new, self.alpha * tau);
        AuvError { sigma2: prev.sigma2, eps2, los }
    }
}

/// Eq. (1a). Returns the new ε² and the line of sight to remember. When the CNA is directly above
/// the AUV (no horizontal bearing), the bearing is taken as unchanged.
#[inline(always)]
pub(crate) fn tangential_update(
    sigma2: f64,
    eps2: f64,
    prev: &[f64; 3],
    new: [f64; 3],
    alpha_tau: f64,
) -> (f64, [f64; 3]) {
    let n_prev = prev[0] * prev[0] + prev[1] * prev[1] + prev[2] * prev[2];
    let n_new = new[0] * new[0] + new[1] * new[1] + new[2] * new[2];
    let denom = n_prev * n_new;
    if denom <= 1e-18 {
        let keep = if n_new <= 1e-9 { *prev } else { new };
        return (eps2 + alpha_tau, keep);
    }
    let dot = prev[0] * new[0] + prev[1] * new[1] + prev[2] * new[2];
    let c2 = (dot * dot / denom).min(1.0);
    (sigma2 * (1.0 - c2) + eps2 * c2 + alpha_tau, new)
}

pub(crate) fn to_arr(v: &Vec3) -> [f64; 3] {
    [v.x, v.y, v.z]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_geometry_reaches_the_floor() {
        // A 90° bearing change every step: ε² → σ² + ατ, total error → √(2σ² + ατ) (docs/models.md#hudson-error-model).
        let m = ErrorModel::default();
        let tau = 30.0;
        let mut e = m.initial(1.0, 1.0, &Vec3::zeros(), &Vec3::new(100.0, 0.0, 0.0));
        for n in 0..20 {
            let ang = (n + 1) as f64 * std::f64::consts::FRAC_PI_2;
            e = m.step(&e, [100.0 * ang.cos(), 100.0 * ang.sin(), 0.0], tau);
        }
        assert!((e.total() - 5f64.sqrt()).abs() < 1e-9, "{}", e.total());
    }

    #[test]
    fn constant_bearing_grows_unaided() {
        // ε² = ε₀² + n·α·τ when the bearing never changes (docs/models.md#hudson-error-model).
        let m = ErrorModel::default();
        let mut e = m.initial(1.0, 1.5, &Vec3::zeros(), &Vec3::new(0.0, 300.0, 50.0));
        for n in 1..=50 {
            e = m.step(&e, [0.0, 200.0 + n as f64, 0.0], 10.0);
            assert!((e.eps2 - (2.25 + n as f64 * 1.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn slant_mode_sees_depth_changes() {
        let h = ErrorModel::default();
        let s = ErrorModel { bearing: BearingMode::Slant3d, ..h };
        let cna = Vec3::zeros();
        let a = Vec3::new(100.0, 0.0, 0.0);
        let eh = h.step(&h.initial(1.0, 2.0, &cna, &a), h.los([0.0; 3], [100.0, 0.0, 100.0]), 10.0);
        let es = s.step(&s.initial(1.0, 2.0, &cna, &a), s.los([0.0; 3], [100.0, 0.0, 100.0]), 10.0);
        assert!((eh.eps2 - 5.0).abs() < 1e-12);
        assert!((es.eps2 - (0.5 + 2.0 + 1.0)).abs() < 1e-12);
    }
}
