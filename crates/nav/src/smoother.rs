//! Rauch–Tung–Striebel smoothers (Gill 2013, §2.4.3, after its reference 25;
//! docs/models.md#gill-post-processing): backward passes over the forward filter's
//! history. The EKF-RTS pass (default) uses the recorded linearisation,
//!   C_k = P⁺_k F_{k+1}ᵀ (P⁻_{k+1})⁻¹,
//!   x^s_k = x⁺_k + C_k (x^s_{k+1} ⊖ x⁻_{k+1}),
//!   P^s_k = P⁺_k + C_k (P^s_{k+1} − P⁻_{k+1}) C_kᵀ;
//! the unscented pass (Särkkä's URTS, the thesis's reference 25) instead pushes sigma points of
//! (x⁺_k, P⁺_k) through the nonlinear transition for the prediction and the cross-covariance.
//! Angle components are differenced and re-wrapped in both.

use crate::ekf::{state_difference, symmetrise, Step};
use coopnav_core::wrap_pi;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Which backward pass to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SmootherKind {
    /// EKF-RTS on the recorded Jacobians (Gill 2013, §2.4.3).
    #[default]
    Ekf,
    /// Unscented RTS (the variant of Gill 2013's reference 25) with 2N equally weighted sigma points at ±√N σ
    /// (α = 1, β = 0, κ = 0: no negative weights, so every covariance stays positive).
    Unscented,
}

#[derive(Debug, Error, PartialEq)]
pub enum SmoothError {
    #[error("the filter recorded no history (call record_history before filtering)")]
    NoHistory,
    #[error("step {0}: the predicted covariance is not invertible")]
    Singular(usize),
    #[error("step {0}: the filtered covariance is not positive definite (no sigma points)")]
    NotPositiveDefinite(usize),
}

/// One smoothed step.
#[derive(Debug, Clone, PartialEq)]
pub struct Smoothed<const N: usize> {
    pub t: f64,
    pub x: SVector<f64, N>,
    pub p: SMatrix<f64, N, N>,
}

/// Smooths a recorded history; the result has one entry per step, in time order.
pub fn rts<const N: usize>(history: &[Step<N>], angles: &[bool; N]) -> Result<Vec<Smoothed<N>>, SmoothError> {
    let last = history.last().ok_or(SmoothError::NoHistory)?;
    let mut out = vec![Smoothed { t: last.t, x: last.x_post, p: last.p_post }; history.len()];
    for k in (0..history.len() - 1).rev() {
        let (cur, next) = (&history[k], &history[k + 1]);
        let filtered = Smoothed { t: cur.t, x: cur.x_post, p: cur.p_post };
        out[k] = rts_step(&filtered, &next.f, &next.x_prior, &next.p_prior, &out[k + 1], angles)
            .ok_or(SmoothError::Singular(k + 1))?;
    }
    Ok(out)
}

/// One EKF-RTS backward step from the filtered estimate at step k, the next step's transition F
/// and prior (x⁻, P⁻), and the smoothed next step; None when P⁻ is not invertible.
pub fn rts_step<const N: usize>(
    filtered: &Smoothed<N>,
    f_next: &SMatrix<f64, N, N>,
    x_prior_next: &SVector<f64, N>,
    p_prior_next: &SMatrix<f64, N, N>,
    later: &Smoothed<N>,
    angles: &[bool; N],
) -> Option<Smoothed<N>> {
    let chol = p_prior_next.cholesky()?;
    // C = P⁺ Fᵀ (P⁻)⁻¹ = ((P⁻)⁻¹ F P⁺)ᵀ.
    let c = chol.solve(&(f_next * filtered.p)).transpose();
    Some(backward_step(filtered, later, x_prior_next, p_prior_next, &c, angles))
}

/// Unscented RTS over a recorded history. `transition(k, x)` is the mean map from step k to
/// step k + 1 (the one the forward filter linearised); Q comes from the history.
pub fn urts<const N: usize>(
    history: &[Step<N>],
    angles: &[bool; N],
    transition: impl Fn(usize, &SVector<f64, N>) -> SVector<f64, N>,
) -> Result<Vec<Smoothed<N>>, SmoothError> {
    let last = history.last().ok_or(SmoothError::NoHistory)?;
    let mut out = vec![Smoothed { t: last.t, x: last.x_post, p: last.p_post }; history.len()];
    for k in (0..history.len() - 1).rev() {
        let (cur, next) = (&history[k], &history[k + 1]);
        let filtered = Smoothed { t: cur.t, x: cur.x_post, p: cur.p_post };
        out[k] = urts_step(&filtered, &next.q, |x| transition(k, x), &out[k + 1], angles, k)?;
    }
    Ok(out)
}

/// One unscented backward step (step k) from the filtered estimate, the next step's process
/// noise Q and mean map, and the smoothed next step.
pub fn urts_step<const N: usize>(
    filtered: &Smoothed<N>,
    q_next: &SMatrix<f64, N, N>,
    transition: impl Fn(&SVector<f64, N>) -> SVector<f64, N>,
    later: &Smoothed<N>,
    angles: &[bool; N],
    k: usize,
) -> Result<Smoothed<N>, SmoothError> {
    let weight = 1.0 / (2 * N) as f64;
    let sigma = sigma_points(&filtered.x, &filtered.p, angles).ok_or(SmoothError::NotPositiveDefinite(k))?;
    let moved: Vec<SVector<f64, N>> = sigma.iter().map(&transition).collect();
    // Mean of the propagated points, averaged as offsets from the propagated mean state.
    let centre = transition(&filtered.x);
    let offset = moved.iter().map(|x| state_difference(x, &centre, angles)).sum::<SVector<f64, N>>() * weight;
    let x_prior = wrap(centre + offset, angles);
    let (mut p_prior, mut cross) = (*q_next, SMatrix::<f64, N, N>::zeros());
    for (before, after) in sigma.iter().zip(&moved) {
        let (a, b) = (state_difference(before, &filtered.x, angles), state_difference(after, &x_prior, angles));
        p_prior += b * b.transpose() * weight;
        cross += a * b.transpose() * weight;
    }
    let p_prior = symmetrise(p_prior);
    let chol = p_prior.cholesky().ok_or(SmoothError::Singular(k + 1))?;
    // G = D (P⁻)⁻¹ = ((P⁻)⁻¹ Dᵀ)ᵀ.
    let g = chol.solve(&cross.transpose()).transpose();
    Ok(backward_step(filtered, later, &x_prior, &p_prior, &g, angles))
}

/// The RTS correction shared by both passes, with gain `g`.
fn backward_step<const N: usize>(
    filtered: &Smoothed<N>,
    later: &Smoothed<N>,
    x_prior: &SVector<f64, N>,
    p_prior: &SMatrix<f64, N, N>,
    g: &SMatrix<f64, N, N>,
    angles: &[bool; N],
) -> Smoothed<N> {
    let x = wrap(filtered.x + g * state_difference(&later.x, x_prior, angles), angles);
    let p = symmetrise(filtered.p + g * (later.p - p_prior) * g.transpose());
    Smoothed { t: filtered.t, x, p }
}

/// Angle components re-wrapped to (-π, π].
pub fn wrap<const N: usize>(mut x: SVector<f64, N>, angles: &[bool; N]) -> SVector<f64, N> {
    for (i, is_angle) in angles.iter().enumerate() {
        if *is_angle {
            x[i] = wrap_pi(x[i]);
        }
    }
    x
}

/// x ± √N · (columns of the Cholesky factor of P); None if P is not positive definite.
fn sigma_points<const N: usize>(
    x: &SVector<f64, N>,
    p: &SMatrix<f64, N, N>,
    angles: &[bool; N],
) -> Option<Vec<SVector<f64, N>>> {
    let l = p.cholesky()?.l() * (N as f64).sqrt();
    Some(l.column_iter().flat_map(|c| [wrap(x + c, angles), wrap(x - c, angles)]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::{is_positive_definite, Ekf, Gate};
    use nalgebra::{Matrix2, Vector2};

    /// A 1-D constant-velocity random walk observed in position: the smoother must agree with
    /// the filter at the last step and shrink the variance everywhere else.
    #[test]
    fn smoother_reduces_variance_and_matches_filter_at_end() {
        let mut e = Ekf::new(0.0, Vector2::new(0.0, 1.0), Matrix2::identity(), [false, false]);
        e.record_history();
        let f = Matrix2::new(1.0, 1.0, 0.0, 1.0);
        let q = Matrix2::new(0.01, 0.0, 0.0, 0.01);
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        for k in 1..=20 {
            let x = f * e.x();
            e.predict(k as f64, x, f, q);
            let z = k as f64 + if k % 2 == 0 { 0.3 } else { -0.3 };
            e.update_scalar(z - e.x()[0], h, 0.25, &Gate::OFF);
        }
        let hist = e.history().unwrap();
        let s = rts(hist, e.angles()).unwrap();
        assert_eq!(s.len(), 21);
        assert_eq!(s[20].x, *e.x());
        for (sm, st) in s.iter().zip(hist) {
            assert!(sm.p[(0, 0)] <= st.p_post[(0, 0)] + 1e-12);
            assert!(is_positive_definite(&sm.p));
        }
        assert!(s[10].p[(0, 0)] < hist[10].p_post[(0, 0)] * 0.9);
    }

    /// For a linear transition the unscented transform is exact, so the unscented pass must
    /// reproduce the EKF-RTS pass (to round-off) on the same history.
    #[test]
    fn unscented_pass_equals_ekf_pass_on_a_linear_model() {
        let mut e = Ekf::new(0.0, Vector2::new(0.0, 1.0), Matrix2::new(2.0, 0.3, 0.3, 1.0), [false, false]);
        e.record_history();
        let f = Matrix2::new(1.0, 0.5, 0.0, 1.0);
        let q = Matrix2::new(0.02, 0.001, 0.001, 0.01);
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        for k in 1..=30 {
            let x = f * e.x();
            e.predict(k as f64 * 0.5, x, f, q);
            if k % 3 != 0 {
                e.update_scalar((k as f64 * 0.5 + 0.2 * (k as f64).sin()) - e.x()[0], h, 0.1, &Gate::OFF);
            }
        }
        let hist = e.history().unwrap();
        let ekf = rts(hist, e.angles()).unwrap();
        let unscented = urts(hist, e.angles(), |_, x| f * x).unwrap();
        for (a, b) in ekf.iter().zip(&unscented) {
            assert!((a.x - b.x).norm() < 1e-9 && (a.p - b.p).norm() < 1e-9, "{a:?} vs {b:?}");
        }
        // And it is not the trivial pass-through: smoothing moved the early estimates.
        assert!((unscented[5].x - hist[5].x_post).norm() > 1e-3);
    }

    /// Sigma points straddling ±π: the smoothed heading stays wrapped and near the truth.
    #[test]
    fn unscented_pass_wraps_angles() {
        let mut e = Ekf::new(0.0, Vector2::new(3.1, 0.0), Matrix2::new(0.05, 0.0, 0.0, 0.01), [true, false]);
        e.record_history();
        let f = Matrix2::identity();
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        for k in 1..=10 {
            e.predict(k as f64, *e.x(), f, Matrix2::new(1e-3, 0.0, 0.0, 1e-4));
            e.update_scalar(wrap_pi(-3.13 - e.x()[0]), h, 0.01, &Gate::OFF);
        }
        let s = urts(e.history().unwrap(), e.angles(), |_, x| *x).unwrap();
        for sm in &s {
            assert!(sm.x[0].abs() <= std::f64::consts::PI && wrap_pi(sm.x[0] + 3.13).abs() < 0.1, "{:?}", sm.x);
        }
    }

    #[test]
    fn empty_history_is_an_error() {
        let h: Vec<Step<2>> = vec![];
        assert_eq!(rts(&h, &[false, false]), Err(SmoothError::NoHistory));
        assert_eq!(urts(&h, &[false, false], |_, x| *x), Err(SmoothError::NoHistory));
    }
}
