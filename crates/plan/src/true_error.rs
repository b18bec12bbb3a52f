//! The true-error cost (invented, docs/models.md#true-error-cost): the planner scores the survey AUVs' expected TRUE
//! horizontal navigation error under their own filters' gains, not the filters' covariance. The
//! filters' process noise far exceeds the true dead-reckoning drift and their range noise leaves
//! out the truth's outliers and the CNA's own navigation error, so the covariance the estimator-aware
//! cost minimises is not the error it stands for (the filters' NEES is well above 1).
//!
//! Derivation, per AUV and look-ahead level of τ seconds: a suboptimal-filter error recursion
//! (the filter's gain applied to the true error; Gill 2013, §2.2.1 for the filter, the rest an
//! invention). Horizontal errors only; ε = x̂ − x the AUV's estimate error, e_c = the CNA's
//! broadcast position minus its true one. The state is P (the filter's covariance, as
//! `estimator` steps 1–3 model it), S = E[εεᵀ], C = E[ε e_cᵀ] and E[e_c e_cᵀ] = v·I.
//! 1. Prediction: P̃ = P + q_f·τ·I (the filter's process noise), S̃ = S + q_t·τ·I (the TRUE drift
//!    per axis, [`TruthSpec::drift_m2_s`]), C unchanged (the AUV's drift is independent of the
//!    CNA's), ṽ = v + D·τ (the CNA's own navigation diffusion, [`TruthSpec::cna_diffusion_m2_s`]):
//!    the CNA's error is a shared, persistent random walk, not fresh noise per ping.
//!    An unmodelled water current c (`EstimatorSpec::unmodelled_current`, as the CNA measures it)
//!    moves the AUV by cτ per level while its filter predicts no such
//!    motion: ε gains the deterministic d = −cτ. With m = E[ε] carried beside S (which holds the
//!    mean: S = Cov ε + m mᵀ), S̃ gains m dᵀ + d mᵀ + d dᵀ and m̃ = m + d (exact).
//! 2. A ping from the CNA, h its horizontal range Jacobian (`estimator` step 2). The filter's gain
//!    is K = P̃h/(hᵀP̃h + R_f(r) + σ_c²|h|²), its own model. The range is measured from the true
//!    CNA and predicted from the broadcast one, so the innovation is −hᵀε + hᵀe_c + n with n the
//!    true range error, and ε⁺ = (I − Khᵀ)ε + Khᵀe_c + K·n. With A = I − Khᵀ:
//!    S⁺ = A S̃ Aᵀ + A C h Kᵀ + K hᵀCᵀAᵀ + (ṽ|h|² + R_t(r))·KKᵀ
//!       = S̃ + K(g − S̃h)ᵀ + (g − S̃h)Kᵀ + (hᵀS̃h + ṽ|h|² + R_t(r))·KKᵀ, g = Ch − K·(hᵀCh);
//!    C⁺ = A C + ṽ·Khᵀ = C + K·(ṽh − Cᵀh)ᵀ.
//!    R_t(r) = σ_t² + (k_t·r/1000)² ([`TruthSpec::range_noise`]): the true range error's second
//!    moment (Gill's outlier mixture, Gill 2013, §2.4.1: 5 % of ranges 5–10 m long, 10 % dropped,
//!    so 5.6 % of those received; E[n²] ≈ 3.2 m², against the filter's 0.15 m). The update is
//!    linear in the errors, so second moments carry
//!    over exactly whatever their distribution.
//! 3. The ping arrives with probability p_s(r): S_E = (1 − p_s)·S̃ + p_s·S⁺, C_E likewise (the
//!    second moments of the mixture), P as `estimator` step 3. The mean: ε⁺'s is A·m̃ (e_c and n
//!    have none), so m_E = m̃ − p_s·K·(hᵀm̃).
//! 4. The level's term is `estimator` steps 4 and 5 on S_E (the range bias β(r)²/2·I added, then
//!    the aggregate); the cost-to-go is steps 6 and 7 with the true drift q_t for the growth
//!    (the current's mean is not grown beyond the horizon).
//!
//!
//! Lower bound below a node. The recursion is the exact second
//! moment of a linear estimator with deterministic gains (K follows the filter's expected P, not
//! the pings that arrived) whose pings arrive independently: S = E over the arrivals of
//! E[εεᵀ | arrivals], and given the arrivals ε is the error of a linear unbiased estimator of the
//! AUV's position from its node estimate (error with the node's moments), its dead reckoning and
//! the ranges. Two estimators with more data bound it (Gauss–Markov: no linear unbiased estimator
//! beats the best one on the same data, and more data never hurts the best one):
//! - F1, the CNA's error known (`CovFloor` on Σ): the ranges then measure the AUV with the true
//!   noise R_t alone; the node's error given e_c has Σ = S − mmᵀ − CCᵀ/v (the mean is known, and
//!   the regression on e_c removes CCᵀ/v); the best estimator is the Kalman filter on drift q_t·τ
//!   with information |h|²/R_t(r) per ping that arrives. Its information J is concave and
//!   non-decreasing through a prediction (J ↦ (J⁻¹ + q_tτ·I)⁻¹, a parallel sum) and E[J⁻¹] ⪰
//!   E[J]⁻¹ (the inverse is convex), so by Jensen, level by level, E over the arrivals is ⪰ the
//!   filter fed the expected information p_s|h|²/R_t ≤ p̄(r_min)/R_t(r_min) along its line of
//!   sight: `estimator`'s two chains with that information and no lost share.
//! - F2, the relative position u = x_a + e_c (what the ranges see) known exactly at every level:
//!   the AUV's position is then u − e_c, so its error is the error in e_c given the node's
//!   z = ε − e_c (covariance F = v·I − G·C_z⁻¹·Gᵀ, G = Cᵀ − v·I, C_z = S − mmᵀ − C − Cᵀ + v·I)
//!   and, each level, the sum of the AUV's drift and the CNA's diffusion (u's growth): the CNA's
//!   share of it stays unknown, F grows by w = q_tτ·Dτ/(q_tτ + Dτ) per axis and level whatever
//!   the pings. This is the part repeated pings hand over (S → v·I, the tests below).
//! Each level takes the larger, then `estimator` steps 4 to 7 as its bound does (the bias at the
//! shortest range, the leaf's reach growth at the true drift). Both need the moments to be a
//! joint covariance (Σ ⪰ 0); an AUV whose are not (an input no recursion produces) is bounded by
//! 0, and F2 is left out where C_z is near singular (its inverse would be rounding).
//! It is loose where the filter's own gain is far from the best one: the filter trusts its ranges
//! (R_f ≪ R_t), so each ping hands over nearly the whole range error, and only the newest ping's
//! share of that is counted. It cuts nodes when the CNA's own error is correlated with the AUVs'
//! (an AUV CNA's settled moments) and hardly any for an ASC (C = 0).

use crate::cost_model::{Below, CostModel};
use crate::estimator::{eigenvalues, CovFloor, EigenFloor, EkfCost, Ping, RangeNoise};
use crate::PlanError;
use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// What the truth model needs beyond the filter's own settings (the estimator cost's `truth = {...}`).
/// Every default is invented (docs/models.md#true-error-cost), chosen on tuning runs apart from
/// the evaluation's seeds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruthSpec {
    /// q_t of step 1: the AUVs' true dead-reckoning drift per axis, m²/s (≥ 0).
    pub drift_m2_s: f64,
    /// R_t of step 2: the true range error's root mean square and its growth per km.
    pub range_noise: RangeNoise,
    /// D of step 1: the CNA's own navigation diffusion per axis, m²/s (≥ 0; 0 for a CNA whose
    /// position error does not grow, whose error is then the root's v alone).
    #[serde(default)]
    pub cna_diffusion_m2_s: f64,
}

impl CheckFields for TruthSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.non_negative(&format!("{prefix}drift_m2_s"), self.drift_m2_s);
        p.positive(&format!("{prefix}range_noise.sigma_m"), self.range_noise.sigma_m);
        p.non_negative(&format!("{prefix}range_noise.per_km_m"), self.range_noise.per_km_m);
        p.non_negative(&format!("{prefix}cna_diffusion_m2_s"), self.cna_diffusion_m2_s);
    }
}

/// One AUV's true-error moments: S = E[εεᵀ] as [S_ee, S_en, S_nn] (m²), C = E[ε e_cᵀ]
/// row-major [C_ee, C_en, C_ne, C_nn] (m²) and the mean m = E[ε] (east, north; m), non-zero only
/// under an unmodelled current (step 1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrueError {
    pub s: [f64; 3],
    pub c: [f64; 4],
    pub m: [f64; 2],
}

/// What the true-error cost starts from at a decision: each AUV's moments (the order of
/// `PlanInput::estimates`) and v, the CNA's own horizontal error variance per axis now, m².
#[derive(Debug, Clone, Copy)]
pub struct TruthInput<'a> {
    pub errors: &'a [TrueError],
    pub cna_variance: f64,
}

/// The recursion's state of one AUV at a node: the filter's P, the true moments and v.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueState {
    pub p: [f64; 3],
    pub truth: TrueError,
    pub v: f64,
}

/// The growth of one level (step 1): q_f·τ, q_t·τ (m² per axis), D·τ (m²) and the error's
/// deterministic shift d = −cτ under an unmodelled current (m; zero without one).
#[derive(Debug, Clone, Copy)]
pub struct Growth {
    pub filter: f64,
    pub truth: f64,
    pub cna: f64,
    pub shift: [f64; 2],
}

/// The noise models of step 2: the filter's (its gain) and the truth's (the error it causes).
#[derive(Debug, Clone, Copy)]
pub struct PingNoise {
    pub filter: RangeNoise,
    /// σ_c² the filter model adds to the range variance (`estimator` step 2), m².
    pub filter_cna_variance: f64,
    pub truth: RangeNoise,
}

/// Steps 1–3: one level's prediction and a ping from `cna` to the AUV at `auv` that arrives with
/// probability `success(slant range)`. Shared by the planner's cost and the closed loop's tracker.
#[inline(always)]
pub fn true_error_step(
    state: &TrueState,
    growth: Growth,
    cna: [f64; 3],
    auv: [f64; 3],
    noise: &PingNoise,
    success: impl Fn(f64) -> f64,
) -> TrueState {
    let predicted = true_error_prediction(state, growth);
    let d = [auv[0] - cna[0], auv[1] - cna[1], auv[2] - cna[2]];
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if r2 <= 1e-12 {
        return predicted;
    }
    let TrueState { p: [pa, pb, pc], truth: TrueError { s: [sa, sb, sc], c, m: [m0, m1] }, v } = predicted;
    let r = r2.sqrt();
    let (h0, h1) = (d[0] / r, d[1] / r);
    let hh = h0 * h0 + h1 * h1;
    let (ph0, ph1) = (pa * h0 + pb * h1, pb * h0 + pc * h1);
    let innovation = h0 * ph0 + h1 * ph1 + noise.filter.variance(r) + noise.filter_cna_variance * hh;
    let (k0, k1) = (ph0 / innovation, ph1 / innovation);
    let p_s = success(r);
    // S̃h, Ch, hᵀCh, Cᵀh.
    let (sh0, sh1) = (sa * h0 + sb * h1, sb * h0 + sc * h1);
    let (ch0, ch1) = (c[0] * h0 + c[1] * h1, c[2] * h0 + c[3] * h1);
    let hch = h0 * ch0 + h1 * ch1;
    let (cth0, cth1) = (c[0] * h0 + c[2] * h1, c[1] * h0 + c[3] * h1);
    let (g0, g1) = (ch0 - k0 * hch - sh0, ch1 - k1 * hch - sh1);
    let w = h0 * sh0 + h1 * sh1 + v * hh + noise.truth.variance(r);
    let s = [
        sa + p_s * (2.0 * k0 * g0 + w * k0 * k0),
        sb + p_s * (k0 * g1 + g0 * k1 + w * k0 * k1),
        sc + p_s * (2.0 * k1 * g1 + w * k1 * k1),
    ];
    let (u0, u1) = (v * h0 - cth0, v * h1 - cth1);
    let c = [c[0] + p_s * k0 * u0, c[1] + p_s * k0 * u1, c[2] + p_s * k1 * u0, c[3] + p_s * k1 * u1];
    let p = [pa - p_s * k0 * ph0, pb - p_s * k0 * ph1, pc - p_s * k1 * ph1];
    let hm = h0 * m0 + h1 * m1;
    let m = [m0 - p_s * k0 * hm, m1 - p_s * k1 * hm];
    TrueState { p, truth: TrueError { s, c, m }, v }
}

/// Step 1 alone: one level's (or any interval's) growth and shift, no ping.
#[inline(always)]
pub fn true_error_prediction(state: &TrueState, growth: Growth) -> TrueState {
    let [pa, pb, pc] = state.p;
    let [m0, m1] = state.truth.m;
    let [d0, d1] = growth.shift;
    let [sa, sb, sc] = state.truth.s;
    let s = [
        sa + growth.truth + (2.0 * m0 + d0) * d0,
        sb + m0 * d1 + d0 * m1 + d0 * d1,
        sc + growth.truth + (2.0 * m1 + d1) * d1,
    ];
    let truth = TrueError { s, c: state.truth.c, m: [m0 + d0, m1 + d1] };
    TrueState { p: [pa + growth.filter, pb, pc + growth.filter], truth, v: state.v + growth.cna }
}

/// The true-error model of one decision: the estimator-aware model (its filter model, link,
/// bias, aggregate and cost-to-go) with the truth's growth and noise.
pub(crate) struct TrueErrorCost {
    pub filter: EkfCost,
    pub truth: TruthSpec,
    /// q_t·τ and D·τ of step 1, m², and the error's shift d = −cτ per level, m.
    pub truth_tau: f64,
    pub cna_tau: f64,
    pub shift: [f64; 2],
}

impl TrueErrorCost {
    pub fn new(filter: EkfCost, truth: TruthSpec, tau: f64) -> Self {
        let [ce, cn] = filter.spec.unmodelled_current;
        let shift = [-ce * tau, -cn * tau];
        TrueErrorCost {
            truth_tau: truth.drift_m2_s * tau,
            cna_tau: truth.cna_diffusion_m2_s * tau,
            shift,
            filter,
            truth,
        }
    }

    /// The root states from the filter covariances and the truth input (one each per AUV).
    pub fn root(covs: impl Iterator<Item = [f64; 3]>, truth: &TruthInput) -> Result<Vec<TrueState>, PlanError> {
        let v = truth.cna_variance;
        if !(v.is_finite() && v >= 0.0) {
            return Err(PlanError::Input(format!(
                "the CNA's true horizontal variance {v} m² is not a finite number >= 0"
            )));
        }
        let roots: Vec<TrueState> = covs.zip(truth.errors).map(|(p, &t)| TrueState { p, truth: t, v }).collect();
        for (k, r) in roots.iter().enumerate() {
            let [a, b, c] = r.truth.s;
            let finite = r.truth.s.iter().chain(&r.truth.c).all(|x| x.is_finite());
            if !(finite && a >= 0.0 && c >= 0.0 && b * b <= a * c * (1.0 + 1e-9)) {
                return Err(PlanError::Input(format!(
                    "AUV {k}: true-error moments {:?} are not a finite positive semi-definite covariance",
                    r.truth
                )));
            }
        }
        Ok(roots)
    }

    /// F1's ping at slant ranges ≥ `range_m`: the expected information p̄/R_t (module header),
    /// taken as a ping that always arrives.
    fn ping_floor(&self, range_m: f64) -> Ping {
        let success = self.filter.link.best_beyond(range_m);
        Ping { iota: success / self.truth.range_noise.variance(range_m), success: 1.0 }
    }

    /// A lower bound on tr(p_s·R_t·KKᵀ), the newest ping's noise (module header): with
    /// x = hᵀP̃h ≥ λ·|h|² (λ ≤ P̃'s smaller eigenvalue), hᵀK = x/(x + R_f + σ_c²|h|²) ≥
    /// λ/(λ + σ_c² + R_f/|h|²) and |K|² ≥ (hᵀK)² (|h| ≤ 1); the CNA is at `nearest` to
    /// `nearest` + 2·spread from the AUV and at most |Δz| + spread above or below it, so
    /// |h|² ≥ 1 − (Δz_max/nearest)², R_f and p_s are taken at the far end and R_t at the near.
    fn newest_noise(&self, k: usize, smallest_p: f64, nearest: f64, b: Below, cna: [f64; 3]) -> f64 {
        let dz = (b.auv[2] - cna[2]).abs() + b.spread;
        if !(nearest > dz) {
            return 0.0;
        }
        let horizontal2 = 1.0 - (dz / nearest) * (dz / nearest);
        let far = nearest + 2.0 * b.spread;
        let filter_noise = self.filter.spec.range_noise.variance(far) / horizontal2 + self.filter.cna_variance;
        let gain = smallest_p / (smallest_p + filter_noise);
        self.filter.worst_success_up_to(k, far) * self.truth.range_noise.variance(nearest) * gain * gain
    }

    /// F2's growth per axis and level, w = q_tτ·Dτ/(q_tτ + Dτ), m² (0 if either is 0).
    fn relative_growth(&self) -> f64 {
        let (q, d) = (self.truth_tau, self.cna_tau);
        if q > 0.0 && d > 0.0 {
            q * d / (q + d)
        } else {
            0.0
        }
    }

    /// Steps 1–3 for AUV `k`.
    #[inline(always)]
    fn step(&self, k: usize, parent: &TrueState, cna: [f64; 3], auv: [f64; 3]) -> TrueState {
        let growth =
            Growth { filter: self.filter.q_tau[k], truth: self.truth_tau, cna: self.cna_tau, shift: self.shift };
        true_error_step(parent, growth, cna, auv, &self.noise(), |r| self.filter.success(k, r))
    }

    fn noise(&self) -> PingNoise {
        PingNoise {
            filter: self.filter.spec.range_noise,
            filter_cna_variance: self.filter.cna_variance,
            truth: self.truth.range_noise,
        }
    }
}

impl CostModel for TrueErrorCost {
    type State = TrueState;

    /// Steps 1–4 of the module's derivation.
    #[inline(always)]
    fn update(&self, k: usize, parent: &TrueState, cna: [f64; 3], auv: [f64; 3]) -> (TrueState, f64) {
        let next = self.step(k, parent, cna, auv);
        let term = self.filter.moments_term(&next.truth.s, self.filter.bias_variance(cna, auv));
        (next, term)
    }

    /// β² computed once for the term and the cost-to-go.
    #[inline(always)]
    fn leaf_cost(&self, k: usize, parent: &TrueState, cna: [f64; 3], auv: [f64; 3]) -> f64 {
        let (next, bias2) = (self.step(k, parent, cna, auv), self.filter.bias_variance(cna, auv));
        let term = self.filter.moments_term(&next.truth.s, bias2);
        self.filter.leaf_term_biased((k, self.truth_tau), &next.truth.s, (cna, auv), term, || bias2)
    }

    fn terminal_levels(&self) -> f64 {
        self.filter.spec.terminal_levels
    }

    /// Steps 6 and 7 of `estimator` with the true drift.
    #[inline(always)]
    fn leaf_term(&self, k: usize, state: &TrueState, cna: [f64; 3], auv: [f64; 3], term: f64) -> f64 {
        self.filter.leaf_term_with((k, self.truth_tau), &state.truth.s, cna, auv, term)
    }

    #[inline(always)]
    fn combine(&self, acc: f64, term: f64) -> f64 {
        self.filter.combine(acc, term)
    }

    /// The larger of F1 and F2 with the newest ping's noise (module header) at each level below
    /// the node.
    fn bound_rest(
        &self,
        k: usize,
        state: &TrueState,
        cna: [f64; 3],
        auv: [f64; 3],
        below: impl Iterator<Item = Below>,
        out: &mut [f64],
    ) {
        let Some(node) = NodeFloor::of(state) else { return };
        let mut known_cna = CovFloor::of(&node.known_cna, cna, auv);
        let mut filter = EigenFloor::of(&state.p);
        let (q_filter, w) = (self.filter.q_tau[k], self.relative_growth());
        let leaf = out.len().saturating_sub(1);
        for (j, (slot, b)) in out.iter_mut().zip(below).enumerate() {
            // The filter's P̃ before this level's ping, then its own chain past it.
            let smallest_p = filter.smaller() + q_filter;
            let ([turn, eigen], nearest) = known_cna.step(self.truth_tau, cna, b, |r| self.ping_floor(r));
            filter.step(q_filter, self.filter.ping_floor(nearest));
            let (trace, det) = node.relative_at(j + 1, w);
            let noise = self.newest_noise(k, smallest_p, nearest, b, cna);
            let half_bias2 = 0.5 * self.filter.bias_variance_floor(b.auv[2], nearest * nearest);
            let growth = if j == leaf { self.filter.reach_growth_of(k, self.truth_tau, nearest) } else { 0.0 };
            let pairs = [turn, eigen, (trace + noise, det)];
            *slot = self.filter.combine(*slot, self.filter.level_bound(pairs, half_bias2, growth));
        }
    }

    /// F1's eigenvalue chain with pings at range 0 and F2, from each root.
    fn level_floors(&self, root: &[TrueState], depth: usize) -> Vec<f64> {
        let (ping, w) = (self.ping_floor(0.0), self.relative_growth());
        let mut nodes: Vec<Option<(NodeFloor, EigenFloor)>> =
            root.iter().map(|s| NodeFloor::of(s).map(|n| (n, EigenFloor::of(&n.known_cna)))).collect();
        (1..=depth)
            .map(|level| {
                let mut f = 0.0;
                for (node, chain) in nodes.iter_mut().flatten() {
                    let known_cna = chain.step(self.truth_tau, ping);
                    let relative = node.relative_at(level, w);
                    f = self.filter.combine(f, self.filter.level_bound([known_cna, relative], 0.0, 0.0));
                }
                f
            })
            .collect()
    }
}

/// What the bound takes from a node's moments (module header): Σ, F1's start, and F's
/// eigenvalues (0, 0 where F2 is left out).
#[derive(Debug, Clone, Copy)]
struct NodeFloor {
    known_cna: [f64; 3],
    relative: (f64, f64),
}

impl NodeFloor {
    /// None when the moments are not a joint covariance (Σ has a negative eigenvalue beyond
    /// rounding).
    fn of(state: &TrueState) -> Option<Self> {
        let (TrueError { s, c, m }, v) = (state.truth, state.v);
        let cov = [s[0] - m[0] * m[0], s[1] - m[0] * m[1], s[2] - m[1] * m[1]];
        let scale = cov[0] + cov[2] + 2.0 * v;
        let known_cna = if v > 0.0 {
            let cct = [c[0] * c[0] + c[1] * c[1], c[0] * c[2] + c[1] * c[3], c[2] * c[2] + c[3] * c[3]];
            [cov[0] - cct[0] / v, cov[1] - cct[1] / v, cov[2] - cct[2] / v]
        } else if c.iter().all(|&x| x == 0.0) {
            cov
        } else {
            return None;
        };
        if !(scale.is_finite() && smallest_eigenvalue(&known_cna) >= -1e-9 * scale) {
            return None;
        }
        Some(NodeFloor { known_cna, relative: Self::relative(cov, c, v, scale) })
    }

    /// F's eigenvalues, larger first: F = v·I − G·C_z⁻¹·Gᵀ with G = Cᵀ − v·I and
    /// C_z = cov − C − Cᵀ + v·I; (0, 0) when C_z's smallest eigenvalue is below 10⁻⁶ of the
    /// moments' scale.
    fn relative(cov: [f64; 3], c: [f64; 4], v: f64, scale: f64) -> (f64, f64) {
        let cz = [cov[0] - 2.0 * c[0] + v, cov[1] - c[1] - c[2], cov[2] - 2.0 * c[3] + v];
        if !(smallest_eigenvalue(&cz) > 1e-6 * scale) {
            return (0.0, 0.0);
        }
        let det = cz[0] * cz[2] - cz[1] * cz[1];
        let inv = [cz[2] / det, -cz[1] / det, cz[0] / det];
        // G row-major: Cᵀ − v·I.
        let g = [c[0] - v, c[2], c[1], c[3] - v];
        // G·C_z⁻¹ (row-major), then its product with Gᵀ (symmetric).
        let a = [
            g[0] * inv[0] + g[1] * inv[1],
            g[0] * inv[1] + g[1] * inv[2],
            g[2] * inv[0] + g[3] * inv[1],
            g[2] * inv[1] + g[3] * inv[2],
        ];
        let gcg = [a[0] * g[0] + a[1] * g[1], a[0] * g[2] + a[1] * g[3], a[2] * g[2] + a[3] * g[3]];
        eigenvalues(&[v - gcg[0], -gcg[1], v - gcg[2]])
    }

    /// F2's (tr, det) after `levels` levels of growth `w` per axis.
    fn relative_at(&self, levels: usize, w: f64) -> (f64, f64) {
        let grown = levels as f64 * w;
        let (l1, l2) = (self.relative.0 + grown, self.relative.1 + grown);
        (l1 + l2, l1 * l2)
    }
}

/// The smaller eigenvalue of the symmetric 2×2 [[a, b], [b, c]], unclamped.
fn smallest_eigenvalue(p: &[f64; 3]) -> f64 {
    let [a, b, c] = *p;
    0.5 * (a + c) - (0.25 * (a - c) * (a - c) + b * b).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXACT: RangeNoise = RangeNoise { sigma_m: 0.5, per_km_m: 0.0 };

    fn noise(truth_sd: f64) -> PingNoise {
        PingNoise { filter: EXACT, filter_cna_variance: 0.0, truth: RangeNoise { sigma_m: truth_sd, per_km_m: 0.0 } }
    }

    /// 2×2 helpers for the hand-written joint propagation.
    type M2 = [[f64; 2]; 2];
    fn mul(a: M2, b: M2) -> M2 {
        let mut m = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                m[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
            }
        }
        m
    }
    fn tr(a: M2) -> M2 {
        [[a[0][0], a[1][0]], [a[0][1], a[1][1]]]
    }
    fn add(a: M2, b: M2) -> M2 {
        [[a[0][0] + b[0][0], a[0][1] + b[0][1]], [a[1][0] + b[1][0], a[1][1] + b[1][1]]]
    }

    /// The joint error [ε; e_c] propagated as a 4×4 linear map ε⁺ = Aε + Be_c + Kn written out
    /// block by block, against the closed form of step 2.
    #[test]
    fn a_ping_is_the_joseph_form_of_the_joint_error() {
        let state = TrueState {
            p: [40.0, 6.0, 25.0],
            truth: TrueError { s: [3.0, 0.5, 2.0], c: [0.4, -0.1, 0.2, 0.3], m: [0.0; 2] },
            v: 1.5,
        };
        let growth = Growth { filter: 10.0, truth: 0.3, cna: 0.2, shift: [0.0; 2] };
        let (cna, auv) = ([0.0, 0.0, 10.0], [300.0, -400.0, 70.0]);
        let got = true_error_step(&state, growth, cna, auv, &noise(1.8), |_| 1.0);
        // By hand.
        let r = ((300.0f64).powi(2) + 400.0f64.powi(2) + 60.0f64.powi(2)).sqrt();
        let h = [300.0 / r, -400.0 / r];
        let p: M2 = [[50.0, 6.0], [6.0, 35.0]];
        let s: M2 = [[3.3, 0.5], [0.5, 2.3]];
        let c: M2 = [[0.4, -0.1], [0.2, 0.3]];
        let v = 1.7;
        let ph = [p[0][0] * h[0] + p[0][1] * h[1], p[1][0] * h[0] + p[1][1] * h[1]];
        let innovation = h[0] * ph[0] + h[1] * ph[1] + 0.25;
        let k = [ph[0] / innovation, ph[1] / innovation];
        let b: M2 = [[k[0] * h[0], k[0] * h[1]], [k[1] * h[0], k[1] * h[1]]];
        let a: M2 = [[1.0 - b[0][0], -b[0][1]], [-b[1][0], 1.0 - b[1][1]]];
        let vb: M2 = [[v * b[0][0], v * b[0][1]], [v * b[1][0], v * b[1][1]]];
        let kk: M2 = [[k[0] * k[0] * 3.24, k[0] * k[1] * 3.24], [k[1] * k[0] * 3.24, k[1] * k[1] * 3.24]];
        let acb = mul(mul(a, c), tr(b));
        let want_s = add(add(add(mul(mul(a, s), tr(a)), add(acb, tr(acb))), mul(vb, tr(b))), kk);
        let want_c = add(mul(a, c), vb);
        let close = |x: f64, y: f64| (x - y).abs() < 1e-12 * (1.0 + y.abs());
        let s_got = got.truth.s;
        assert!(close(s_got[0], want_s[0][0]) && close(s_got[1], want_s[0][1]) && close(s_got[2], want_s[1][1]));
        assert!(close(s_got[1], want_s[1][0]));
        let c_got = got.truth.c;
        assert!(close(c_got[0], want_c[0][0]) && close(c_got[1], want_c[0][1]), "{c_got:?} vs {want_c:?}");
        assert!(close(c_got[2], want_c[1][0]) && close(c_got[3], want_c[1][1]), "{c_got:?} vs {want_c:?}");
        assert!(close(got.v, 1.7));
        // P is the estimator's expected posterior.
        let want_p = crate::expected_posterior(&state.p, 10.0, cna, auv, &EXACT, 0.0, |_| 1.0);
        for i in 0..3 {
            assert!(close(got.p[i], want_p[i]), "{:?} vs {want_p:?}", got.p);
        }
    }

    #[test]
    fn a_lost_ping_is_growth_and_half_a_ping_is_half_way() {
        let state = TrueState {
            p: [40.0, 6.0, 25.0],
            truth: TrueError { s: [3.0, 0.5, 2.0], c: [0.4; 4], m: [0.0; 2] },
            v: 1.5,
        };
        let growth = Growth { filter: 10.0, truth: 0.3, cna: 0.2, shift: [0.0; 2] };
        let (cna, auv) = ([0.0; 3], [500.0, 0.0, 0.0]);
        let lost = true_error_step(&state, growth, cna, auv, &noise(1.8), |_| 0.0);
        assert_eq!(lost.truth, TrueError { s: [3.3, 0.5, 2.3], c: [0.4; 4], m: [0.0; 2] });
        let full = true_error_step(&state, growth, cna, auv, &noise(1.8), |_| 1.0);
        let half = true_error_step(&state, growth, cna, auv, &noise(1.8), |_| 0.5);
        for i in 0..3 {
            assert!((half.truth.s[i] - 0.5 * (full.truth.s[i] + lost.truth.s[i])).abs() < 1e-12);
        }
    }

    /// A filter that trusts its ranges (large P, small R) takes a noisier range's error whole
    /// along the line of sight, and the CNA's persistent offset is inherited: pinged from every
    /// side, the AUV's error follows e_c (C → v·I) and S → v·I, not 0.
    #[test]
    fn repeated_pings_hand_the_cnas_offset_to_the_auv() {
        let mut state = TrueState {
            p: [100.0, 0.0, 100.0],
            truth: TrueError { s: [4.0, 0.0, 4.0], c: [0.0; 4], m: [0.0; 2] },
            v: 9.0,
        };
        let growth = Growth { filter: 50.0, truth: 0.0, cna: 0.0, shift: [0.0; 2] };
        let quiet =
            PingNoise { filter: EXACT, filter_cna_variance: 0.0, truth: RangeNoise { sigma_m: 1e-6, per_km_m: 0.0 } };
        for i in 0..200 {
            let angle = i as f64 * 2.4;
            let cna = [400.0 * angle.cos(), 400.0 * angle.sin(), 0.0];
            state = true_error_step(&state, growth, cna, [0.0; 3], &quiet, |_| 1.0);
        }
        let [sa, sb, sc] = state.truth.s;
        assert!((sa - 9.0).abs() < 0.5 && (sc - 9.0).abs() < 0.5 && sb.abs() < 0.5, "{:?}", state.truth);
        assert!((state.truth.c[0] - 9.0).abs() < 0.5 && (state.truth.c[3] - 9.0).abs() < 0.5, "{:?}", state.truth);
    }

    /// Under an unmodelled current (0.1 m/s east, τ = 30 s) a noiseless AUV's error is the
    /// deterministic mean −cτ per level: S = m mᵀ exactly. A range along the current (from the
    /// east) takes the mean off; one across it (from the north) leaves it whole.
    #[test]
    fn an_unmodelled_current_biases_the_error_and_only_pings_along_it_take_the_bias_off() {
        let start = TrueState { p: [100.0, 0.0, 100.0], truth: TrueError::default(), v: 0.0 };
        let growth = Growth { filter: 50.0, truth: 0.0, cna: 0.0, shift: [-3.0, 0.0] };
        let quiet =
            PingNoise { filter: EXACT, filter_cna_variance: 0.0, truth: RangeNoise { sigma_m: 1e-9, per_km_m: 0.0 } };
        let step =
            |state: &TrueState, cna: [f64; 3], p_s: f64| true_error_step(state, growth, cna, [0.0; 3], &quiet, |_| p_s);
        let lost = step(&start, [500.0, 0.0, 0.0], 0.0);
        assert_eq!((lost.truth.m, lost.truth.s), ([-3.0, 0.0], [9.0, 0.0, 0.0]));
        let lost_twice = step(&lost, [500.0, 0.0, 0.0], 0.0);
        assert_eq!((lost_twice.truth.m, lost_twice.truth.s), ([-6.0, 0.0], [36.0, 0.0, 0.0]));
        let along = step(&lost, [500.0, 0.0, 0.0], 1.0);
        let across = step(&lost, [0.0, 500.0, 0.0], 1.0);
        assert!(along.truth.m[0].abs() < 0.1 && along.truth.s[0] < 0.01, "{:?}", along.truth);
        assert_eq!(across.truth.m, [-6.0, 0.0], "a range across the current cannot see it");
        for e in [along.truth, across.truth] {
            let [m0, m1] = e.m;
            let close = |x: f64, y: f64| (x - y).abs() < 1e-9 * (1.0 + y.abs());
            assert!(close(e.s[0], m0 * m0) && close(e.s[1], m0 * m1) && close(e.s[2], m1 * m1), "{e:?}");
        }
        // Half a ping along: the mean is the mixture's, half way.
        let half = step(&lost, [500.0, 0.0, 0.0], 0.5);
        assert!((half.truth.m[0] - 0.5 * (along.truth.m[0] + lost_twice.truth.m[0])).abs() < 1e-12);
    }

    #[test]
    fn bad_truth_settings_and_inputs_are_named() {
        let bad = TruthSpec {
            drift_m2_s: -1.0,
            range_noise: RangeNoise { sigma_m: 0.0, per_km_m: 0.0 },
            cna_diffusion_m2_s: f64::NAN,
        };
        let e = bad.validate("planner.cost.truth.").unwrap_err().to_string();
        for field in ["drift_m2_s", "range_noise.sigma_m", "cna_diffusion_m2_s"] {
            assert!(e.contains(&format!("planner.cost.truth.{field}")), "{field}: {e}");
        }
        let errors = [TrueError { s: [1.0, 3.0, 1.0], c: [0.0; 4], m: [0.0; 2] }];
        let e = TrueErrorCost::root([[1.0, 0.0, 1.0]].into_iter(), &TruthInput { errors: &errors, cna_variance: 0.0 });
        assert!(e.unwrap_err().to_string().contains("AUV 0: true-error moments"));
        let ok = [TrueError::default()];
        let e = TrueErrorCost::root([[1.0, 0.0, 1.0]].into_iter(), &TruthInput { errors: &ok, cna_variance: -1.0 });
        assert!(e.unwrap_err().to_string().contains("the CNA's true horizontal variance -1"));
    }

    /// A model for the bound's tests: one AUV whose filter grows by 1.5 m² per level, ranges
    /// σ 1.8 m in truth, the AUVs' drift and the CNA's diffusion 0.01 m²/s, τ = 30 s, a link
    /// that falls from 0.8 past 1.5 km, and `spec`'s aggregate, bias and cost-to-go.
    fn bound_model(spec: crate::EstimatorSpec) -> TrueErrorCost {
        struct Falling;
        impl crate::LinkModel for Falling {
            fn success(&self, r: f64) -> f64 {
                0.8 / (1.0 + (r / 1500.0).powi(4))
            }
        }
        let estimates = [crate::AuvEstimate { cov: [20.0, 0.0, 20.0], process_noise: 0.051 }];
        let link = crate::estimator::LinkTable::sample(&Falling).unwrap();
        let filter = EkfCost::new(spec, &estimates, (30.0, 1.5, 2.0), link).unwrap();
        let truth = TruthSpec {
            drift_m2_s: 0.01,
            range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 },
            cna_diffusion_m2_s: 0.01,
        };
        TrueErrorCost::new(filter, truth, 30.0)
    }

    /// The moments the closed loop settles at: the AUV's error follows the CNA's (C = v·I) plus
    /// a relative part; `p` the filter's covariance.
    fn settled(v: f64, relative: f64) -> TrueState {
        let truth = TrueError { s: [v + relative, 0.3, v + relative], c: [v, 0.0, 0.0, v], m: [0.4, -0.2] };
        TrueState { p: [20.0, 2.0, 18.0], truth, v }
    }

    proptest::proptest! {
        /// Along random CNA paths (45 m per level, any heading, any depth change) every level's
        /// bound stays below the level's term, the leaf's below its term with the cost-to-go
        /// over 1 + H.
        #[test]
        fn the_bound_stays_below_every_level_of_any_path(
            headings in proptest::collection::vec((-3.2f64..3.2, -1.0f64..1.0), 6),
            start in (-1500.0f64..1500.0, -1500.0f64..1500.0),
            (v, relative) in (0.0f64..12.0, 0.5f64..6.0),
            aggregate in 0usize..4, bias_per_km_m in 0.0f64..8.0, terminal_levels in 0.0f64..25.0,
            slot_reach in proptest::option::of(0.0f64..3000.0),
        ) {
            let aggregate = [crate::Aggregate::TraceSum, crate::Aggregate::WorstAuv, crate::Aggregate::LogDet, crate::Aggregate::SigmaSum][aggregate];
            let spec = crate::EstimatorSpec { aggregate, bias_per_km_m, terminal_levels, reach_success: 0.7, ..crate::EstimatorSpec::default() };
            let mut cost = bound_model(spec);
            cost.filter.slot_reach = slot_reach.into_iter().collect();
            let root = settled(v, relative);
            let (mut cna, step) = ([start.0, start.1, 10.0], 45.0);
            let auv_at = |j: usize| [0.0, 1.5 * 30.0 * j as f64, 90.0];
            let (node_cna, node_auv) = (cna, auv_at(0));
            let (mut state, mut terms, mut below) = (root, vec![], vec![]);
            for (j, &(heading, climb)) in headings.iter().enumerate() {
                let horizontal = step * (1.0 - climb * climb).sqrt();
                cna = [cna[0] + horizontal * heading.cos(), cna[1] + horizontal * heading.sin(), (cna[2] + step * climb).max(0.0)];
                let auv = auv_at(j + 1);
                let (next, term) = cost.update(0, &state, cna, auv);
                let last = j + 1 == headings.len();
                terms.push(if last { cost.leaf_term(0, &next, cna, auv, term) / (1.0 + terminal_levels) } else { term });
                state = next;
                below.push(Below { auv, spread: (j + 1) as f64 * step, turn: 1.5 * 30.0 + step });
            }
            let mut out = vec![0.0; headings.len()];
            cost.bound_rest(0, &root, node_cna, node_auv, below.into_iter(), &mut out);
            for (j, (bound, term)) in out.iter().zip(&terms).enumerate() {
                proptest::prop_assert!(*bound <= term * (1.0 + 1e-12), "level {}: bound {} above the term {}", j, bound, term);
            }
        }
    }

    /// Where the AUV's error has become the CNA's (S ≈ v·I + a relative part, C = v·I), F2 keeps
    /// the CNA's share v per axis whatever the pings, which F1 (the CNA known) leaves out; and
    /// moments that are no joint covariance (C too large for S) get no bound.
    #[test]
    fn the_bound_keeps_the_share_repeated_pings_hand_over() {
        let spec = crate::EstimatorSpec { aggregate: crate::Aggregate::TraceSum, ..crate::EstimatorSpec::default() };
        let cost = bound_model(spec);
        let below =
            |levels: usize| (1..=levels).map(|j| Below { auv: [0.0, 0.0, 90.0], spread: 45.0 * j as f64, turn: 45.0 });
        let mut out = [0.0; 3];
        cost.bound_rest(0, &settled(8.0, 2.0), [500.0, 0.0, 10.0], [0.0, 0.0, 90.0], below(3), &mut out);
        assert!(out.iter().all(|&b| b >= 16.0), "{out:?}");
        let mut invalid = settled(8.0, 2.0);
        invalid.truth.c = [12.0, 0.0, 0.0, 12.0];
        let mut out = [0.0; 3];
        cost.bound_rest(0, &invalid, [500.0, 0.0, 10.0], [0.0, 0.0, 90.0], below(3), &mut out);
        assert_eq!(out, [0.0; 3]);
    }
}
