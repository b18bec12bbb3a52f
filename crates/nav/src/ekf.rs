//! Generic fixed-size extended Kalman filter (digest §3.1): the caller supplies the propagated
//! state, the Jacobians and the noise; this module owns the covariance algebra (Joseph-form
//! update, symmetrisation), angle-wrapped state components, innovation gating, and the optional
//! history of x⁻, P⁻, x⁺, P⁺, F that the RTS smoother needs.

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::wrap_pi;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Innovation gate. Both tests are optional; a measurement failing either is rejected.
/// Default: off (faithful to the thesis, which describes no outlier rejection — digest §10 A5).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gate {
    /// Reject when any |innovation component| exceeds this (measurement units).
    pub max_abs_residual: Option<f64>,
    /// Reject when the normalised innovation squared yᵀS⁻¹y exceeds this (χ² threshold).
    pub max_nis: Option<f64>,
}

impl Gate {
    pub const OFF: Gate = Gate { max_abs_residual: None, max_nis: None };
}

impl CheckFields for Gate {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let Some(v) = self.max_abs_residual {
            p.positive(&format!("{prefix}max_abs_residual"), v);
        }
        if let Some(v) = self.max_nis {
            p.positive(&format!("{prefix}max_nis"), v);
        }
    }
}

/// What happened to one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum UpdateOutcome {
    Applied {
        nis: f64,
    },
    /// Rejected by the gate; the state is unchanged.
    Gated {
        nis: f64,
    },
    /// The measurement or its geometry could not be used (non-finite numbers, singular
    /// innovation covariance, degenerate Jacobian); the state is unchanged.
    Unusable,
}

impl UpdateOutcome {
    pub fn applied(self) -> bool {
        matches!(self, UpdateOutcome::Applied { .. })
    }
}

/// One filter step as the RTS smoothers need it: the transition F and noise Q from the previous step,
/// the prior after prediction and the posterior after all updates at time `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Step<const N: usize> {
    pub t: f64,
    pub f: SMatrix<f64, N, N>,
    /// Process noise W Q Wᵀ added by this step's prediction (zero for the first step).
    pub q: SMatrix<f64, N, N>,
    pub x_prior: SVector<f64, N>,
    pub p_prior: SMatrix<f64, N, N>,
    pub x_post: SVector<f64, N>,
    pub p_post: SMatrix<f64, N, N>,
}

/// The filter state: mean, covariance, time, which components are angles, and an optional
/// history.
#[derive(Debug, Clone)]
pub struct Ekf<const N: usize> {
    x: SVector<f64, N>,
    p: SMatrix<f64, N, N>,
    t: f64,
    angles: [bool; N],
    history: Option<Vec<Step<N>>>,
    predicts: u64,
    updates: u64,
}

impl<const N: usize> Ekf<N> {
    /// A filter at time `t0` with mean `x0`, covariance `p0`; `angles[i]` marks component i as an
    /// angle in radians, kept wrapped to (-π, π].
    pub fn new(t0: f64, x0: SVector<f64, N>, p0: SMatrix<f64, N, N>, angles: [bool; N]) -> Self {
        let mut e = Ekf { x: x0, p: p0, t: t0, angles, history: None, predicts: 0, updates: 0 };
        e.wrap_state();
        e
    }

    /// Starts recording every step (for smoothing). The current state becomes the first step.
    pub fn record_history(&mut self) {
        self.history = Some(vec![Step {
            t: self.t,
            f: SMatrix::identity(),
            q: SMatrix::zeros(),
            x_prior: self.x,
            p_prior: self.p,
            x_post: self.x,
            p_post: self.p,
        }]);
    }

    pub fn x(&self) -> &SVector<f64, N> {
        &self.x
    }
    pub fn p(&self) -> &SMatrix<f64, N, N> {
        &self.p
    }
    pub fn t(&self) -> f64 {
        self.t
    }
    pub fn angles(&self) -> &[bool; N] {
        &self.angles
    }
    pub fn history(&self) -> Option<&[Step<N>]> {
        self.history.as_deref()
    }
    /// Number of predictions and of applied measurement updates so far.
    pub fn counts(&self) -> (u64, u64) {
        (self.predicts, self.updates)
    }

    /// Prediction to time `t`: `x_new` = f(x⁺), `f` = ∂f/∂x at x⁺, `q` = W Q Wᵀ for this step.
    /// A non-finite `x_new`, `f` or `q` leaves the filter unchanged and returns false.
    pub fn predict(&mut self, t: f64, x_new: SVector<f64, N>, f: SMatrix<f64, N, N>, q: SMatrix<f64, N, N>) -> bool {
        if !(t.is_finite() && all_finite(x_new.as_slice()) && all_finite(f.as_slice()) && all_finite(q.as_slice())) {
            return false;
        }
        self.x = x_new;
        self.wrap_state();
        self.p = symmetrise(f * self.p * f.transpose() + q);
        self.t = t;
        self.predicts += 1;
        if let Some(h) = self.history.as_mut() {
            h.push(Step { t, f, q, x_prior: self.x, p_prior: self.p, x_post: self.x, p_post: self.p });
        }
        true
    }

    /// Prediction to time `t` with a transition Jacobian F = I + G, G given by its non-zero
    /// entries (row, column, value), and a diagonal process noise: the same P⁻ = F P Fᵀ + Q as
    /// [`Self::predict`] (up to rounding), computed as two sparse row/column passes instead of
    /// two dense N×N products — the filter-rate predictions of a fleet are most of a run's time.
    pub fn predict_sparse(
        &mut self,
        t: f64,
        x_new: SVector<f64, N>,
        g: &[(usize, usize, f64)],
        q_diag: &SVector<f64, N>,
    ) -> bool {
        let g_ok = g.iter().all(|&(i, j, v)| i < N && j < N && v.is_finite());
        if !(t.is_finite() && g_ok && all_finite(x_new.as_slice()) && all_finite(q_diag.as_slice())) {
            return false;
        }
        propagate_covariance(&mut self.p, g, q_diag);
        self.x = x_new;
        self.wrap_state();
        self.t = t;
        self.predicts += 1;
        if let Some(h) = self.history.as_mut() {
            let mut f = SMatrix::<f64, N, N>::identity();
            g.iter().for_each(|&(i, j, v)| f[(i, j)] += v);
            let q = SMatrix::<f64, N, N>::from_diagonal(q_diag);
            h.push(Step { t, f, q, x_prior: self.x, p_prior: self.p, x_post: self.x, p_post: self.p });
        }
        true
    }

    /// Scalar update: `innovation` = z − h(x⁻) (already wrapped by the caller if it is an angle),
    /// `h` the Jacobian row, `r` the measurement variance. The Joseph form of [`Self::update`]
    /// with the gain a rank-one correction: (I − k h) P (I − k h)ᵀ + r k kᵀ is computed as
    /// B = P − k (P hᵀ)ᵀ, then B − (B hᵀ) kᵀ + r k kᵀ, O(N²) instead of dense N×N products
    /// (equal up to rounding). Products with h visit only its non-zero entries (a speed row has
    /// one, a compass row two; a zero term adds nothing to a sum), and the rank-one corrections
    /// run down the columns of the column-major storage: this runs twice per AUV per filter step.
    pub fn update_scalar(&mut self, innovation: f64, h: SMatrix<f64, 1, N>, r: f64, gate: &Gate) -> UpdateOutcome {
        if !(innovation.is_finite() && all_finite(h.as_slice()) && r.is_finite()) {
            return UpdateOutcome::Unusable;
        }
        let seen = NonZero::of(&h);
        // `p[j][i]` is entry (i, j) of the column-major storage.
        let p = &self.p.data.0;
        let pht = seen.times(|i, j| p[j][i], &h);
        let s = seen.columns().iter().map(|&j| h[j] * pht[j]).sum::<f64>() + r;
        if !(s > 0.0 && s.is_finite()) {
            return UpdateOutcome::Unusable;
        }
        let nis = innovation * innovation / s;
        let residual_ok = gate.max_abs_residual.map_or(true, |b| innovation.abs() <= b);
        let nis_ok = gate.max_nis.map_or(true, |b| nis <= b);
        if !(residual_ok && nis_ok) {
            return UpdateOutcome::Gated { nis };
        }
        let k = pht.map(|v| v / s);
        // B = P − k (P hᵀ)ᵀ, then P⁺ = B − (B hᵀ) kᵀ + r k kᵀ = B + c kᵀ with c = r k − B hᵀ.
        // B hᵀ needs only h's columns of B, so P⁺ is written in one pass, every entry rounded
        // as in the two-pass form, (p − kᵢ (P hᵀ)ⱼ) + cᵢ kⱼ, and each off-diagonal pair averaged
        // as [`symmetrise`] averages it.
        let b = |i: usize, j: usize| p[j][i] - k[i] * pht[j];
        let bht = seen.times(b, &h);
        let mut c = [0.0; N];
        for (i, v) in c.iter_mut().enumerate() {
            *v = r * k[i] - bht[i];
        }
        let entry = |i: usize, j: usize| b(i, j) + c[i] * k[j];
        let mut columns = [[0.0; N]; N];
        for j in 0..N {
            columns[j][j] = entry(j, j);
            for i in 0..j {
                let v = 0.5 * (entry(i, j) + entry(j, i));
                columns[j][i] = v;
                columns[i][j] = v;
            }
        }
        let p_new = SMatrix::<f64, N, N>::from_data(nalgebra::ArrayStorage(columns));
        let x_new = self.x + SVector::<f64, N>::from(k) * innovation;
        self.commit(x_new, p_new).map_or(UpdateOutcome::Unusable, |()| UpdateOutcome::Applied { nis })
    }

    /// Vector update of M measurements with innovation y, Jacobian H and noise covariance R, in
    /// Joseph form: P⁺ = (I − KH) P⁻ (I − KH)ᵀ + K R Kᵀ.
    pub fn update<const M: usize>(
        &mut self,
        y: SVector<f64, M>,
        h: SMatrix<f64, M, N>,
        r: SMatrix<f64, M, M>,
        gate: &Gate,
    ) -> UpdateOutcome {
        if !(all_finite(y.as_slice()) && all_finite(h.as_slice()) && all_finite(r.as_slice())) {
            return UpdateOutcome::Unusable;
        }
        let pht = self.p * h.transpose();
        let s = symmetrise(h * pht + r);
        let Some(chol) = s.cholesky() else { return UpdateOutcome::Unusable };
        let nis = (y.transpose() * chol.solve(&y))[(0, 0)];
        let residual_ok = gate.max_abs_residual.map_or(true, |b| y.iter().all(|v| v.abs() <= b));
        let nis_ok = gate.max_nis.map_or(true, |b| nis <= b);
        if !(residual_ok && nis_ok) {
            return UpdateOutcome::Gated { nis };
        }
        // K = P Hᵀ S⁻¹, computed as (S⁻¹ H P)ᵀ since S and P are symmetric.
        let k = chol.solve(&pht.transpose()).transpose();
        let i_kh = SMatrix::<f64, N, N>::identity() - k * h;
        let p_new = symmetrise(i_kh * self.p * i_kh.transpose() + k * r * k.transpose());
        let x_new = self.x + k * y;
        self.commit(x_new, p_new).map_or(UpdateOutcome::Unusable, |()| UpdateOutcome::Applied { nis })
    }

    /// Takes an update's posterior unless it is non-finite; records it in the history.
    fn commit(&mut self, x_new: SVector<f64, N>, p_new: SMatrix<f64, N, N>) -> Option<()> {
        if !(all_finite(x_new.as_slice()) && all_finite(p_new.as_slice())) {
            return None;
        }
        self.x = x_new;
        self.p = p_new;
        self.wrap_state();
        self.updates += 1;
        if let Some(last) = self.history.as_mut().and_then(|h| h.last_mut()) {
            last.x_post = self.x;
            last.p_post = self.p;
        }
        Some(())
    }

    fn wrap_state(&mut self) {
        for (i, is_angle) in self.angles.iter().enumerate() {
            if *is_angle {
                self.x[i] = wrap_angle(self.x[i]);
            }
        }
    }
}

/// Difference a − b of two states, with angle components wrapped to (-π, π].
pub fn state_difference<const N: usize>(
    a: &SVector<f64, N>,
    b: &SVector<f64, N>,
    angles: &[bool; N],
) -> SVector<f64, N> {
    let mut d = a - b;
    for (i, is_angle) in angles.iter().enumerate() {
        if *is_angle {
            d[i] = wrap_pi(d[i]);
        }
    }
    d
}

/// An angle wrapped to (-π, π]: as [`wrap_pi`], but one already inside is returned untouched
/// (wrap_pi's remainder would round it, and costs a division the filter pays every step).
pub fn wrap_angle(a: f64) -> f64 {
    if a > -std::f64::consts::PI && a <= std::f64::consts::PI {
        a
    } else {
        wrap_pi(a)
    }
}

/// The columns where a measurement row h is non-zero, in increasing order.
struct NonZero<const N: usize> {
    columns: [usize; N],
    len: usize,
}

impl<const N: usize> NonZero<N> {
    fn of(h: &SMatrix<f64, 1, N>) -> Self {
        let mut nz = NonZero { columns: [0; N], len: 0 };
        for j in (0..N).filter(|&j| h[j] != 0.0) {
            nz.columns[nz.len] = j;
            nz.len += 1;
        }
        nz
    }

    fn columns(&self) -> &[usize] {
        &self.columns[..self.len]
    }

    /// M hᵀ for M given entry by entry (`m(i, j)`), summed over h's non-zero entries in column
    /// order.
    fn times(&self, m: impl Fn(usize, usize) -> f64, h: &SMatrix<f64, 1, N>) -> [f64; N] {
        let mut out = [0.0; N];
        for (i, v) in out.iter_mut().enumerate() {
            *v = self.columns().iter().map(|&j| m(i, j) * h[j]).sum();
        }
        out
    }
}

/// [`symmetrise`] in place, mirroring the averaged upper triangle.
fn symmetrise_in_place<const N: usize>(m: &mut SMatrix<f64, N, N>) {
    // `columns[j][i]` is entry (i, j).
    let columns = &mut m.data.0;
    for j in 1..N {
        for i in 0..j {
            let v = 0.5 * (columns[j][i] + columns[i][j]);
            columns[j][i] = v;
            columns[i][j] = v;
        }
    }
}

/// (M + Mᵀ)/2: removes the round-off asymmetry that would otherwise accumulate.
pub fn symmetrise<const N: usize>(m: SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    (m + m.transpose()) * 0.5
}

/// True when the symmetric matrix has a Cholesky factor (is positive definite).
pub fn is_positive_definite<const N: usize>(m: &SMatrix<f64, N, N>) -> bool {
    all_finite(m.as_slice()) && m.cholesky().is_some()
}

/// Every value finite; without an early exit, so the check vectorises (it runs on every step).
#[inline]
fn all_finite(v: &[f64]) -> bool {
    v.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// P ← F P Fᵀ + diag(q) for F = I + G, G given by its non-zero entries (row, column, value),
/// symmetrised: O(N²) per entry instead of two dense products.
pub fn propagate_covariance<const N: usize>(
    p: &mut SMatrix<f64, N, N>,
    g: &[(usize, usize, f64)],
    q_diag: &SVector<f64, N>,
) {
    // A = F P = P + G P (rows of G read the old P), then P⁻ = A Fᵀ = A + A Gᵀ (columns);
    // `columns[c][r]` is entry (r, c).
    let old = p.data.0;
    let columns = &mut p.data.0;
    for &(i, j, v) in g {
        for (column, old_column) in columns.iter_mut().zip(&old) {
            column[i] += v * old_column[j];
        }
    }
    let a = *columns;
    for &(i, j, v) in g {
        for (x, &a_rj) in columns[i].iter_mut().zip(&a[j]) {
            *x += v * a_rj;
        }
    }
    for i in 0..N {
        p[(i, i)] += q_diag[i];
    }
    symmetrise_in_place(p);
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    fn filter() -> Ekf<2> {
        Ekf::new(0.0, Vector2::new(0.0, 0.0), Matrix2::identity() * 4.0, [false, true])
    }

    #[test]
    fn scalar_update_matches_closed_form() {
        let mut e = filter();
        let out = e.update_scalar(2.0, SMatrix::<f64, 1, 2>::new(1.0, 0.0), 4.0, &Gate::OFF);
        // K = 4/(4+4) = 0.5, x = 1, P = 2; NIS = 4/8.
        let UpdateOutcome::Applied { nis } = out else { panic!("{out:?}") };
        assert!((nis - 0.5).abs() < 1e-12);
        assert!((e.x()[0] - 1.0).abs() < 1e-12);
        assert!((e.p()[(0, 0)] - 2.0).abs() < 1e-12);
        assert!((e.p()[(1, 1)] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn gates_reject_and_leave_state_alone() {
        let mut e = filter();
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        let g = Gate { max_abs_residual: Some(1.0), max_nis: None };
        assert!(matches!(e.update_scalar(2.0, h, 4.0, &g), UpdateOutcome::Gated { .. }));
        let g = Gate { max_abs_residual: None, max_nis: Some(0.4) };
        assert!(matches!(e.update_scalar(2.0, h, 4.0, &g), UpdateOutcome::Gated { .. }));
        assert_eq!(e.x()[0], 0.0);
        assert_eq!(e.counts(), (0, 0));
    }

    #[test]
    fn angles_stay_wrapped_and_nan_is_refused() {
        let mut e = filter();
        let f = Matrix2::identity();
        assert!(e.predict(1.0, Vector2::new(0.0, 3.0 * std::f64::consts::PI), f, Matrix2::zeros()));
        assert!((e.x()[1] - std::f64::consts::PI).abs() < 1e-12);
        assert!(!e.predict(2.0, Vector2::new(f64::NAN, 0.0), f, Matrix2::zeros()));
        assert_eq!(e.t(), 1.0);
        let out = e.update_scalar(f64::NAN, SMatrix::<f64, 1, 2>::new(1.0, 0.0), 1.0, &Gate::OFF);
        assert_eq!(out, UpdateOutcome::Unusable);
        let out = e.update_scalar(1.0, SMatrix::<f64, 1, 2>::new(0.0, 0.0), 0.0, &Gate::OFF);
        assert_eq!(out, UpdateOutcome::Unusable, "singular S must not divide by zero");
    }

    #[test]
    fn history_records_prior_and_posterior() {
        let mut e = filter();
        e.record_history();
        e.predict(1.0, Vector2::new(1.0, 0.0), Matrix2::identity(), Matrix2::identity());
        e.update_scalar(1.0, SMatrix::<f64, 1, 2>::new(1.0, 0.0), 1.0, &Gate::OFF);
        let h = e.history().unwrap();
        assert_eq!(h.len(), 2);
        assert_eq!(h[1].x_prior[0], 1.0);
        assert!(h[1].x_post[0] > 1.0);
        assert!(h[1].p_post[(0, 0)] < h[1].p_prior[(0, 0)]);
    }

    #[test]
    fn fast_paths_equal_the_dense_algebra() {
        let p0 = SMatrix::<f64, 3, 3>::new(4.0, 0.5, -0.2, 0.5, 2.0, 0.3, -0.2, 0.3, 1.0);
        let (mut dense, mut fast) =
            (Ekf::new(0.0, SVector::zeros(), p0, [false; 3]), Ekf::new(0.0, SVector::zeros(), p0, [false; 3]));
        let g = [(0, 1, 0.1), (0, 2, -0.3), (1, 2, 0.05)];
        let mut f = SMatrix::<f64, 3, 3>::identity();
        g.iter().for_each(|&(i, j, v)| f[(i, j)] += v);
        let q = SVector::<f64, 3>::new(0.01, 0.02, 0.0);
        let x = SVector::<f64, 3>::new(1.0, 2.0, 3.0);
        assert!(dense.predict(1.0, x, f, SMatrix::from_diagonal(&q)));
        assert!(fast.predict_sparse(1.0, x, &g, &q));
        assert!((dense.p() - fast.p()).abs().max() < 1e-12, "{} vs {}", dense.p(), fast.p());
        let h = SMatrix::<f64, 1, 3>::new(0.6, 0.0, 0.8);
        let UpdateOutcome::Applied { nis: nis_dense } =
            dense.update(SVector::<f64, 1>::new(0.7), h, SMatrix::<f64, 1, 1>::new(0.5), &Gate::OFF)
        else {
            panic!()
        };
        let UpdateOutcome::Applied { nis } = fast.update_scalar(0.7, h, 0.5, &Gate::OFF) else { panic!() };
        assert!((nis - nis_dense).abs() < 1e-12);
        assert!((dense.p() - fast.p()).abs().max() < 1e-12 && (dense.x() - fast.x()).abs().max() < 1e-12);
        assert!(!fast.predict_sparse(2.0, x, &[(3, 0, 1.0)], &q), "an entry outside the matrix is refused");
    }

    #[test]
    fn joseph_update_keeps_covariance_positive_definite_with_tiny_noise() {
        let mut e = Ekf::new(0.0, Vector2::zeros(), Matrix2::new(1e6, 0.0, 0.0, 1e-6), [false, false]);
        for _ in 0..1000 {
            e.update_scalar(0.1, SMatrix::<f64, 1, 2>::new(1.0, 1.0), 1e-9, &Gate::OFF);
            assert!(is_positive_definite(e.p()));
        }
    }
}
