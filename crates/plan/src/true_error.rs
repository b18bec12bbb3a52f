//! The true-error cost (issue 10, session 23): the planner scores the survey AUVs' expected TRUE
//! horizontal navigation error under their own filters' gains, not the filters' covariance. The
//! filters' process noise far exceeds the true dead-reckoning drift and their range noise leaves
//! out the truth's outliers and the CNA's own navigation error, so the covariance the estimator-aware
//! cost minimises is not the error it stands for (NEES 2.7 against 1.6–1.9 for the baselines).
//!
//! Derivation, per AUV and look-ahead level of τ seconds: a suboptimal-filter error recursion
//! (the filter's gain applied to the true error; digest gill §3 for the filter, the rest an
//! invention). Horizontal errors only; ε = x̂ − x the AUV's estimate error, e_c = the CNA's
//! broadcast position minus its true one. The state is P (the filter's covariance, as
//! `estimator` steps 1–3 model it), S = E[εεᵀ], C = E[ε e_cᵀ] and E[e_c e_cᵀ] = v·I.
//! 1. Prediction: P̃ = P + q_f·τ·I (the filter's process noise), S̃ = S + q_t·τ·I (the TRUE drift
//!    per axis, [`TruthSpec::drift_m2_s`]), C unchanged (the AUV's drift is independent of the
//!    CNA's), ṽ = v + D·τ (the CNA's own navigation diffusion, [`TruthSpec::cna_diffusion_m2_s`]):
//!    the CNA's error is a shared, persistent random walk, not fresh noise per ping.
//!    An unmodelled water current c (`EstimatorSpec::unmodelled_current`, as the CNA measures it;
//!    issue 10, session 29) moves the AUV by cτ per level while its filter predicts no such
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
//!    moment (Gill's outlier mixture, digest gill §4: 5.6 % of ranges 5–10 m long, E[n²] ≈ 3.2 m²,
//!    against the filter's 0.15 m). The update is linear in the errors, so second moments carry
//!    over exactly whatever their distribution.
//! 3. The ping arrives with probability p_s(r): S_E = (1 − p_s)·S̃ + p_s·S⁺, C_E likewise (the
//!    second moments of the mixture), P as `estimator` step 3. The mean: ε⁺'s is A·m̃ (e_c and n
//!    have none), so m_E = m̃ − p_s·K·(hᵀm̃).
//! 4. The level's term is `estimator` steps 4 and 5 on S_E (the range bias β(r)²/2·I added, then
//!    the aggregate); the cost-to-go is steps 6 and 7 with the true drift q_t for the growth
//!    (the current's mean is not grown beyond the horizon).
//!
//! No lower bound below a node: every term is ≥ 0, so 0 is a valid one, and branch-and-bound
//! is exact by construction (it prunes on the penalties and the costs reached only). The search
//! is then about as costly as brute force: 15·5⁵ leaves for the AUV CNA at L = 5, a few tens of
//! milliseconds per decision.

use crate::cost_model::{Below, CostModel};
use crate::estimator::{EkfCost, RangeNoise};
use crate::PlanError;
use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// What the truth model needs beyond the filter's own settings (`[planner.cost] truth = {...}`).
/// Every value is an invention of issue 10 (session 23), chosen on the tuning seed.
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
        let growth =
            Growth { filter: self.filter.q_tau[k], truth: self.truth_tau, cna: self.cna_tau, shift: self.shift };
        let link = &self.filter.link;
        let next = true_error_step(parent, growth, cna, auv, &self.noise(), |r| link.success(r));
        let term = self.filter.moments_term(&next.truth.s, self.filter.bias_variance(cna, auv));
        (next, term)
    }

    fn terminal_levels(&self) -> f64 {
        self.filter.spec.terminal_levels
    }

    /// Steps 6 and 7 of `estimator` with the true drift.
    #[inline(always)]
    fn leaf_term(&self, _k: usize, state: &TrueState, cna: [f64; 3], auv: [f64; 3], term: f64) -> f64 {
        self.filter.leaf_term_with(self.truth_tau, &state.truth.s, cna, auv, term)
    }

    #[inline(always)]
    fn combine(&self, acc: f64, term: f64) -> f64 {
        self.filter.combine(acc, term)
    }

    /// 0: every term is ≥ 0 (the module header).
    fn bound_rest(
        &self,
        _: usize,
        _: &TrueState,
        _: [f64; 3],
        _: [f64; 3],
        _: impl Iterator<Item = Below>,
        _: &mut [f64],
    ) {
    }

    fn level_floors(&self, _root: &[TrueState], depth: usize) -> Vec<f64> {
        vec![0.0; depth]
    }
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
}
