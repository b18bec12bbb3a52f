//! The true-error cost on a filter that estimates the water current (invented,
//! docs/models.md#current-states-cost): the survey AUVs' 7-state filters (Gill 2013, §2.2.1, with
//! two current states added) carry, horizontally, the position and the current east and north. A
//! range's line of sight h only measures position, but through the filter's position–current
//! covariance every ping along h also corrects the current estimate along h, so the geometry of
//! successive pings decides which components of the current the filter learns, and an unlearnt
//! component keeps pushing the position error at (ĉ − c)·t. The 2-state true-error cost
//! (`true_error`) cannot see that: its filter is position only, and a current is either none or
//! wholly unmodelled.
//!
//! Per AUV the state is x = [p_e, p_n, c_e, c_n]; the filter's covariance P (4 × 4), the true
//! error ε = x̂ − x's second moment S = E[εεᵀ] (4 × 4) and mean m (4). One level of τ seconds:
//! 1. Prediction. The filter's model is p ← p + b·c, c ← φ·c + w (a random walk: φ = 1, b = τ;
//!    Gauss–Markov of correlation time T: φ = e^(−τ/T), b = T(1 − φ)), so with F = [[I, bI],
//!    [0, φI]]: P ← F P Fᵀ + diag(q_f τ, q_f τ, q_c τ, q_c τ) (the cross term of the driven
//!    current, O(q_c τ²), left out). The truth's current c_w is constant (as the CNA's ADCP
//!    measures it), its position drifts by q_t per axis and second (`TruthSpec::drift_m2_s`):
//!    ε ← F ε + u + w_t, u = [(b − τ)·c_w, (φ − 1)·c_w] (zero for a random walk), so
//!    m ← F m + u and S ← F S Fᵀ + (F m) uᵀ + u (F m)ᵀ + u uᵀ + diag(q_t τ, q_t τ, 0, 0).
//! 2. Ping, h = [h_xy, 0, 0] the range's horizontal Jacobian (`estimator` step 2). The filter's
//!    gain K = P h / (hᵀP h + R_f(r) + σ_c²|h|²); ε⁺ = (I − K hᵀ) ε + K·n, n the true range error
//!    plus the CNA's broadcast error along h, E[n²] = R_t(r) + v·|h|² (v the CNA's variance,
//!    taken as fresh per ping: this model does not carry the CNA's correlation with the AUVs'
//!    errors that `true_error`'s C does). So S⁺ = S − K(Sh)ᵀ − (Sh)Kᵀ + (hᵀS h + E[n²])·K Kᵀ,
//!    m⁺ = m − K (hᵀm), P⁺ = P − K (P h)ᵀ.
//! 3. The ping arrives with probability p_s(r): the expected moments are the mixture,
//!    S_E = S + p_s·(S⁺ − S), m_E = m + p_s·(m⁺ − m), P_E = P + p_s·(P⁺ − P) (`estimator` step 3).
//! 4. The level's term is `estimator` steps 4 and 5 on S's position block; the cost-to-go
//!    steps 6 and 7 with the true drift, as `true_error` step 4.
//!
//! Bounds: each term is ≥ 0, so 0 is a lower bound below every node and the per-level floors are
//! 0: the search stays exact (branch-and-bound then cuts on the path cost alone), at the price of
//! fewer cuts than the 2-state models' bounds give.

use crate::cost_model::{Below, CostModel};
use crate::estimator::EkfCost;
use crate::true_error::TruthSpec;
use crate::PlanError;
use serde::{Deserialize, Serialize};

/// What the planner knows of the filters' current states and of the water.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurrentStates {
    /// The filters' initial current variance per axis, (m/s)².
    pub p0: f64,
    /// The filters' current noise density per axis, (m/s)²/s.
    pub q: f64,
    /// The filters' current correlation time T, s; None: a random walk.
    #[serde(default)]
    pub correlation_s: Option<f64>,
    /// The water current c_w east and north, m/s, as the CNA measures it (its ADCP); the filters
    /// start from a current estimate of zero, so their current error starts at −c_w.
    #[serde(default)]
    pub water: [f64; 2],
}

/// A symmetric 4 × 4 matrix, dense.
pub type Mat4 = [[f64; 4]; 4];

/// One AUV's state under the current-states model (module header).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurrentState {
    /// The filter's covariance P, [p_e, p_n, c_e, c_n] (m², m²/s, (m/s)²).
    pub p: Mat4,
    /// The true error's second moment S = E[εεᵀ].
    pub s: Mat4,
    /// The true error's mean m.
    pub m: [f64; 4],
}

impl CurrentState {
    /// At launch: the filter's position variance `position_p0` and current variance p0 per axis;
    /// the true position error's variance `launch_variance` per axis, the current error −c_w exactly.
    pub fn launch(spec: &CurrentStates, position_p0: [f64; 3], launch_variance: f64) -> Self {
        let mut p = [[0.0; 4]; 4];
        (p[0][0], p[0][1], p[1][0], p[1][1]) = (position_p0[0], position_p0[1], position_p0[1], position_p0[2]);
        (p[2][2], p[3][3]) = (spec.p0, spec.p0);
        let m = [0.0, 0.0, -spec.water[0], -spec.water[1]];
        let mut s = [[0.0; 4]; 4];
        (s[0][0], s[1][1]) = (launch_variance, launch_variance);
        for (i, row) in s.iter_mut().enumerate().skip(2) {
            for (j, v) in row.iter_mut().enumerate().skip(2) {
                *v = m[i] * m[j];
            }
        }
        CurrentState { p, s, m }
    }

    /// The position block of S as [S_ee, S_en, S_nn].
    pub fn position_moments(&self) -> [f64; 3] {
        [self.s[0][0], self.s[0][1], self.s[1][1]]
    }

    /// The filter's position covariance as [P_ee, P_en, P_nn].
    pub fn position_covariance(&self) -> [f64; 3] {
        [self.p[0][0], self.p[0][1], self.p[1][1]]
    }
}

/// The growth of one interval of `dt` seconds (step 1): filter and truth noise, F's b and φ, u.
#[derive(Debug, Clone, Copy)]
pub struct CurrentGrowth {
    /// q_f·dt and q_c·dt, the filter's position and current noise per axis.
    pub filter_position: f64,
    pub filter_current: f64,
    /// q_t·dt, the truth's position drift per axis.
    pub truth: f64,
    pub b: f64,
    pub phi: f64,
    pub u: [f64; 4],
}

impl CurrentGrowth {
    /// Over `dt` seconds, with the filter's position noise `q_f` (m²/s) and the truth's `q_t`.
    pub fn over(spec: &CurrentStates, dt: f64, q_f: f64, q_t: f64) -> Self {
        let dt = dt.max(0.0);
        let (b, phi) = match spec.correlation_s {
            Some(tc) if tc > 0.0 => {
                let phi = (-dt / tc).exp();
                (tc * (1.0 - phi), phi)
            }
            _ => (dt, 1.0),
        };
        let [ce, cn] = spec.water;
        let u = [(b - dt) * ce, (b - dt) * cn, (phi - 1.0) * ce, (phi - 1.0) * cn];
        CurrentGrowth { filter_position: q_f * dt, filter_current: spec.q * dt, truth: q_t * dt, b, phi, u }
    }
}

/// F M Fᵀ for F = [[I, bI], [0, φI]].
#[inline(always)]
fn propagate(m: &Mat4, b: f64, phi: f64) -> Mat4 {
    // Rows: r_i = Σ_j F_ij M_j.
    let mut fm = *m;
    for j in 0..4 {
        fm[0][j] = m[0][j] + b * m[2][j];
        fm[1][j] = m[1][j] + b * m[3][j];
        fm[2][j] = phi * m[2][j];
        fm[3][j] = phi * m[3][j];
    }
    let mut out = fm;
    for row in out.iter_mut() {
        let r = *row;
        row[0] = r[0] + b * r[2];
        row[1] = r[1] + b * r[3];
        row[2] = phi * r[2];
        row[3] = phi * r[3];
    }
    out
}

/// Step 1 alone.
#[inline(always)]
pub fn current_prediction(state: &CurrentState, g: &CurrentGrowth) -> CurrentState {
    let mut p = propagate(&state.p, g.b, g.phi);
    p[0][0] += g.filter_position;
    p[1][1] += g.filter_position;
    p[2][2] += g.filter_current;
    p[3][3] += g.filter_current;
    let m = state.m;
    let fm = [m[0] + g.b * m[2], m[1] + g.b * m[3], g.phi * m[2], g.phi * m[3]];
    let mut s = propagate(&state.s, g.b, g.phi);
    for (i, row) in s.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v += fm[i] * g.u[j] + g.u[i] * fm[j] + g.u[i] * g.u[j];
        }
    }
    s[0][0] += g.truth;
    s[1][1] += g.truth;
    CurrentState { p, s, m: [fm[0] + g.u[0], fm[1] + g.u[1], fm[2] + g.u[2], fm[3] + g.u[3]] }
}

/// The noise of step 2: the filter's range variance R_f(r) + σ_c²|h|², the true E[n²].
#[derive(Debug, Clone, Copy)]
pub struct CurrentPingNoise {
    pub filter: f64,
    pub truth: f64,
}

/// Steps 2 and 3: a ping from `cna` to the AUV at `auv` arriving with probability `p_s`, the
/// noise given by `noise(slant range, |h|²)`. No ping (the two at one point): unchanged.
#[inline(always)]
pub fn current_ping(
    state: &CurrentState,
    cna: [f64; 3],
    auv: [f64; 3],
    noise: impl Fn(f64, f64) -> CurrentPingNoise,
    success: impl Fn(f64) -> f64,
) -> CurrentState {
    let d = [auv[0] - cna[0], auv[1] - cna[1], auv[2] - cna[2]];
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if r2 <= 1e-12 {
        return *state;
    }
    let r = r2.sqrt();
    let (h0, h1) = (d[0] / r, d[1] / r);
    let n = noise(r, h0 * h0 + h1 * h1);
    let p_s = success(r);
    let CurrentState { p, s, m } = *state;
    let ph: [f64; 4] = std::array::from_fn(|i| p[i][0] * h0 + p[i][1] * h1);
    let sh: [f64; 4] = std::array::from_fn(|i| s[i][0] * h0 + s[i][1] * h1);
    let innovation = h0 * ph[0] + h1 * ph[1] + n.filter;
    let k: [f64; 4] = std::array::from_fn(|i| ph[i] / innovation);
    let hsh = h0 * sh[0] + h1 * sh[1];
    let w = hsh + n.truth;
    let hm = h0 * m[0] + h1 * m[1];
    let mut out = CurrentState { p, s, m };
    for i in 0..4 {
        for j in 0..4 {
            out.p[i][j] -= p_s * k[i] * ph[j];
            out.s[i][j] += p_s * (w * k[i] * k[j] - k[i] * sh[j] - sh[i] * k[j]);
        }
        out.m[i] -= p_s * k[i] * hm;
    }
    out
}

/// The current-states model of one decision: the estimator-aware model (filter noise, link,
/// bias, aggregate, cost-to-go), the truth's drift and noise, and the current states.
pub(crate) struct CurrentStatesCost {
    pub filter: EkfCost,
    pub truth: TruthSpec,
    pub growth: Vec<CurrentGrowth>,
    /// The CNA's own variance v, m² (step 2).
    pub cna_variance: f64,
}

impl CurrentStatesCost {
    pub fn new(filter: EkfCost, truth: TruthSpec, spec: CurrentStates, tau: f64, cna_variance: f64) -> Self {
        let growth = filter.q_tau.iter().map(|q| CurrentGrowth::over(&spec, tau, q / tau, truth.drift_m2_s)).collect();
        CurrentStatesCost { filter, truth, growth, cna_variance }
    }

    /// Checks the root states (finite).
    pub fn check(root: &[CurrentState]) -> Result<(), PlanError> {
        for (k, r) in root.iter().enumerate() {
            let finite = r.p.iter().chain(&r.s).flatten().chain(&r.m).all(|v| v.is_finite());
            if !finite || r.s[0][0] < 0.0 || r.s[1][1] < 0.0 {
                return Err(PlanError::Input(format!("AUV {k}: current-states moments {r:?} are not finite")));
            }
        }
        Ok(())
    }

    #[inline(always)]
    fn step(&self, k: usize, parent: &CurrentState, cna: [f64; 3], auv: [f64; 3]) -> CurrentState {
        let predicted = current_prediction(parent, &self.growth[k]);
        let (f, t, v) = (self.filter.spec.range_noise, self.truth.range_noise, self.cna_variance);
        let filter_v = self.filter.cna_variance;
        current_ping(
            &predicted,
            cna,
            auv,
            |r, hh| CurrentPingNoise { filter: f.variance(r) + filter_v * hh, truth: t.variance(r) + v * hh },
            |r| self.filter.success(k, r),
        )
    }
}

impl CostModel for CurrentStatesCost {
    type State = CurrentState;

    /// A no-op bound: nothing to compute.
    const BOUND_COST: f64 = 0.0;

    #[inline(always)]
    fn update(&self, k: usize, parent: &CurrentState, cna: [f64; 3], auv: [f64; 3]) -> (CurrentState, f64) {
        let next = self.step(k, parent, cna, auv);
        let term = self.filter.moments_term(&next.position_moments(), self.filter.bias_variance(cna, auv));
        (next, term)
    }

    fn terminal_levels(&self) -> f64 {
        self.filter.spec.terminal_levels
    }

    #[inline(always)]
    fn leaf_term(&self, k: usize, state: &CurrentState, cna: [f64; 3], auv: [f64; 3], term: f64) -> f64 {
        self.filter.leaf_term_with((k, self.growth[k].truth), &state.position_moments(), cna, auv, term)
    }

    #[inline(always)]
    fn combine(&self, acc: f64, term: f64) -> f64 {
        self.filter.combine(acc, term)
    }

    /// Every term is ≥ 0: nothing is added (module header).
    fn bound_rest(
        &self,
        _k: usize,
        _state: &CurrentState,
        _cna: [f64; 3],
        _auv: [f64; 3],
        _below: impl Iterator<Item = Below>,
        _out: &mut [f64],
    ) {
    }

    fn level_floors(&self, _root: &[CurrentState], depth: usize) -> Vec<f64> {
        vec![0.0; depth]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(water: [f64; 2]) -> CurrentStates {
        CurrentStates { p0: 0.09, q: 2.5e-5, correlation_s: None, water }
    }

    fn noise(_r: f64, _hh: f64) -> CurrentPingNoise {
        CurrentPingNoise { filter: 0.04, truth: 1.0 }
    }

    /// Pings whose line of sight stays east-west teach the filter the east current only: the
    /// north current's mean error (−c_w) stays, and the north position error grows by it; pings
    /// that turn through north as well take both off.
    #[test]
    fn only_a_line_of_sight_along_the_current_teaches_the_filter_that_current() {
        let s = spec([0.0, 0.1]);
        let g = CurrentGrowth::over(&s, 30.0, 0.05, 0.002);
        let start = CurrentState::launch(&s, [4.0, 0.0, 4.0], 1.0);
        let auv = [0.0, 0.0, 20.0];
        let (mut east, mut turning) = (start, start);
        for i in 0..60 {
            east = current_ping(&current_prediction(&east, &g), [300.0, 0.0, 0.0], auv, noise, |_| 1.0);
            let a = i as f64 * 0.7;
            let cna = [300.0 * a.cos(), 300.0 * a.sin(), 0.0];
            turning = current_ping(&current_prediction(&turning, &g), cna, auv, noise, |_| 1.0);
        }
        // The east line of sight: the north current error untouched, its north position error
        // far beyond the turning geometry's.
        assert!((east.m[3] + 0.1).abs() < 1e-9, "{:?}", east.m);
        assert!(east.s[1][1] > 100.0 * turning.s[1][1], "{} against {}", east.s[1][1], turning.s[1][1]);
        assert!(turning.m[3].abs() < 0.02 && turning.s[1][1] < 10.0, "{turning:?}");
    }

    /// With no current in the water and none in the filter's noise, the model is the 2-state
    /// true-error recursion's position part: one level of the two agree.
    #[test]
    fn without_current_states_it_is_the_position_only_true_error_step() {
        use crate::true_error::{true_error_step, Growth, PingNoise, TrueError, TrueState};
        use crate::RangeNoise;
        let s = CurrentStates { p0: 0.0, q: 0.0, correlation_s: None, water: [0.0; 2] };
        let g = CurrentGrowth::over(&s, 30.0, 0.5, 0.01);
        let mut start = CurrentState::launch(&s, [20.0, 3.0, 12.0], 2.0);
        start.s[0][1] = 0.5;
        start.s[1][0] = 0.5;
        let (cna, auv) = ([250.0, -120.0, 0.0], [0.0, 10.0, 20.0]);
        let filter = RangeNoise { sigma_m: 0.2, per_km_m: 0.0 };
        let truth = RangeNoise { sigma_m: 1.0, per_km_m: 0.0 };
        let four = current_ping(
            &current_prediction(&start, &g),
            cna,
            auv,
            |r, _| CurrentPingNoise { filter: filter.variance(r), truth: truth.variance(r) },
            |_| 0.7,
        );
        let two_start = TrueState {
            p: [20.0, 3.0, 12.0],
            truth: TrueError { s: [2.0, 0.5, 2.0], c: [0.0; 4], m: [0.0; 2] },
            v: 0.0,
        };
        let growth = Growth { filter: 15.0, truth: 0.3, cna: 0.0, shift: [0.0; 2] };
        let noise = PingNoise { filter, filter_cna_variance: 0.0, truth };
        let two = true_error_step(&two_start, growth, cna, auv, &noise, |_| 0.7);
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9 * (1.0 + y.abs()));
        assert!(close(four.position_moments(), two.truth.s), "{:?} {:?}", four.position_moments(), two.truth.s);
        assert!(close(four.position_covariance(), two.p), "{:?} {:?}", four.position_covariance(), two.p);
    }
}
