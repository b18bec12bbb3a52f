//! Ship and buoy 4-state EKFs [E, N, S, ψ] (Gill 2013, §2.2.2): constant speed and heading, no input,
//! scalar state updates from the quantised 13-bit broadcasts. The same type serves both; the
//! buoy differs only by its coefficients (Table 3) and by never hearing speed or heading. Speed
//! is signed and never clamped: the buoy filter uses it as a 1-D north/south drift (an
//! interpretation: docs/models.md#gill-buoy-drift).
//! Also the ship's port/starboard outrigger transponder geometry.

use crate::ekf::{Ekf, Gate, UpdateOutcome};
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{wrap_pi, Vec3};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

pub type SurfaceState = SVector<f64, 4>;

/// Which state component a broadcast carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StateKind {
    East,
    North,
    Speed,
    Heading,
}

impl StateKind {
    fn index(self) -> usize {
        match self {
            StateKind::East => 0,
            StateKind::North => 1,
            StateKind::Speed => 2,
            StateKind::Heading => 3,
        }
    }
}

/// Coefficients of a surface-vehicle filter (variances; Q per nominal step `step_s`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceParams {
    pub step_s: f64,
    /// Initial variances [E, N, S, ψ].
    pub p0: [f64; 4],
    /// Per-step process noise [E, N, S, ψ].
    pub q: [f64; 4],
    /// Broadcast measurement variances [E, N, S, ψ].
    pub r: [f64; 4],
}

impl SurfaceParams {
    /// Ship filter. Invented: docs/models.md#gill-coefficients (the thesis gives no ship numbers).
    pub fn ship() -> Self {
        let deg = std::f64::consts::PI / 180.0;
        SurfaceParams {
            step_s: 0.1,
            p0: [21.36663, 21.36663, 0.0025, 0.01],
            q: [0.535915, 0.535915, 1e-3, (0.5 * deg).powi(2)],
            r: Self::quantised_r(),
        }
    }

    /// Buoy filter: P^B and Q^B of Gill 2013, Table 3, R^B = R^S for E and N.
    pub fn buoy() -> Self {
        SurfaceParams {
            step_s: 0.1,
            p0: [21.36663, 21.36663, 0.00016215, 0.000001],
            q: [0.535915, 0.535915, 0.00016215, 0.000001],
            r: Self::quantised_r(),
        }
    }

    /// Quantisation (box²/12) plus DGPS or sensor noise. Reconstructed: docs/models.md#gill-coefficients.
    fn quantised_r() -> [f64; 4] {
        let deg = std::f64::consts::PI / 180.0;
        [
            1.6f64.powi(2) / 12.0 + 0.01,
            0.6f64.powi(2) / 12.0 + 0.01,
            0.015625f64.powi(2) / 12.0 + 4e-4,
            (1.40625 * deg).powi(2) / 12.0 + (0.5 * deg).powi(2),
        ]
    }
}

impl CheckFields for SurfaceParams {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.positive(&format!("{prefix}step_s"), self.step_s);
        for i in 0..4 {
            p.positive(&format!("{prefix}p0[{i}]"), self.p0[i]);
            p.non_negative(&format!("{prefix}q[{i}]"), self.q[i]);
            p.positive(&format!("{prefix}r[{i}]"), self.r[i]);
        }
    }
}

impl CheckFields for Outriggers {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.non_negative(&format!("{prefix}separation"), self.separation);
        p.finite(&format!("{prefix}along_offset"), self.along_offset);
        p.non_negative(&format!("{prefix}depth"), self.depth);
    }
}

/// A ship or buoy filter as run on board the AUV.
#[derive(Debug, Clone)]
pub struct SurfaceEkf {
    ekf: Ekf<4>,
    params: SurfaceParams,
}

impl SurfaceEkf {
    /// Starts at `t0` from (e, n), speed and math heading ψ.
    pub fn new(t0: f64, e: f64, n: f64, speed: f64, psi: f64, params: SurfaceParams) -> Self {
        let p0 = SMatrix::<f64, 4, 4>::from_diagonal(&SVector::from(params.p0));
        SurfaceEkf {
            ekf: Ekf::new(t0, SurfaceState::from([e, n, speed, psi]), p0, [false, false, false, true]),
            params,
        }
    }

    pub fn state(&self) -> &SurfaceState {
        self.ekf.x()
    }
    pub fn ekf(&self) -> &Ekf<4> {
        &self.ekf
    }
    pub fn position(&self) -> (f64, f64) {
        (self.ekf.x()[0], self.ekf.x()[1])
    }

    /// Mean position extrapolated to time `t` (constant speed and heading), without touching
    /// the filter.
    pub fn position_at(&self, t: f64) -> [f64; 2] {
        let x = self.ekf.x();
        let h = t - self.ekf.t();
        [x[0] + h * x[2] * x[3].cos(), x[1] + h * x[2] * x[3].sin()]
    }

    /// Predicts to time `t` in steps no longer than the nominal step, so the Jacobian and the
    /// per-step Q mean the same thing for any gap length (eq. 11).
    pub fn predict_to(&mut self, t: f64) {
        while t - self.ekf.t() > 1e-12 {
            let h = (t - self.ekf.t()).min(self.params.step_s);
            let x = *self.ekf.x();
            let (sin, cos) = x[3].sin_cos();
            let mut x_new = x;
            x_new[0] += h * x[2] * cos;
            x_new[1] += h * x[2] * sin;
            let mut f = SMatrix::<f64, 4, 4>::identity();
            f[(0, 2)] = h * cos;
            f[(0, 3)] = -h * x[2] * sin;
            f[(1, 2)] = h * sin;
            f[(1, 3)] = h * x[2] * cos;
            let q = SMatrix::<f64, 4, 4>::from_diagonal(&SVector::from(self.params.q)) * (h / self.params.step_s);
            let target = self.ekf.t() + h;
            if !self.ekf.predict(target, x_new, f, q) {
                return;
            }
        }
    }

    /// Scalar update of one broadcast state (heading in math convention, rad).
    pub fn update(&mut self, kind: StateKind, value: f64) -> UpdateOutcome {
        let i = kind.index();
        let mut h = SMatrix::<f64, 1, 4>::zeros();
        h[i] = 1.0;
        let mut y = value - self.ekf.x()[i];
        if kind == StateKind::Heading {
            y = wrap_pi(y);
        }
        self.ekf.update_scalar(y, h, self.params.r[i], &Gate::OFF)
    }
}

/// Which ship-mounted modem transmitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    Port,
    Starboard,
}

/// Outrigger geometry: transponders `separation` m apart across the ship, `along_offset` m ahead
/// of the position reference, at `depth` m. Defaults: 9.3 m, 0, 1.5 m (Gill 2013, §2.4.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Outriggers {
    pub separation: f64,
    pub along_offset: f64,
    pub depth: f64,
}

impl Default for Outriggers {
    fn default() -> Self {
        Outriggers { separation: 9.3, along_offset: 0.0, depth: 1.5 }
    }
}

impl Outriggers {
    /// Transponder position for a ship at (e, n) with math heading ψ. Port is to the left of
    /// the direction of travel.
    pub fn position(&self, side: Side, e: f64, n: f64, psi: f64) -> Vec3 {
        let (sin, cos) = psi.sin_cos();
        let half = match side {
            Side::Port => 0.5 * self.separation,
            Side::Starboard => -0.5 * self.separation,
        };
        Vec3::new(e + self.along_offset * cos - half * sin, n + self.along_offset * sin + half * cos, self.depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::is_positive_definite;

    #[test]
    fn port_is_left_of_travel() {
        let o = Outriggers::default();
        // Heading west (math π): port is to the south.
        let p = o.position(Side::Port, 0.0, 0.0, std::f64::consts::PI);
        let s = o.position(Side::Starboard, 0.0, 0.0, std::f64::consts::PI);
        assert!((p.y + 4.65).abs() < 1e-9 && (s.y - 4.65).abs() < 1e-9);
        assert!(((p - s).norm() - 9.3).abs() < 1e-9);
    }

    #[test]
    fn buoy_speed_may_go_negative() {
        // North-initialised buoy filter seeing southward drift.
        let mut b = SurfaceEkf::new(0.0, 0.0, 0.0, 0.0, std::f64::consts::FRAC_PI_2, SurfaceParams::buoy());
        for k in 1..=30 {
            let t = k as f64 * 10.0;
            b.predict_to(t);
            b.update(StateKind::North, -0.1 * t);
        }
        assert!(b.state()[2] < 0.0, "speed {}", b.state()[2]);
        assert!(is_positive_definite(b.ekf().p()));
    }

    #[test]
    fn long_gaps_grow_covariance_but_stay_finite() {
        let mut s = SurfaceEkf::new(0.0, 0.0, 0.0, 1.3, 0.0, SurfaceParams::ship());
        s.predict_to(600.0);
        assert!(s.state().iter().all(|v| v.is_finite()));
        assert!(is_positive_definite(s.ekf().p()));
        assert!(s.ekf().p()[(0, 0)] > 1000.0);
        assert!((s.state()[0] - 780.0).abs() < 1e-6);
    }
}
