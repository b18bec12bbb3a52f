//! Generic fixed-size extended Kalman filter (Gill 2013, App. A, after Simon 2006): the caller supplies the propagated
//! state, the Jacobians and the noise; this module owns the covariance algebra (Joseph-form
//! update, symmetrisation), angle-wrapped state components, innovation gating, and the optional
//! history of x⁻, P⁻, x⁺, P⁺, F that the RTS smoother needs.
//!
//! The filter-rate path (sparse prediction, unit-row updates, what they call, and the AUV
//! filter's methods over them) is `#[inline(always)]`: a step is a few hundred operations on
//! small arrays that separate functions pass through memory (`cargo bench -p coopnav-nav` shows
//! the difference); inlining never changes a floating-point result. The AUV filter's step
//! (prediction, speed, compass) runs as one
//! ([`Ekf::predict_and_read`]), bit for bit its three calls.

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::wrap_pi;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Innovation gate. Both tests are optional; a measurement failing either is rejected.
/// Default: off (faithful to the thesis, which describes no outlier rejection: Gill 2013, §2.2.1).
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

    /// Whether a measurement with these innovation components and NIS passes both tests.
    #[inline]
    pub fn admits(&self, residuals: &[f64], nis: f64) -> bool {
        let residual_ok = self.max_abs_residual.map_or(true, |b| residuals.iter().all(|v| v.abs() <= b));
        residual_ok && self.max_nis.map_or(true, |b| nis <= b)
    }
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
        // Symmetric from the start (unchanged when `p0` is): every step keeps it so, which the
        // sparse prediction relies on.
        let mut e = Ekf { x: x0, p: symmetrise(p0), t: t0, angles, history: None, predicts: 0, updates: 0 };
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
    /// Every state and covariance entry finite: over the storage's slices, without an early exit,
    /// so the check vectorises (nalgebra's matrix iterators cost about ten times as much).
    #[inline]
    pub fn is_finite(&self) -> bool {
        all_finite(self.x.as_slice()) & all_finite(self.p.as_slice())
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

    /// Prediction to time `t` with a transition Jacobian F = I + G, G given by the non-zero
    /// entries of its rows, and a diagonal process noise: the same P⁻ = F P Fᵀ + Q as
    /// [`Self::predict`] (up to rounding), computed as two sparse row/column passes instead of
    /// two dense N×N products — the filter-rate predictions of a fleet are most of a run's time.
    #[inline(always)]
    pub fn predict_sparse<const R: usize, const K: usize>(
        &mut self,
        t: f64,
        x_new: SVector<f64, N>,
        g: &SparseRows<R, K>,
        q_diag: &SVector<f64, N>,
    ) -> bool {
        if !(t.is_finite() && rows_ok::<N, R, K>(g) && all_finite(x_new.as_slice()) && all_finite(q_diag.as_slice())) {
            return false;
        }
        propagate_covariance(&mut self.p, g, q_diag);
        self.x = x_new;
        self.wrap_state();
        self.t = t;
        self.predicts += 1;
        if let Some(h) = self.history.as_mut() {
            let mut f = SMatrix::<f64, N, N>::identity();
            for (i, entries) in g {
                entries.iter().for_each(|&(j, v)| f[(*i, j)] += v);
            }
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
        self.update_row(innovation, &Weighted { seen: NonZero::of(&h), h: &h }, r, gate)
    }

    /// [`Self::update_scalar`] for the Jacobian row h = Σ e_j over `columns` (distinct, in
    /// increasing order): a direct reading of one state (speed) or of a sum of states (compass:
    /// heading plus bias). Bit for bit the same result, with the row's shape known when compiled
    /// (the filter-rate updates are most of a fleet's filter time); columns out of range or out of
    /// order make the measurement unusable.
    #[inline(always)]
    pub fn update_units<const K: usize>(
        &mut self,
        innovation: f64,
        columns: [usize; K],
        r: f64,
        gate: &Gate,
    ) -> UpdateOutcome {
        if !(innovation.is_finite() && r.is_finite() && columns_in_order::<N, K>(&columns)) {
            return UpdateOutcome::Unusable;
        }
        self.update_row(innovation, &Units(columns), r, gate)
    }

    /// The scalar Joseph update of [`Self::update_scalar`] for a row given by its non-zero entries.
    #[inline(always)]
    fn update_row(&mut self, innovation: f64, h: &impl SparseRow<N>, r: f64, gate: &Gate) -> UpdateOutcome {
        let (mut x, mut p) = (self.x, self.p);
        let outcome = joseph_update(&mut x, &mut p, innovation, h, r, gate);
        if !outcome.applied() {
            return outcome;
        }
        if !(all_finite(p.as_slice()) && all_finite(x.as_slice())) {
            return UpdateOutcome::Unusable;
        }
        self.accept(x, p);
        outcome
    }

    /// [`Self::update_units`] for a reading of the sum of the states at its columns: the
    /// innovation is its value minus each of those states in turn, wrapped when the sum is an angle.
    #[inline(always)]
    pub fn update_reading<const K: usize>(&mut self, reading: &UnitReading<K>) -> UpdateOutcome {
        let innovation = reading.innovation(&self.x);
        self.update_units(innovation, reading.columns, reading.variance, &Gate::OFF)
    }

    /// [`Self::predict_sparse`], then [`Self::update_reading`] for `first` and then `second`: bit
    /// for bit the three calls, run as one step in place, the two updates in one pass over P, and
    /// checked once (a fleet's filters run this ten times a second per AUV: most of a run's time).
    ///
    /// Every entry that goes non-finite stays non-finite to the end of the step (each stage adds
    /// to the entries it reads, `wrap_angle` keeps a non-finite angle non-finite), so a finite
    /// result means every call would have succeeded as it did here; anything else (and a filter
    /// recording its history, or a prediction it would refuse) restores the state and runs the
    /// three calls.
    #[inline(always)]
    pub fn predict_and_read<const R: usize, const K: usize, const A: usize, const B: usize>(
        &mut self,
        t: f64,
        x_new: SVector<f64, N>,
        g: &SparseRows<R, K>,
        q_diag: &SVector<f64, N>,
        first: &UnitReading<A>,
        second: &UnitReading<B>,
    ) -> (bool, [UpdateOutcome; 2]) {
        // A non-finite mean, noise or reading would leave a non-finite entry at the end, which
        // the check there catches; only what it cannot see is checked first.
        let predictable = t.is_finite() && rows_ok::<N, R, K>(g);
        if !(predictable && self.history.is_none() && first.usable::<N>() && second.usable::<N>()) {
            return self.predict_then_read(t, x_new, g, q_diag, first, second);
        }
        // Worked in place; the state before is kept for a step that has to be run call by call.
        let before = (self.x, self.p);
        self.x = x_new;
        propagate_covariance(&mut self.p, g, q_diag);
        wrap_angles(&mut self.x, &self.angles);
        let outcomes = joseph_two_readings(&mut self.x, &mut self.p, &self.angles, first, second);
        // P is symmetric here (every stage writes each pair once), so its upper triangle is all of it.
        let finite = all_finite(self.x.as_slice()) & upper_triangle_finite(&self.p);
        let Some(outcomes) = outcomes.filter(|_| finite) else {
            (self.x, self.p) = before;
            return self.predict_then_read(t, x_new, g, q_diag, first, second);
        };
        self.t = t;
        self.predicts += 1;
        self.updates += 2;
        (true, outcomes)
    }

    /// The three calls [`Self::predict_and_read`] stands for, one after the other.
    fn predict_then_read<const R: usize, const K: usize, const A: usize, const B: usize>(
        &mut self,
        t: f64,
        x_new: SVector<f64, N>,
        g: &SparseRows<R, K>,
        q_diag: &SVector<f64, N>,
        first: &UnitReading<A>,
        second: &UnitReading<B>,
    ) -> (bool, [UpdateOutcome; 2]) {
        let predicted = self.predict_sparse(t, x_new, g, q_diag);
        (predicted, [self.update_reading(first), self.update_reading(second)])
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
        if !gate.admits(y.as_slice(), nis) {
            return UpdateOutcome::Gated { nis };
        }
        // K = P Hᵀ S⁻¹, computed as (S⁻¹ H P)ᵀ since S and P are symmetric.
        let k = chol.solve(&pht.transpose()).transpose();
        let i_kh = SMatrix::<f64, N, N>::identity() - k * h;
        let p_new = symmetrise(i_kh * self.p * i_kh.transpose() + k * r * k.transpose());
        let x_new = self.x + k * y;
        self.commit(x_new, p_new).map_or(UpdateOutcome::Unusable, |()| UpdateOutcome::Applied { nis })
    }

    /// The scalar update of [`Self::update_scalar`] with the gain's entries at the `considered`
    /// states set to zero: the Schmidt–Kalman ("consider") update, which leaves those states'
    /// mean and variance as they were and carries their correlation with the rest (Schmidt
    /// 1966). The covariance is the Joseph form P − k (P hᵀ)ᵀ − (P hᵀ) kᵀ + s k kᵀ,
    /// valid for any gain, so the result stays the covariance of the estimate's error.
    pub fn update_scalar_considering(
        &mut self,
        innovation: f64,
        h: SMatrix<f64, 1, N>,
        r: f64,
        gate: &Gate,
        considered: &[bool; N],
    ) -> UpdateOutcome {
        if !(innovation.is_finite() && all_finite(h.as_slice()) && r.is_finite()) {
            return UpdateOutcome::Unusable;
        }
        let pht = self.p * h.transpose();
        let s = (h * pht)[(0, 0)] + r;
        if !(s > 0.0 && s.is_finite()) {
            return UpdateOutcome::Unusable;
        }
        let nis = innovation * innovation / s;
        if !gate.admits(&[innovation], nis) {
            return UpdateOutcome::Gated { nis };
        }
        let k = SVector::<f64, N>::from_fn(|i, _| if considered[i] { 0.0 } else { pht[i] / s });
        let p_new = symmetrise(self.p - k * pht.transpose() - pht * k.transpose() + k * k.transpose() * s);
        let x_new = self.x + k * innovation;
        self.commit(x_new, p_new).map_or(UpdateOutcome::Unusable, |()| UpdateOutcome::Applied { nis })
    }

    /// Takes an update's posterior unless it is non-finite; records it in the history.
    fn commit(&mut self, x_new: SVector<f64, N>, p_new: SMatrix<f64, N, N>) -> Option<()> {
        if !(all_finite(x_new.as_slice()) && all_finite(p_new.as_slice())) {
            return None;
        }
        self.accept(x_new, p_new);
        Some(())
    }

    /// Takes a posterior already checked finite; records it in the history.
    #[inline(always)]
    fn accept(&mut self, x_new: SVector<f64, N>, p_new: SMatrix<f64, N, N>) {
        self.x = x_new;
        self.p = p_new;
        self.wrap_state();
        self.updates += 1;
        if let Some(last) = self.history.as_mut().and_then(|h| h.last_mut()) {
            last.x_post = self.x;
            last.p_post = self.p;
        }
    }

    #[inline(always)]
    fn wrap_state(&mut self) {
        wrap_angles(&mut self.x, &self.angles);
    }
}

/// The components of `x` that are angles wrapped to (-π, π].
#[inline(always)]
fn wrap_angles<const N: usize>(x: &mut SVector<f64, N>, angles: &[bool; N]) {
    for (i, is_angle) in angles.iter().enumerate() {
        if *is_angle {
            x[i] = wrap_angle(x[i]);
        }
    }
}

/// A scalar reading of the sum of the states at `columns` (distinct, in increasing order): a
/// speed log reads one state, a compass two (heading plus its bias).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitReading<const K: usize> {
    pub columns: [usize; K],
    pub value: f64,
    /// The reading's noise variance.
    pub variance: f64,
    /// The sum is an angle: its innovation is wrapped to (-π, π].
    pub angle: bool,
}

impl<const K: usize> UnitReading<K> {
    /// z − h x: the value minus each read state in turn, wrapped for an angle.
    #[inline(always)]
    fn innovation<const N: usize>(&self, x: &SVector<f64, N>) -> f64 {
        let y = self.columns.iter().fold(self.value, |y, &j| y - x[j]);
        if self.angle {
            wrap_angle(y)
        } else {
            y
        }
    }

    /// What [`Ekf::update_units`] requires of a reading before it looks at the state: finite
    /// numbers, columns in increasing order inside an `N`-state vector.
    #[inline(always)]
    fn usable<const N: usize>(&self) -> bool {
        columns_in_order::<N, K>(&self.columns) && self.value.is_finite() && self.variance.is_finite()
    }
}

/// The gain k = P hᵀ/s and w = s k/2 − P hᵀ of [`joseph_update`] from P hᵀ and s.
#[inline(always)]
fn gain<const N: usize>(pht: &[f64; N], s: f64) -> ([f64; N], [f64; N]) {
    let (half_s, inverse_s) = (0.5 * s, 1.0 / s);
    let (mut k, mut w) = ([0.0; N], [0.0; N]);
    for i in 0..N {
        k[i] = pht[i] * inverse_s;
        w[i] = half_s * k[i] - pht[i];
    }
    (k, w)
}

/// Sets every entry (i, j) of the symmetric matrix `columns` (column-major) to `entry(i, j, old
/// value)`, for an `entry` whose result at (j, i) is bitwise the same: computed once per pair, on
/// and above the diagonal, and copied below it.
#[inline(always)]
fn for_upper_triangle<const N: usize>(columns: &mut [[f64; N]; N], entry: impl Fn(usize, usize, f64) -> f64) {
    for j in 0..N {
        for i in 0..=j {
            let v = entry(i, j, columns[j][i]);
            columns[j][i] = v;
            columns[i][j] = v;
        }
    }
}

/// Entry (i, j) of k wᵀ + w kᵀ, the same two products summed in the same order as entry (j, i).
#[inline(always)]
fn rank_two<const N: usize>(k: &[f64; N], w: &[f64; N], i: usize, j: usize) -> f64 {
    k[i] * w[j] + w[i] * k[j]
}

/// [`joseph_update`] for `first`, then for `second`, bit for bit, in one pass over P: the second
/// gain needs only the columns of P⁺ it reads, computed entry by entry as the pass computes them.
/// None unless both are applied (the caller then runs them one at a time); `x` is wrapped by
/// `angles` after each, as [`Ekf`] wraps its state.
#[inline(always)]
fn joseph_two_readings<const N: usize, const A: usize, const B: usize>(
    x: &mut SVector<f64, N>,
    p: &mut SMatrix<f64, N, N>,
    angles: &[bool; N],
    first: &UnitReading<A>,
    second: &UnitReading<B>,
) -> Option<[UpdateOutcome; 2]> {
    let columns = &mut p.data.0;
    let (first_row, second_row) = (Units(first.columns), Units(second.columns));
    let y1 = first.innovation(x);
    let pht1: [f64; N] = first_row.times(|i, j| columns[j][i]);
    let s1 = first_row.dot(&pht1) + first.variance;
    if !(s1 > 0.0 && s1.is_finite()) {
        return None;
    }
    let (k1, w1) = gain(&pht1, s1);
    for (x_i, k_i) in x.iter_mut().zip(&k1) {
        *x_i += k_i * y1;
    }
    wrap_angles(x, angles);
    let y2 = second.innovation(x);
    let pht2: [f64; N] = second_row.times(|i, j| columns[j][i] + rank_two(&k1, &w1, i, j));
    let s2 = second_row.dot(&pht2) + second.variance;
    if !(s2 > 0.0 && s2.is_finite()) {
        return None;
    }
    let (k2, w2) = gain(&pht2, s2);
    for_upper_triangle(columns, |i, j, v| (v + rank_two(&k1, &w1, i, j)) + rank_two(&k2, &w2, i, j));
    for (x_i, k_i) in x.iter_mut().zip(&k2) {
        *x_i += k_i * y2;
    }
    wrap_angles(x, angles);
    Some([UpdateOutcome::Applied { nis: y1 * y1 / s1 }, UpdateOutcome::Applied { nis: y2 * y2 / s2 }])
}

/// Columns in increasing order, each inside an `N`-state vector.
#[inline(always)]
fn columns_in_order<const N: usize, const K: usize>(columns: &[usize; K]) -> bool {
    let mut ordered = true;
    for (n, &j) in columns.iter().enumerate() {
        ordered &= j < N && (n == 0 || columns[n - 1] < j);
    }
    ordered
}

/// The scalar Joseph update P⁺ = (I − k h) P (I − k h)ᵀ + r k kᵀ, x⁺ = x + k y of `x` and `p` in
/// place, for a row h given by its non-zero entries; `p` must be symmetric. Gated or unusable
/// (s = h P hᵀ + r not positive and finite): both left as they were.
///
/// With P hᵀ = p̄ and k = p̄/s, the Joseph form expands for any gain k to P − k p̄ᵀ − p̄ kᵀ + s k kᵀ
/// = P + k wᵀ + w kᵀ with w = s k/2 − p̄: s k − p̄ is the gain's rounding residual, kept, so P⁺ is
/// insensitive to first order to k's rounding as the Joseph form is (the plain P − k p̄ᵀ is not),
/// and k is p̄ times one reciprocal of s (a division per entry is measurably slower).
/// Each entry is pᵢⱼ + (kᵢ wⱼ + wᵢ kⱼ): its mirror adds the same two products in the other order,
/// and a floating-point sum does not depend on the order of two terms, so the entries on and above
/// the diagonal are computed and copied below it, and P⁺ is exactly symmetric with no averaging.
#[inline(always)]
fn joseph_update<const N: usize>(
    x: &mut SVector<f64, N>,
    p: &mut SMatrix<f64, N, N>,
    innovation: f64,
    h: &impl SparseRow<N>,
    r: f64,
    gate: &Gate,
) -> UpdateOutcome {
    // `columns[j][i]` is entry (i, j) of the column-major storage.
    let columns = &mut p.data.0;
    let pht = h.times(|i, j| columns[j][i]);
    let s = h.dot(&pht) + r;
    if !(s > 0.0 && s.is_finite()) {
        return UpdateOutcome::Unusable;
    }
    let nis = innovation * innovation / s;
    if !gate.admits(&[innovation], nis) {
        return UpdateOutcome::Gated { nis };
    }
    let (k, w) = gain(&pht, s);
    for_upper_triangle(columns, |i, j, v| v + rank_two(&k, &w, i, j));
    for (x_i, k_i) in x.iter_mut().zip(&k) {
        *x_i += k_i * innovation;
    }
    UpdateOutcome::Applied { nis }
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
#[inline(always)]
pub fn wrap_angle(a: f64) -> f64 {
    if a > -std::f64::consts::PI && a <= std::f64::consts::PI {
        a
    } else {
        wrap_pi(a)
    }
}

/// A scalar measurement's Jacobian row h by its non-zero entries, visited in column order (a zero
/// term adds nothing to a sum).
trait SparseRow<const N: usize> {
    /// M hᵀ for M given entry by entry (`m(i, j)`).
    fn times(&self, m: impl Fn(usize, usize) -> f64) -> [f64; N];
    /// h v.
    fn dot(&self, v: &[f64; N]) -> f64;
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
}

/// A general row: its non-zero columns and their values.
struct Weighted<'a, const N: usize> {
    seen: NonZero<N>,
    h: &'a SMatrix<f64, 1, N>,
}

impl<const N: usize> SparseRow<N> for Weighted<'_, N> {
    #[inline(always)]
    fn times(&self, m: impl Fn(usize, usize) -> f64) -> [f64; N] {
        let mut out = [0.0; N];
        for (i, v) in out.iter_mut().enumerate() {
            *v = sum_over(self.seen.columns(), |j| m(i, j) * self.h[j]);
        }
        out
    }

    #[inline(always)]
    fn dot(&self, v: &[f64; N]) -> f64 {
        sum_over(self.seen.columns(), |j| self.h[j] * v[j])
    }
}

/// A row of ones at `K` columns (in increasing order), zeros elsewhere: a product with a one is
/// the value itself, so the sums are those of [`Weighted`] bit for bit.
struct Units<const K: usize>([usize; K]);

impl<const N: usize, const K: usize> SparseRow<N> for Units<K> {
    #[inline(always)]
    fn times(&self, m: impl Fn(usize, usize) -> f64) -> [f64; N] {
        let mut out = [0.0; N];
        for (i, v) in out.iter_mut().enumerate() {
            *v = sum_over(&self.0, |j| m(i, j));
        }
        out
    }

    #[inline(always)]
    fn dot(&self, v: &[f64; N]) -> f64 {
        sum_over(&self.0, |j| v[j])
    }
}

/// Σ `term(j)` over `columns` in order, from 0 (a plain loop: an iterator's `sum` is not always
/// inlined, and this runs for every entry of P hᵀ).
#[inline(always)]
fn sum_over(columns: &[usize], term: impl Fn(usize) -> f64) -> f64 {
    let mut sum = 0.0;
    for &j in columns {
        sum += term(j);
    }
    sum
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
#[inline(always)]
fn all_finite(v: &[f64]) -> bool {
    let mut ok = true;
    for x in v {
        ok &= x.is_finite();
    }
    ok
}

/// Every entry on and above the diagonal finite.
#[inline(always)]
fn upper_triangle_finite<const N: usize>(p: &SMatrix<f64, N, N>) -> bool {
    let mut ok = true;
    for (j, column) in p.data.0.iter().enumerate() {
        ok &= all_finite(&column[..=j]);
    }
    ok
}

/// The non-zero entries of a sparse G, grouped by row: `R` rows, each (row, its `K` entries
/// (column, value) in order). F = I + G is a transition Jacobian that differs from the identity
/// in a few rows (the AUV filter's position rows).
pub type SparseRows<const R: usize, const K: usize> = [(usize, [(usize, f64); K]); R];

/// G's rows distinct and inside the matrix, its values finite (plain loops: this runs every
/// filter step).
#[inline(always)]
fn rows_ok<const N: usize, const R: usize, const K: usize>(g: &SparseRows<R, K>) -> bool {
    let mut ok = true;
    for (r, (i, entries)) in g.iter().enumerate() {
        ok &= *i < N;
        for (other, _) in &g[..r] {
            ok &= other != i;
        }
        for &(j, v) in entries {
            ok &= j < N && v.is_finite();
        }
    }
    ok
}

/// P ← F P Fᵀ + diag(q) for F = I + G, G given by its rows' non-zero entries, symmetrised:
/// O(N·R·K) instead of two dense products; `p` must be symmetric (see [`Ekf::new`]).
///
/// A = F P = P + G P changes only G's rows, and P⁻ = A Fᵀ = A + A Gᵀ only the columns of the same
/// indices. Bit for bit the dense two-pass form (rows of G in pass one, its columns in pass two,
/// each entry summed in its row's order, every pair averaged), with P's symmetry doing half the
/// work: A's row i is P's column i plus v times column j for each entry (j, v), the same
/// numbers as the rows; an entry of P⁻ with one index among G's rows, i, is A(i, c) = A(c, i)
/// summed in the same order on both sides of the diagonal, so only the block of pairs where both
/// indices are G's rows is computed twice and averaged (this runs once per AUV per filter step).
#[inline(always)]
pub fn propagate_covariance<const N: usize, const R: usize, const K: usize>(
    p: &mut SMatrix<f64, N, N>,
    g: &SparseRows<R, K>,
    q_diag: &SVector<f64, N>,
) {
    // `columns[c][r]` is entry (r, c).
    let columns = &mut p.data.0;
    let mut a_rows = [[0.0; N]; R];
    for ((i, entries), a) in g.iter().zip(a_rows.iter_mut()) {
        *a = columns[*i];
        for &(j, v) in entries {
            for (a_c, p_jc) in a.iter_mut().zip(&columns[j]) {
                *a_c += v * p_jc;
            }
        }
    }
    // P⁻(i_r, i_s) = A(i_r, i_s) + Σ v A(i_r, l) over G's row s: pass two's column i_s at row i_r.
    let mut block = [[0.0; R]; R];
    for (r, a) in a_rows.iter().enumerate() {
        for (s, (i_s, entries)) in g.iter().enumerate() {
            block[r][s] = entries.iter().fold(a[*i_s], |sum, &(l, v)| sum + v * a[l]);
        }
        block[r][r] += q_diag[g[r].0];
    }
    for (c, column) in columns.iter_mut().enumerate() {
        column[c] += q_diag[c];
    }
    for ((i, _), a) in g.iter().zip(&a_rows) {
        for (c, &a_c) in a.iter().enumerate() {
            columns[c][*i] = a_c;
        }
        columns[*i] = *a;
    }
    for (r, (i_r, _)) in g.iter().enumerate() {
        for (s, (i_s, _)) in g.iter().enumerate() {
            columns[*i_s][*i_r] = 0.5 * (block[r][s] + block[s][r]);
        }
    }
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
        let g = [(0, [(1, 0.1), (2, -0.3)]), (1, [(2, 0.05), (0, 0.2)])];
        let mut f = SMatrix::<f64, 3, 3>::identity();
        g.iter().for_each(|(i, entries)| entries.iter().for_each(|&(j, v)| f[(*i, j)] += v));
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
        assert!(!fast.predict_sparse(2.0, x, &[(3, [(0, 1.0)])], &q), "an entry outside the matrix is refused");
        assert!(!fast.predict_sparse(2.0, x, &[(0, [(1, 1.0)]), (0, [(2, 1.0)])], &q), "a row given twice is refused");
    }

    /// The dense two-pass form of [`propagate_covariance`] with G's entries flat, in the order
    /// each row lists them: A = P + G P (rows, from the old P), P⁻ = A + A Gᵀ (columns, from A),
    /// + Q, every pair averaged.
    fn two_pass(p: &SMatrix<f64, 7, 7>, g: &SparseRows<2, 3>, q: &SVector<f64, 7>) -> SMatrix<f64, 7, 7> {
        let flat: Vec<(usize, usize, f64)> =
            g.iter().flat_map(|(i, entries)| entries.iter().map(move |&(j, v)| (*i, j, v))).collect();
        let mut a = *p;
        for &(i, j, v) in &flat {
            for c in 0..7 {
                a[(i, c)] += v * p[(j, c)];
            }
        }
        let mut out = a;
        for &(i, j, v) in &flat {
            for r in 0..7 {
                out[(r, i)] += v * a[(r, j)];
            }
        }
        for i in 0..7 {
            out[(i, i)] += q[i];
        }
        for j in 1..7 {
            for i in 0..j {
                let v = 0.5 * (out[(i, j)] + out[(j, i)]);
                (out[(i, j)], out[(j, i)]) = (v, v);
            }
        }
        out
    }

    /// Uniform numbers in [−0.5, 0.5) from a xorshift generator seeded with `seed`.
    fn uniform_source(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    #[test]
    fn sparse_prediction_is_the_two_pass_form_bit_for_bit() {
        let mut uniform = uniform_source(0x2545_f491_4f6c_dd1d);
        for case in 0..200 {
            let m = SMatrix::<f64, 7, 7>::from_fn(|_, _| uniform());
            let p = m * m.transpose() + SMatrix::identity() * 0.1;
            let q = SVector::<f64, 7>::from_fn(|_, _| uniform().abs() * 1e-3);
            // The AUV filter's shape, rows 0 and 1 reading columns 2, 3 and a current state; and
            // rows reading themselves (the 5-state filter's entries there) or each other: columns
            // the second pass rewrites while it reads them.
            let (c0, c1) = [(5, 6), (0, 1), (1, 0)][case % 3];
            let g = [
                (0, [(2, uniform()), (3, uniform()), (c0, uniform())]),
                (1, [(2, uniform()), (3, uniform()), (c1, uniform())]),
            ];
            let mut fast = p;
            propagate_covariance(&mut fast, &g, &q);
            let reference = two_pass(&p, &g, &q);
            let same = fast.iter().zip(reference.iter()).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "case {case}: {fast} vs {reference}");
        }
    }

    #[test]
    fn unit_rows_update_as_the_general_row_bit_for_bit() {
        let m = SMatrix::<f64, 4, 4>::from_fn(|i, j| ((i * 4 + j) as f64 * 0.37).sin());
        let p0 = m * m.transpose() + SMatrix::identity() * 0.05;
        let x0 = SVector::<f64, 4>::new(1.0, -2.0, 0.5, 3.0);
        let (mut general, mut units) = (Ekf::new(0.0, x0, p0, [false; 4]), Ekf::new(0.0, x0, p0, [false; 4]));
        for step in 0..50 {
            let y = (step as f64 * 0.7).cos();
            let mut h = SMatrix::<f64, 1, 4>::zeros();
            let out = if step % 2 == 0 {
                h[2] = 1.0;
                (general.update_scalar(y, h, 0.3, &Gate::OFF), units.update_units(y, [2], 0.3, &Gate::OFF))
            } else {
                (h[1], h[3]) = (1.0, 1.0);
                (general.update_scalar(y, h, 0.02, &Gate::OFF), units.update_units(y, [1, 3], 0.02, &Gate::OFF))
            };
            assert_eq!(out.0, out.1);
            let bits = |e: &Ekf<4>| e.p().iter().chain(e.x().iter()).map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&general), bits(&units), "step {step}");
        }
        assert_eq!(units.update_units(1.0, [3, 1], 0.1, &Gate::OFF), UpdateOutcome::Unusable, "out of order");
        assert_eq!(units.update_units(1.0, [4], 0.1, &Gate::OFF), UpdateOutcome::Unusable, "outside the state");
    }

    /// The scalar Joseph update as written in the textbook, with dense matrices: k = P hᵀ/s,
    /// s = h P hᵀ + r, P⁺ = (I − k h) P (I − k h)ᵀ + r k kᵀ, x⁺ = x + k y.
    fn dense_joseph(
        p: &SMatrix<f64, 7, 7>,
        x: &SVector<f64, 7>,
        h: &SMatrix<f64, 1, 7>,
        r: f64,
        y: f64,
    ) -> (SMatrix<f64, 7, 7>, SVector<f64, 7>) {
        let s = (h * p * h.transpose())[(0, 0)] + r;
        let k = p * h.transpose() / s;
        let a = SMatrix::<f64, 7, 7>::identity() - k * h;
        (a * p * a.transpose() + k * k.transpose() * r, x + k * y)
    }

    #[test]
    fn scalar_updates_are_the_dense_joseph_form_exactly_symmetric_and_positive_definite() {
        let mut uniform = uniform_source(0x853c_49e6_748f_ea9b);
        for case in 0..300 {
            let m = SMatrix::<f64, 7, 7>::from_fn(|_, _| uniform());
            let p = m * m.transpose() + SMatrix::identity() * 0.1;
            let x = SVector::<f64, 7>::from_fn(|_, _| uniform() * 100.0);
            let y = uniform() * 10.0;
            // A general row (a range's: two position entries), then the unit rows of the AUV
            // filter's speed and compass readings; r from 5 % to 105 % of h P hᵀ.
            let mut h = SMatrix::<f64, 1, 7>::zeros();
            match case % 3 {
                0 => (h[0], h[1]) = (uniform(), uniform()),
                1 => h[2] = 1.0,
                _ => (h[3], h[4]) = (1.0, 1.0),
            }
            let r = (h * p * h.transpose())[(0, 0)] * (0.55 + uniform());
            let mut filter = Ekf::new(0.0, x, p, [false; 7]);
            let out = match case % 3 {
                0 => filter.update_scalar(y, h, r, &Gate::OFF),
                1 => filter.update_units(y, [2], r, &Gate::OFF),
                _ => filter.update_units(y, [3, 4], r, &Gate::OFF),
            };
            assert!(out.applied(), "case {case}: {out:?}");
            let (p_ref, x_ref) = dense_joseph(&p, &x, &h, r, y);
            let p_error = (filter.p() - p_ref).abs().max() / p_ref.abs().max();
            let x_error = (filter.x() - x_ref).abs().max() / x_ref.abs().max();
            assert!(p_error <= 1e-12 && x_error <= 1e-12, "case {case}: relative error P {p_error:e}, x {x_error:e}");
            let p_new = filter.p();
            let symmetric = (0..7).all(|i| (0..7).all(|j| p_new[(i, j)].to_bits() == p_new[(j, i)].to_bits()));
            assert!(symmetric, "case {case}: {p_new}");
            assert!(is_positive_definite(p_new), "case {case}: {p_new}");
        }
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
