//! EKF Rauch–Tung–Striebel smoother (digest §3.6): a backward pass over the forward filter's
//! history,
//!   C_k = P⁺_k F_{k+1}ᵀ (P⁻_{k+1})⁻¹,
//!   x^s_k = x⁺_k + C_k (x^s_{k+1} ⊖ x⁻_{k+1}),
//!   P^s_k = P⁺_k + C_k (P^s_{k+1} − P⁻_{k+1}) C_kᵀ,
//! with angle components differenced and re-wrapped.

use crate::ekf::{state_difference, symmetrise, Step};
use coopnav_core::wrap_pi;
use nalgebra::{SMatrix, SVector};
use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
pub enum SmoothError {
    #[error("the filter recorded no history (call record_history before filtering)")]
    NoHistory,
    #[error("step {0}: the predicted covariance is not invertible")]
    Singular(usize),
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
        let chol = next.p_prior.cholesky().ok_or(SmoothError::Singular(k + 1))?;
        // C = P⁺ Fᵀ (P⁻)⁻¹ = ((P⁻)⁻¹ F P⁺)ᵀ.
        let c = chol.solve(&(next.f * cur.p_post)).transpose();
        let dx = state_difference(&out[k + 1].x, &next.x_prior, angles);
        let mut x = cur.x_post + c * dx;
        for (i, is_angle) in angles.iter().enumerate() {
            if *is_angle {
                x[i] = wrap_pi(x[i]);
            }
        }
        let p = symmetrise(cur.p_post + c * (out[k + 1].p - next.p_prior) * c.transpose());
        out[k] = Smoothed { t: cur.t, x, p };
    }
    Ok(out)
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

    #[test]
    fn empty_history_is_an_error() {
        let h: Vec<Step<2>> = vec![];
        assert_eq!(rts(&h, &[false, false]), Err(SmoothError::NoHistory));
    }
}
