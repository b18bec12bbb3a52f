//! The estimator-aware cost (invented, docs/models.md#estimator-cost): the planner scores a CNA
//! path by the horizontal position
//! covariances the survey AUVs' own EKFs would hold, instead of Hudson's isotropic model.
//!
//! Derivation, per AUV and look-ahead level of τ seconds (P = [[a, b], [b, c]] east/north, m²):
//! 1. Prediction: P̃ = P + q·τ·I, with q (m²/s) the horizontal process noise the AUV's filter
//!    adds per second and axis (reported with P, [`AuvEstimate`]).
//!    Step 1b (invented): a water current c (m/s) the AUVs' filters do not
//!    model, as the CNA measures it (`unmodelled_current`), moves each AUV's true position by cτ
//!    per level while its filter's covariance does not see it. The error it leaves is along c,
//!    deterministic, and removed only by pings whose line of sight has a component along c. Taken
//!    as a random walk along c that reaches the deterministic m·cτ after m levels unobserved,
//!    m = `drift_levels`: P̃ gains m·(cτ)(cτ)ᵀ per level. The growth is ⪰ 0 and the update is
//!    monotone in P̃, so the bounds below, which leave it out, stay lower bounds. The true-error
//!    cost (`true_error`, step 1) carries the same current exactly, as the error's mean.
//! 2. Ping from the CNA at p to the AUV at x, slant range r = |x − p|. The range's Jacobian with
//!    respect to the AUV's horizontal position is h = (x − p)_xy / r (|h| ≤ 1: a CNA right above
//!    the AUV tells it nothing horizontally, which is the 3-D geometry). Range noise variance
//!    R(r) = σ₀² + (k·r/1000)² ([`RangeNoise`]). The EKF update is
//!    P⁺ = P̃ − P̃hhᵀP̃ / (hᵀP̃h + R).
//!    The CNA's own horizontal position error (an AUV CNA, or a GPS-fixed one): the AUV's filter takes the
//!    CNA's broadcast position as exact, but it is off by e ~ N(0, σ_c²·I₂) per axis (its GPS σ,
//!    or an AUV CNA's dead-reckoning σ grown since its last fix: `PlanInput::cna_variance`). The
//!    range is measured from the true CNA and predicted from the broadcast one, so the innovation
//!    carries −h_xyᵀe more: the effective range variance is R(r) + σ_c²·|h_xy|². (Taken as fresh
//!    per ping; the CNA's error is a random walk, so this under-states its correlation.) The
//!    ping's information along its direction û = h/|h| is then |h|²/(R(r) + σ_c²·|h|²), which
//!    grows with |h|² ≤ 1: at most 1/(R(r) + σ_c²). The bounds below therefore take that
//!    (`EkfCost::ping_floor`) with |h| = 1; with 1/R(r_min) alone they stay valid but cut far
//!    fewer nodes.
//! 3. The packet arrives with probability p_s(r) (the acoustic link's model, passed in as a
//!    [`LinkModel`]); the expected posterior is E = (1 − p_s)·P̃ + p_s·P⁺
//!    = P̃ − p_s·P̃hhᵀP̃ / (hᵀP̃h + R). Beyond an AUV's slot reach (`PlanInput::slot_reach_m`: its
//!    own slot starts before a broadcast from that far has arrived, and a modem hears nothing
//!    while it sends) p_s = 0, and step 7's useful range stops there.
//! 4. Range bias the covariance does not see: a sound-speed error δc, the same
//!    for every ping, makes a range over r off by b = r·δc/c. The filter takes it for noise; after
//!    a ping its estimate moves along h until the range fits, so its radial error becomes
//!    g·b + (1 − g)·(the previous radial error), g = hᵀP̃h/(hᵀP̃h + R) close to 1 whenever the
//!    growth between pings dwarfs R (the closed loop: qτ ≈ 15 m² against R ≈ 1 m²). Repeated pings
//!    therefore leave a radial error of about the newest range's bias, and a lost ping keeps the
//!    previous one (taken at nearly the same range: the CNA moves s·τ per level). With the CNA's
//!    belief δc/c ~ N(0, (k_b/1000)²) (`bias_per_km_m` = k_b, from the configured sound-speed
//!    uncertainty, never the true sound speed), the expected squared true error is about
//!    M = E + β(r)²/2·I, β(r) = k_b·r/1000 (isotropic: the bias's direction turns with the line of
//!    sight). k_b = 0 is the covariance alone.
//!    With a known sound-speed profile (a CTD cast the CNA holds; [`BiasTable`]) the scale error
//!    is no longer a belief but f(z_c, z_a) = c_f/c̄ − 1 between the
//!    CNA's depth and the AUV's (c_f the speed the AUVs' filters assume, c̄ the harmonic mean of the
//!    water between): a range over r is measured r·(1 + f), and the filter, which knows both
//!    depths, moves its horizontal estimate along the line of sight by f·r/|h_xy| until the range
//!    fits. β² becomes (k_b·r/1000)² + f²r²/|h_xy|² (k_b then stands for what the profile leaves
//!    out). In the scenarios' summer profile (invented, `SoundSpeed::summer`) f ranges from −0.4 % to
//!    +0.7 % with the two depths, so the CNA's depth decides the bias as much as its distance does.
//!    The bounds take the smallest |f| the table gives for the AUV's depth at any CNA depth
//!    ([`BiasTable::floor`]; |h_xy| ≤ 1 only raises the term).
//! 5. Level cost over the N AUVs ([`Aggregate`]) of M: Σ tr M (default), max tr M (worst AUV),
//!    Σ ln(1 + det M / 1 m⁴) (log-det, shifted by one so costs stay ≥ 0 as the penalties and the
//!    search require), or Σ √tr M (the sum of 1-σ, m). The path cost is the sum of the level costs,
//!    as for Hudson's model.
//! 6. Cost-to-go beyond the horizon (`CostModel::terminal_levels`): at a leaf the CNA would go on
//!    pinging; holding the leaf's range, each further level costs about the leaf's own term (the
//!    bias part is set by the range alone, and the covariance returns to about the same trace
//!    after every ping while the line of sight turns), so H more levels add H·(leaf term) per AUV
//!    (`terminal_levels` = H). It rewards ending the horizon close to the AUVs, whose benefit the
//!    short horizon otherwise cannot see. The last level's terms count 1 + H times, and so do its
//!    bounds (a fixed factor ≥ 1 commutes with sum and max); the bias term of step 4 is ≥ 0 and
//!    only increases every term, so the covariance bounds below stay valid lower bounds for M;
//!    they add it at the shortest range the CNA can be at (`EkfCost::term_bound`).
//! 7. Reach-time cost-to-go (`reach_success` p_u; for AUVs spread beyond the link's reach): step 6 holds the
//!    leaf's term for H levels, which is right for an AUV the CNA can ping from the leaf and wrong
//!    for one beyond the link's reach: its pings are lost (p_s ≈ 0) and its filter's covariance
//!    grows by qτ per axis and level until the CNA gets close enough. The useful range r_u is the
//!    shortest range at which the planner's link model p_s falls below p_u (`useful_range`).
//!    From the leaf pose at slant range d from the AUV's leaf position, at its speed s (s·τ per
//!    level), the CNA needs m = max(0, d − r_u)/(s·τ) levels to be within r_u (the AUV's own motion
//!    is left out: it may open or close the distance). Level i = 1..H beyond the horizon has then
//!    grown by qτ·min(i, m) per axis over the held leaf covariance; taking i as continuous, the
//!    mean over the H levels is ḡ = (qτ/H)·∫₀ᴴ min(x, m) dx = qτ·(m − m²/(2H)) for m ≤ H and
//!    qτ·H/2 beyond (`EkfCost::reach_growth`). The H levels then count H·term(M + ḡ·I) instead
//!    of H·term(M): exact for the trace sum, the mean growth for the other aggregates. Each AUV is
//!    taken alone (the CNA cannot reach every far AUV at once, so this under-states their growth);
//!    it pulls the CNA towards the AUVs that lose most: fast-growing ones, far beyond r_u. The
//!    term grows with ḡ (trace, √trace and ln(1 + det) all grow with M in the semi-definite
//!    order), so the leaf term stays ≥ (1 + H)·term(M) and step 6's bounds stay valid; the bound
//!    adds ḡ at the shortest leaf range the CNA can reach (ḡ grows with d). p_u = 0 is none.
//!
//! Lower bound for branch-and-bound (the levels below a node; derivation in `EkfCost::bound_rest`):
//! E = (1 − p_s)·P̃ + p_s·P⁺ ⪰ (1 − p̄)·P̃ + p̄·G with P⁺ ⪰ G = (P̃⁻¹ + ι·ûûᵀ)⁻¹, where
//! ι = 1/(R(r_min) + σ_c²) bounds the information of a ping that arrives and p̄ = p̄(r_min) its
//! arrival (p̄(r) = the link's best success at ranges ≥ r, [`LinkTable::best_beyond`]; E falls
//! with p_s because P⁺ ⪯ P̃). A lost ping keeps the prior, so a lossy link's (1 − p̄)·P̃ is what
//! keeps the bound close to the cost (with p̄ = 1 a lossy link's tree is searched almost whole). The
//! information Y = G⁻¹ is bounded above by a diagonal matrix in the frame of the last ping's
//! line of sight, propagated level by level; each level's ping direction turns from the last by
//! at most asin(reach / distance) (AUV motion plus CNA step against how close the CNA can be).
//! Invented parameters (R's defaults) are marked. The model it replaces is Hudson 2012, Ch. 3,
//! eq. (1); the filter it models is Gill 2013, §2.2.1.

use crate::cost_model::{norm, Below, CostModel};
use crate::true_error::TruthSpec;
use crate::PlanError;
use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// How the per-AUV covariances of a level are joined into its cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Aggregate {
    /// Σ_k tr P_k (m²).
    #[default]
    TraceSum,
    /// max_k tr P_k (m²).
    WorstAuv,
    /// Σ_k ln(1 + det P_k / 1 m⁴).
    LogDet,
    /// Σ_k √(tr P_k) (m): the sum of the AUVs' horizontal 1-σ, on the scale of the fleet's mean
    /// error, so one AUV with a huge variance does not outweigh the rest as in the trace sum.
    SigmaSum,
}

/// Range noise the planner assumes, as a standard deviation growing with distance:
/// σ(r)² = σ₀² + (k·r/1000)². Invented defaults (docs/models.md#estimator-cost): σ₀ = 0.15 m (the closed loop's range
/// channel), k = 1 m per km (a 0.07 % sound-speed error).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeNoise {
    /// σ₀, m (> 0).
    #[serde(default = "default_sigma")]
    pub sigma_m: f64,
    /// k, m of standard deviation per km of range (≥ 0).
    #[serde(default = "default_per_km")]
    pub per_km_m: f64,
}

fn default_sigma() -> f64 {
    0.15
}
fn default_per_km() -> f64 {
    1.0
}

impl Default for RangeNoise {
    fn default() -> Self {
        RangeNoise { sigma_m: default_sigma(), per_km_m: default_per_km() }
    }
}

impl RangeNoise {
    /// R(r), m²; non-decreasing in r (the bound relies on it).
    #[inline(always)]
    pub fn variance(&self, range_m: f64) -> f64 {
        let grow = self.per_km_m * range_m * 1e-3;
        self.sigma_m * self.sigma_m + grow * grow
    }
}

/// The estimator-aware cost's settings as the search runs them (a `PlannerSpec`'s
/// `cost = { kind = "estimator" }` resolved for a mission).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorSpec {
    #[serde(default)]
    pub aggregate: Aggregate,
    #[serde(default)]
    pub range_noise: RangeNoise,
    /// k_b of step 4: the 1-σ range bias the CNA assumes, m per km of range (≥ 0; 0 = none).
    #[serde(default)]
    pub bias_per_km_m: f64,
    /// H of step 6: levels of cost-to-go counted beyond the horizon at each leaf (≥ 0; 0 = none).
    #[serde(default)]
    pub terminal_levels: f64,
    /// p_u of step 7: the success probability a ping needs to be useful; the reach cost-to-go
    /// counts each AUV's growth until the CNA is within the range where p_s ≥ p_u (in [0, 1];
    /// 0 = none; it acts only with H > 0).
    #[serde(default)]
    pub reach_success: f64,
    /// c of step 1b: the water current the AUVs' filters do not model, east and north, m/s, as
    /// the CNA measures it (its ADCP); [0, 0] (the default) = none. The true-error cost (`truth`)
    /// takes it as the AUVs' mean error instead (`true_error` step 1).
    #[serde(default, skip_serializing_if = "is_still")]
    pub unmodelled_current: [f64; 2],
    /// m of step 1b: levels over which the current's drift is taken to build up unseen (≥ 0).
    /// Invented (docs/models.md#estimator-cost); 4 (2 minutes at τ = 30 s) by default.
    #[serde(default = "drift_levels")]
    pub drift_levels: f64,
    /// Some: score the AUVs' expected true error under their filters' gains instead of the
    /// filters' covariance (`true_error` module); the decision then needs a `TruthInput`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<TruthSpec>,
}

impl Default for EstimatorSpec {
    fn default() -> Self {
        EstimatorSpec {
            aggregate: Aggregate::default(),
            range_noise: RangeNoise::default(),
            bias_per_km_m: 0.0,
            terminal_levels: 0.0,
            reach_success: 0.0,
            unmodelled_current: [0.0, 0.0],
            drift_levels: drift_levels(),
            truth: None,
        }
    }
}

/// No current: `unmodelled_current`'s default, which a settings file leaves out.
pub fn is_still(current: &[f64; 2]) -> bool {
    *current == [0.0, 0.0]
}

fn drift_levels() -> f64 {
    4.0
}

impl CheckFields for EstimatorSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.finite(&format!("{prefix}unmodelled_current[0]"), self.unmodelled_current[0]);
        p.finite(&format!("{prefix}unmodelled_current[1]"), self.unmodelled_current[1]);
        p.non_negative(&format!("{prefix}drift_levels"), self.drift_levels);
        p.positive(&format!("{prefix}range_noise.sigma_m"), self.range_noise.sigma_m);
        p.non_negative(&format!("{prefix}range_noise.per_km_m"), self.range_noise.per_km_m);
        p.non_negative(&format!("{prefix}bias_per_km_m"), self.bias_per_km_m);
        p.non_negative(&format!("{prefix}terminal_levels"), self.terminal_levels);
        p.probability(&format!("{prefix}reach_success"), self.reach_success);
        if let Some(truth) = &self.truth {
            truth.check_fields(&format!("{prefix}truth."), p);
        }
    }
}

/// One survey AUV's navigation uncertainty as its filter reports it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AuvEstimate {
    /// Horizontal position covariance [P_ee, P_en, P_nn], m².
    pub cov: [f64; 3],
    /// Horizontal process noise q per axis, m²/s (the covariance grows by q·τ·I per step).
    pub process_noise: f64,
}

impl AuvEstimate {
    fn validate(&self, k: usize) -> Result<(), PlanError> {
        let [a, b, c] = self.cov;
        let finite = self.cov.iter().all(|x| x.is_finite()) && self.process_noise.is_finite();
        if finite && a >= 0.0 && c >= 0.0 && b * b <= a * c * (1.0 + 1e-9) && self.process_noise >= 0.0 {
            Ok(())
        } else {
            Err(PlanError::Input(format!(
                "AUV {k}: covariance {:?} and process noise {} are not a positive semi-definite covariance and a \
                 non-negative noise",
                self.cov, self.process_noise
            )))
        }
    }
}

/// The acoustic link as the planner needs it: probability that a ping over `slant_range_m`
/// arrives (in [0, 1]). The sim crate wires the acoustic crate's model in; `()` is a perfect link.
pub trait LinkModel {
    fn success(&self, slant_range_m: f64) -> f64;
}

impl LinkModel for () {
    fn success(&self, _: f64) -> f64 {
        1.0
    }
}

/// A link model sampled every [`LinkTable::STEP_M`] up to [`LinkTable::MAX_M`] and interpolated
/// linearly (the last value holds beyond), so the search never calls back into the link model.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkTable {
    p: Arc<[f64]>,
    /// `best[i]` = max of `p[i..]`: the bounds' p̄ ([`LinkTable::best_beyond`]).
    best: Arc<[f64]>,
    /// `worst[i]` = min of `p[..=i]` ([`LinkTable::worst_up_to`]).
    worst: Arc<[f64]>,
}

impl LinkTable {
    pub const STEP_M: f64 = 5.0;
    pub const MAX_M: f64 = 20_000.0;

    pub fn sample(link: &dyn LinkModel) -> Result<Self, PlanError> {
        let count = (Self::MAX_M / Self::STEP_M) as usize + 1;
        let mut p = Vec::with_capacity(count);
        for i in 0..count {
            let r = i as f64 * Self::STEP_M;
            let s = link.success(r);
            if !(0.0..=1.0).contains(&s) {
                return Err(PlanError::Input(format!(
                    "link model: success probability {s} at {r} m is outside [0, 1]"
                )));
            }
            p.push(s);
        }
        Ok(Self::of(p))
    }

    fn of(p: Vec<f64>) -> Self {
        let mut best = p.clone();
        for i in (0..best.len().saturating_sub(1)).rev() {
            best[i] = best[i].max(best[i + 1]);
        }
        let mut worst = p.clone();
        for i in 1..worst.len() {
            worst[i] = worst[i].min(worst[i - 1]);
        }
        LinkTable { p: p.into(), best: best.into(), worst: worst.into() }
    }

    /// A perfect link.
    pub fn perfect() -> Self {
        Self::of(vec![1.0, 1.0])
    }

    /// p̄(r): an upper bound on [`LinkTable::success`] at every range ≥ `r` (the largest sample
    /// from the one at or below `r` on; the interpolation never exceeds its two samples).
    #[inline(always)]
    pub fn best_beyond(&self, r: f64) -> f64 {
        let i = ((r / Self::STEP_M) as usize).min(self.best.len() - 1);
        self.best[i]
    }

    /// A lower bound on [`LinkTable::success`] at every range ≤ `r` (the smallest sample up to
    /// the one above `r`).
    #[inline(always)]
    pub fn worst_up_to(&self, r: f64) -> f64 {
        let i = ((r / Self::STEP_M) as usize + 1).min(self.worst.len() - 1);
        self.worst[i]
    }

    #[inline(always)]
    pub fn success(&self, r: f64) -> f64 {
        let x = r / Self::STEP_M;
        let i = x as usize;
        if i + 1 >= self.p.len() {
            return self.p[self.p.len() - 1];
        }
        let f = x - i as f64;
        self.p[i] + (self.p[i + 1] - self.p[i]) * f
    }

    /// r_u of step 7: the shortest range at which the interpolated success falls below `p_u`, m
    /// (infinite when it never does, so p_u = 0 makes every AUV reachable at once).
    pub fn useful_range(&self, p_u: f64) -> f64 {
        let Some(i) = self.p.iter().position(|&p| p < p_u) else {
            return f64::INFINITY;
        };
        if i == 0 {
            return 0.0;
        }
        // Linear between the last sample at or above p_u and the first below it.
        let (hi, lo) = (self.p[i - 1], self.p[i]);
        (i as f64 - 1.0 + (hi - p_u) / (hi - lo)) * Self::STEP_M
    }
}

/// The range scale error the CNA expects for a ping between two depths (step 4 with a known
/// sound-speed profile): f(z_cna, z_auv) = c_f / c̄(z_cna, z_auv) − 1, with c_f the speed the
/// AUVs' filters convert travel times with and c̄ the harmonic-mean speed of the water between the
/// two depths (a straight ray), so a range over r is measured r·(1 + f). Sampled every
/// [`BiasTable::STEP_M`] of depth for both ends and interpolated bilinearly (depths beyond the
/// table hold its last row or column), so the search never calls back into the sound-speed model.
#[derive(Debug, Clone, PartialEq)]
pub struct BiasTable {
    f: Arc<[f64]>,
    n: usize,
    /// Per AUV-depth sample j: the smallest |f| the interpolation can give at any CNA depth for an
    /// AUV between samples j and j + 1 (0 when f changes sign there): what the bounds may assume.
    floor_by_auv: Arc<[f64]>,
}

/// Where a known-sign scale error enters the horizontal estimate: 1/|h_xy|² is floored here, so a
/// ping from almost overhead (which the distance limits forbid anyway) costs a large finite bias.
/// Invented (the filter it models is Gill 2013, §2.2.1): a numerical guard, not
/// a model of the sea, so it is not a scenario key.
const BIAS_H2_FLOOR: f64 = 0.05;

impl BiasTable {
    pub const STEP_M: f64 = 2.0;

    /// Samples `scale_error(z_cna, z_auv)` on depths 0..=`max_depth_m`.
    pub fn sample(max_depth_m: f64, scale_error: impl Fn(f64, f64) -> f64) -> Result<Self, PlanError> {
        if !(max_depth_m.is_finite() && max_depth_m >= 0.0) {
            return Err(PlanError::Input(format!("bias table: depth {max_depth_m} m is not a finite number >= 0")));
        }
        let n = (max_depth_m / Self::STEP_M).ceil() as usize + 1;
        let mut f = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let v = scale_error(i as f64 * Self::STEP_M, j as f64 * Self::STEP_M);
                if !v.is_finite() {
                    return Err(PlanError::Input(format!(
                        "bias table: scale error {v} at depths {i}, {j} is not finite"
                    )));
                }
                f.push(v);
            }
        }
        // Bilinear values lie within the range of their four samples, so within columns j, j + 1.
        let column = |j: usize| {
            (0..n).map(|i| f[i * n + j]).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
        };
        let floor_by_auv = (0..n)
            .map(|j| {
                let ((lo1, hi1), (lo2, hi2)) = (column(j), column((j + 1).min(n - 1)));
                let (lo, hi) = (lo1.min(lo2), hi1.max(hi2));
                if lo > 0.0 {
                    lo
                } else if hi < 0.0 {
                    -hi
                } else {
                    0.0
                }
            })
            .collect();
        Ok(BiasTable { f: f.into(), n, floor_by_auv })
    }

    /// A lower bound on |f| for an AUV at depth `z_auv` and the CNA at any depth.
    #[inline(always)]
    pub fn floor(&self, z_auv: f64) -> f64 {
        let j = ((z_auv.max(0.0) / Self::STEP_M) as usize).min(self.n - 1);
        self.floor_by_auv[j]
    }

    /// f (dimensionless) at CNA depth `z_cna` and AUV depth `z_auv` (m).
    #[inline(always)]
    pub fn scale_error(&self, z_cna: f64, z_auv: f64) -> f64 {
        if self.n == 1 {
            return self.f[0];
        }
        let last = (self.n - 1) as f64;
        let (x, y) = ((z_cna.max(0.0) / Self::STEP_M).min(last), (z_auv.max(0.0) / Self::STEP_M).min(last));
        let (i, j) = ((x as usize).min(self.n - 2), (y as usize).min(self.n - 2));
        let (u, v) = (x - i as f64, y - j as f64);
        let at = |a: usize, b: usize| self.f[a * self.n + b];
        let top = at(i, j) + (at(i, j + 1) - at(i, j)) * v;
        let bottom = at(i + 1, j) + (at(i + 1, j + 1) - at(i + 1, j)) * v;
        top + (bottom - top) * u
    }
}

/// Steps 1–3 of the module's derivation: the expected covariance [P_ee, P_en, P_nn] after τ of
/// growth (`q_tau` per axis) and a ping from `cna` (its own horizontal variance `cna_variance`
/// per axis, m²) to the AUV at `auv` that arrives with probability `success(slant range)`.
/// Shared by the planner's cost and the closed loop's model of the AUVs' filters, so both use
/// one formula.
#[inline(always)]
pub fn expected_posterior(
    cov: &[f64; 3],
    q_tau: f64,
    cna: [f64; 3],
    auv: [f64; 3],
    noise: &RangeNoise,
    cna_variance: f64,
    success: impl Fn(f64) -> f64,
) -> [f64; 3] {
    let (mut a, mut b, mut c) = (cov[0] + q_tau, cov[1], cov[2] + q_tau);
    let d = [auv[0] - cna[0], auv[1] - cna[1], auv[2] - cna[2]];
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if r2 > 1e-12 {
        let r = r2.sqrt();
        let (h0, h1) = (d[0] / r, d[1] / r);
        let (ph0, ph1) = (a * h0 + b * h1, b * h0 + c * h1);
        let innovation = h0 * ph0 + h1 * ph1 + noise.variance(r) + cna_variance * (h0 * h0 + h1 * h1);
        let gain = success(r) / innovation;
        a -= gain * ph0 * ph0;
        b -= gain * ph0 * ph1;
        c -= gain * ph1 * ph1;
    }
    [a, b, c]
}

/// How much the tangential information is inflated to make the information diagonal in the
/// line-of-sight frame (any value > 0 keeps the bound valid; small keeps the tangential part,
/// which dominates, tight). Chosen with `coopnav bench planner` (docs/evaluation.md).
const TANGENTIAL_SLACK: f64 = 0.005;

/// The estimator-aware model of one decision.
pub(crate) struct EkfCost {
    pub spec: EstimatorSpec,
    /// q_k·τ per AUV, m².
    pub q_tau: Vec<f64>,
    pub link: LinkTable,
    /// σ_c² of step 2: the CNA's own horizontal variance per axis, m².
    pub cna_variance: f64,
    /// Step 7: the useful range r_u (m) and the CNA's step s·τ (m per level).
    pub reach: Reach,
    /// Step 4's scale error from a known sound-speed profile, on top of `bias_per_km_m`.
    pub bias: Option<BiasTable>,
    /// Step 1b's growth per level, m·(cτ)(cτ)ᵀ as [P_ee, P_en, P_nn], m².
    pub drift: [f64; 3],
    /// Per AUV, the slant range beyond which no ping reaches it whatever the link (its own
    /// transmission slot starts before the broadcast has arrived: half-duplex), m; empty: none.
    pub slot_reach: Vec<f64>,
}

/// What step 7 needs of the CNA and its link.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reach {
    pub useful_range_m: f64,
    pub step_m: f64,
}

impl EkfCost {
    /// The model for AUVs `estimates`, levels of `tau` seconds, a CNA moving `speed` m/s whose own
    /// horizontal variance per axis is `cna_variance` m².
    pub fn new(
        spec: EstimatorSpec,
        estimates: &[AuvEstimate],
        (tau, speed, cna_variance): (f64, f64, f64),
        link: LinkTable,
    ) -> Result<Self, PlanError> {
        for (k, e) in estimates.iter().enumerate() {
            e.validate(k)?;
        }
        if !(cna_variance.is_finite() && cna_variance >= 0.0) {
            return Err(PlanError::Input(format!(
                "the CNA's own horizontal variance {cna_variance} m² is not a finite number >= 0"
            )));
        }
        let reach = Reach { useful_range_m: link.useful_range(spec.reach_success), step_m: speed * tau };
        let q_tau = estimates.iter().map(|e| e.process_noise * tau).collect();
        let [ce, cn] = spec.unmodelled_current.map(|v| v * tau);
        let drift = [ce * ce, ce * cn, cn * cn].map(|v| v * spec.drift_levels);
        Ok(EkfCost { spec, q_tau, link, cna_variance, reach, bias: None, drift, slot_reach: Vec::new() })
    }

    /// Step 3's success for AUV `k` at slant range `r`: the link's, and none beyond the AUV's slot
    /// reach.
    #[inline(always)]
    pub(crate) fn success(&self, k: usize, r: f64) -> f64 {
        if self.beyond_slot_reach(k, r) {
            0.0
        } else {
            self.link.success(r)
        }
    }

    /// A lower bound on [`EkfCost::success`] for AUV `k` at every range ≤ `r`.
    #[inline(always)]
    pub(crate) fn worst_success_up_to(&self, k: usize, r: f64) -> f64 {
        if self.beyond_slot_reach(k, r) {
            0.0
        } else {
            self.link.worst_up_to(r)
        }
    }

    #[inline(always)]
    fn beyond_slot_reach(&self, k: usize, r: f64) -> bool {
        self.slot_reach.get(k).is_some_and(|&reach| r >= reach)
    }

    /// r_u of step 7 for AUV `k`: the link's useful range, and at most the AUV's slot reach.
    #[inline(always)]
    fn useful_range(&self, k: usize) -> f64 {
        self.slot_reach.get(k).map_or(self.reach.useful_range_m, |&reach| reach.min(self.reach.useful_range_m))
    }

    /// Steps 1–3 for AUV `k`: its expected covariance after one level and a ping from `cna`.
    #[inline(always)]
    fn posterior(&self, k: usize, parent: &[f64; 3], cna: [f64; 3], auv: [f64; 3]) -> [f64; 3] {
        let drifted = [parent[0] + self.drift[0], parent[1] + self.drift[1], parent[2] + self.drift[2]];
        expected_posterior(&drifted, self.q_tau[k], cna, auv, &self.spec.range_noise, self.cna_variance, |r| {
            self.success(k, r)
        })
    }

    /// ḡ of step 7 for AUV `k` at slant range `range_m` from the leaf pose: the mean growth per
    /// axis over the H levels beyond the horizon before the CNA is within the useful range, m².
    #[inline(always)]
    fn reach_growth(&self, k: usize, range_m: f64) -> f64 {
        self.reach_growth_of(k, self.q_tau[k], range_m)
    }

    /// ḡ of step 7 for AUV `k` when its covariance grows by `q_tau` per axis and level.
    #[inline(always)]
    pub(crate) fn reach_growth_of(&self, k: usize, q_tau: f64, range_m: f64) -> f64 {
        let h = self.spec.terminal_levels;
        let beyond = range_m - self.useful_range(k);
        if !(beyond > 0.0 && h > 0.0) {
            return 0.0;
        }
        let m = (beyond / self.reach.step_m).min(h);
        q_tau * (m - m * m / (2.0 * h))
    }

    /// (ι, p̄) of the bounds at slant ranges ≥ `range_m`: the most information a ping that arrives
    /// can carry along its direction there, 1/(R(range) + σ_c²) in 1/m² (step 2: |h|²/(R + σ_c²·|h|²)
    /// is largest at |h| = 1, and R grows with range), and the most likely it arrives (step 3).
    #[inline(always)]
    pub(crate) fn ping_floor(&self, range_m: f64) -> Ping {
        let iota = 1.0 / (self.spec.range_noise.variance(range_m) + self.cna_variance);
        Ping { iota, success: self.link.best_beyond(range_m) }
    }

    /// β(r)² of step 4 for a ping from `cna` to the AUV at `auv`, m².
    #[inline(always)]
    pub(crate) fn bias_variance(&self, cna: [f64; 3], auv: [f64; 3]) -> f64 {
        let d = [auv[0] - cna[0], auv[1] - cna[1], auv[2] - cna[2]];
        let range2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let k2 = self.spec.bias_per_km_m * self.spec.bias_per_km_m * 1e-6;
        let Some(table) = &self.bias else { return k2 * range2 };
        // The filter moves its estimate along the horizontal line of sight until the range fits:
        // a range error f·r becomes f·r/|h_xy| horizontally.
        let f = table.scale_error(cna[2], auv[2]);
        let h2 = if range2 > 0.0 { (d[0] * d[0] + d[1] * d[1]) / range2 } else { 1.0 };
        k2 * range2 + f * f * range2 / h2.max(BIAS_H2_FLOOR)
    }

    /// A lower bound on β² of step 4 at a squared range `range2` to an AUV at depth `z_auv`, from
    /// the CNA at any depth, m² (|h_xy| ≤ 1 only raises the profile's term).
    #[inline(always)]
    pub(crate) fn bias_variance_floor(&self, z_auv: f64, range2: f64) -> f64 {
        let k2 = self.spec.bias_per_km_m * self.spec.bias_per_km_m * 1e-6;
        let f2 = self.bias.as_ref().map_or(0.0, |t| t.floor(z_auv) * t.floor(z_auv));
        (k2 + f2) * range2
    }

    /// A lower bound on a level's term from lower bounds on tr E and det E and the half bias
    /// variance h = β²/2 at the shortest possible range (plus step 7's growth ḡ at the leaf):
    /// M = E + h·I has tr M = tr E + 2h and det M = det E + h·tr E + h², both increasing in tr E
    /// and det E. With exact tr E and det E it is the term itself.
    #[inline(always)]
    fn term_bound(&self, trace: f64, det: f64, half_bias2: f64) -> f64 {
        let h = half_bias2;
        self.term(trace + 2.0 * h, det + h * trace + h * h)
    }

    /// The largest of [`EkfCost::term_bound`] over pairs of lower bounds (tr E, det E). The
    /// trace-only aggregates take the largest trace first: the term is a non-decreasing function
    /// of the trace alone, and so is its floating-point evaluation (√ and max are correctly
    /// rounded), so the result is the same number with one square root instead of several.
    #[inline(always)]
    fn larger_term_bound<const K: usize>(&self, pairs: [(f64, f64); K], half_bias2: f64) -> f64 {
        match self.spec.aggregate {
            Aggregate::LogDet => pairs.iter().map(|&(t, d)| self.term_bound(t, d, half_bias2)).fold(0.0, f64::max),
            Aggregate::TraceSum | Aggregate::WorstAuv | Aggregate::SigmaSum => {
                let h = half_bias2;
                self.term(pairs.iter().map(|&(t, _)| t + 2.0 * h).fold(0.0, f64::max), 0.0)
            }
        }
    }

    /// A lower bound on one level's term from lower bounds (tr E, det E) on its covariance, the
    /// half bias variance at the shortest range, and at the leaf step 7's growth ḡ there (0
    /// elsewhere), scaled by 1/(1 + H) because the tree weights the leaf's bound by 1 + H
    /// (`Tree::rest_bound`): (term + H·term(+ḡ))/(1 + H).
    #[inline(always)]
    pub(crate) fn level_bound<const K: usize>(&self, pairs: [(f64, f64); K], half_bias2: f64, growth: f64) -> f64 {
        let term = self.larger_term_bound(pairs, half_bias2);
        if growth <= 0.0 {
            return term;
        }
        let h = self.spec.terminal_levels;
        (term + h * self.larger_term_bound(pairs, half_bias2 + growth)) / (1.0 + h)
    }

    /// Step 4 and 5's term of a covariance `cov` with the range bias variance β² (m²):
    /// the aggregate's term of M = cov + β²/2·I.
    #[inline(always)]
    pub(crate) fn moments_term(&self, cov: &[f64; 3], bias2: f64) -> f64 {
        let [a, b, c] = *cov;
        let half_bias2 = 0.5 * bias2;
        let (ma, mc) = (a + half_bias2, c + half_bias2);
        self.term(ma + mc, ma * mc - b * b)
    }

    /// Steps 6 and 7 for a leaf covariance `cov` growing by `q_tau` per axis and level: the
    /// leaf's term plus H levels at M + ḡ·I (ḡ = 0: (1 + H)·term exactly).
    #[inline(always)]
    pub(crate) fn leaf_term_with(
        &self,
        (k, q_tau): (usize, f64),
        cov: &[f64; 3],
        cna: [f64; 3],
        auv: [f64; 3],
        term: f64,
    ) -> f64 {
        self.leaf_term_biased((k, q_tau), cov, (cna, auv), term, || self.bias_variance(cna, auv))
    }

    /// [`EkfCost::leaf_term_with`] given `bias2`, β² of that ping (step 4), when it is needed.
    #[inline(always)]
    pub(crate) fn leaf_term_biased(
        &self,
        (k, q_tau): (usize, f64),
        cov: &[f64; 3],
        (cna, auv): ([f64; 3], [f64; 3]),
        term: f64,
        bias2: impl FnOnce() -> f64,
    ) -> f64 {
        let h = self.spec.terminal_levels;
        if self.useful_range(k) == f64::INFINITY {
            return term * (1.0 + h); // no reach cost-to-go: ḡ = 0 at every range
        }
        let d = [auv[0] - cna[0], auv[1] - cna[1], auv[2] - cna[2]];
        let range2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let growth = self.reach_growth_of(k, q_tau, range2.sqrt());
        if growth <= 0.0 {
            return term * (1.0 + h);
        }
        let [a, b, c] = *cov;
        let half_bias2 = 0.5 * bias2();
        let (ma, mc) = (a + half_bias2, c + half_bias2);
        term + h * self.term_bound(ma + mc, ma * mc - b * b, growth)
    }

    #[inline(always)]
    pub(crate) fn term(&self, trace: f64, det: f64) -> f64 {
        match self.spec.aggregate {
            Aggregate::TraceSum | Aggregate::WorstAuv => trace,
            Aggregate::LogDet => det.max(0.0).ln_1p(),
            // Increasing in the trace, so a lower bound on the trace bounds it too.
            Aggregate::SigmaSum => trace.max(0.0).sqrt(),
        }
    }
}

impl CostModel for EkfCost {
    type State = [f64; 3];

    /// Steps 1–5 of the module's derivation.
    #[inline(always)]
    fn update(&self, k: usize, parent: &[f64; 3], cna: [f64; 3], auv: [f64; 3]) -> ([f64; 3], f64) {
        let posterior = self.posterior(k, parent, cna, auv);
        (posterior, self.moments_term(&posterior, self.bias_variance(cna, auv)))
    }

    /// β² computed once for the term and the cost-to-go.
    #[inline(always)]
    fn leaf_cost(&self, k: usize, parent: &[f64; 3], cna: [f64; 3], auv: [f64; 3]) -> f64 {
        let (posterior, bias2) = (self.posterior(k, parent, cna, auv), self.bias_variance(cna, auv));
        let term = self.moments_term(&posterior, bias2);
        self.leaf_term_biased((k, self.q_tau[k]), &posterior, (cna, auv), term, || bias2)
    }

    /// Step 6: H levels at the leaf's term.
    fn terminal_levels(&self) -> f64 {
        self.spec.terminal_levels
    }

    /// Steps 6 and 7: the leaf's term plus H levels at M + ḡ·I (ḡ = 0: (1 + H)·term exactly).
    #[inline(always)]
    fn leaf_term(&self, k: usize, state: &[f64; 3], cna: [f64; 3], auv: [f64; 3], term: f64) -> f64 {
        self.leaf_term_with((k, self.q_tau[k]), state, cna, auv, term)
    }

    #[inline(always)]
    fn combine(&self, acc: f64, term: f64) -> f64 {
        match self.spec.aggregate {
            Aggregate::WorstAuv => acc.max(term),
            Aggregate::TraceSum | Aggregate::LogDet | Aggregate::SigmaSum => acc + term,
        }
    }

    /// Two chains of lower bounds on P, level by level ([`CovFloor`]); each level takes the
    /// larger. Each level's ping is bounded by `ping_floor` at the shortest range
    /// max(0, |a − c| − spread) the CNA can be at (R grows with range, p̄ only falls); the bias
    /// term of step 4 at that shortest range is added (`term_bound`), and at the leaf step 7's
    /// growth ḡ at that range ([`EkfCost::level_bound`]).
    fn bound_rest(
        &self,
        k: usize,
        state: &[f64; 3],
        cna: [f64; 3],
        auv: [f64; 3],
        below: impl Iterator<Item = Below>,
        out: &mut [f64],
    ) {
        let q = self.q_tau[k];
        let mut floor = CovFloor::of(state, cna, auv);
        let leaf = out.len().saturating_sub(1);
        for (j, (slot, b)) in out.iter_mut().zip(below).enumerate() {
            let (chains, nearest) = floor.step(q, cna, b, |r| self.ping_floor(r));
            let half_bias2 = 0.5 * self.bias_variance_floor(b.auv[2], nearest * nearest);
            let growth = if j == leaf { self.reach_growth(k, nearest) } else { 0.0 };
            *slot = self.combine(*slot, self.level_bound(chains, half_bias2, growth));
        }
    }

    /// The eigenvalue chain ([`EigenFloor`]) from each root covariance, with ι at range 0 (the
    /// most information a ping can carry anywhere) at every level.
    fn level_floors(&self, root: &[[f64; 3]], depth: usize) -> Vec<f64> {
        let ping = self.ping_floor(0.0);
        let mut chains: Vec<EigenFloor> = root.iter().map(EigenFloor::of).collect();
        (0..depth)
            .map(|_| {
                let mut f = 0.0;
                for (k, chain) in chains.iter_mut().enumerate() {
                    let (trace, det) = chain.step(self.q_tau[k], ping);
                    f = self.combine(f, self.term(trace, det));
                }
                f
            })
            .collect()
    }
}

/// The two chains of lower bounds on a covariance below a node, level by level, for any CNA path
/// ([`EkfCost::bound_rest`]'s derivation; the true-error cost's bound runs them on its own
/// covariance and pings):
/// - [`TurnFloor`]: P ⪰ diag(radial, tangential) in the frame of the last ping's horizontal
///   line of sight, starting from the node's (`diagonal_floor`), the line of sight turning per
///   level by at most asin(turn / D_h) where D_h ≥ |(a − c)_h| − spread at the level above
///   (the node's own distance for the first level below);
/// - [`EigenFloor`]: whatever the ping directions.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CovFloor {
    turn: TurnFloor,
    eigen: EigenFloor,
    /// The horizontal line of sight is at least this long before the next level's move, m.
    before: f64,
}

impl CovFloor {
    /// The chains from the covariance `cov` at a node with the CNA at `cna` and the AUV at `auv`.
    pub(crate) fn of(cov: &[f64; 3], cna: [f64; 3], auv: [f64; 3]) -> Self {
        let (dx, dy) = (auv[0] - cna[0], auv[1] - cna[1]);
        let horizontal = (dx * dx + dy * dy).sqrt();
        let u = if horizontal > 1e-9 { [dx / horizontal, dy / horizontal] } else { [1.0, 0.0] };
        let (radial, tangential) = diagonal_floor(cov, u);
        CovFloor { turn: TurnFloor { radial, tangential }, eigen: EigenFloor::of(cov), before: horizontal }
    }

    /// One level below (growth `q_tau` per axis, the ping bounded by `ping` at the shortest slant
    /// range the CNA can be at): each chain's (tr, det) bound, and that shortest range (m).
    #[inline(always)]
    pub(crate) fn step(
        &mut self,
        q_tau: f64,
        cna: [f64; 3],
        b: Below,
        ping: impl Fn(f64) -> Ping,
    ) -> ([(f64, f64); 2], f64) {
        let turn_max = if self.before > b.turn { (b.turn / self.before) * (b.turn / self.before) } else { 1.0 };
        let los = [b.auv[0] - cna[0], b.auv[1] - cna[1], b.auv[2] - cna[2]];
        let nearest = (norm(los) - b.spread).max(0.0);
        let ping = ping(nearest);
        self.before = (los[0] * los[0] + los[1] * los[1]).sqrt() - b.spread;
        ([self.turn.step(q_tau, turn_max, ping), self.eigen.step(q_tau, ping)], nearest)
    }
}

/// Lower bounds (v_u, v_t) with P ⪰ diag(v_u, v_t) in the frame (u, t = u rotated +90°): the
/// information Y = P⁻¹ ⪯ diag(Y_uu + Y_ut²/(ρ·Y_tt), (1 + ρ)·Y_tt) for ρ > 0 (the difference
/// [[Y_ut²/(ρY_tt), −Y_ut], [−Y_ut, ρY_tt]] has zero determinant and is ⪰ 0), ρ =
/// [`TANGENTIAL_SLACK`]. A singular P gets (0, 0).
fn diagonal_floor(p: &[f64; 3], u: [f64; 2]) -> (f64, f64) {
    let [a, b, c] = *p;
    let det = a * c - b * b;
    if !(det > 0.0) {
        return (0.0, 0.0);
    }
    let t = [-u[1], u[0]];
    let p_uu = u[0] * (a * u[0] + b * u[1]) + u[1] * (b * u[0] + c * u[1]);
    let p_tt = t[0] * (a * t[0] + b * t[1]) + t[1] * (b * t[0] + c * t[1]);
    let p_ut = u[0] * (a * t[0] + b * t[1]) + u[1] * (b * t[0] + c * t[1]);
    // Y = P⁻¹ in the frame: Y_uu = p_tt/det, Y_tt = p_uu/det, Y_ut = −p_ut/det.
    let (y_uu, y_tt, y_ut) = (p_tt / det, p_uu / det, p_ut / det);
    if y_ut == 0.0 {
        return (1.0 / y_uu, 1.0 / y_tt);
    }
    let y_uu_max = y_uu + y_ut * y_ut / (TANGENTIAL_SLACK * y_tt);
    (1.0 / y_uu_max, 1.0 / ((1.0 + TANGENTIAL_SLACK) * y_tt))
}

/// What bounds one level's ping (`EkfCost::ping_floor`): ι ≥ the information along its direction
/// if it arrives, 1/m², and p̄ ≥ the probability that it arrives.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ping {
    pub iota: f64,
    pub success: f64,
}

/// Lower bounds m₁ (larger) and m₂ (smaller) on the eigenvalues λ₁ ≥ λ₂ of an AUV's covariance,
/// whatever the ping directions. One level: prediction adds qτ to both; then E = P̃ − (rank-one
/// ⪰ 0) gives, with R = 1/ι and p̄ of [`Ping`] (the reduction p_s·hᵀP̃²h/(hᵀP̃h + R(r) + σ_c²|h|²)
/// equals p_s·ûᵀP̃²û/(ûᵀP̃û + R(r)/|h|² + σ_c²), whose last two terms are ≥ R):
/// - tr E ≥ tr P̃ − p̄·λ₁²/(λ₁ + R) = λ₂ + λ₁R/(λ₁ + R) + (1 − p̄)·λ₁²/(λ₁ + R) (the reduction
///   ûᵀP̃²û/(ûᵀP̃û + R) is largest along the major axis), increasing in λ₁ and λ₂;
/// - λ₁(E) ≥ λ₂(P̃) (interlacing), λ₁(E) ≥ tr E / 2 and λ₁(E) ≥ (1 − p̄)·λ₁ (E ⪰ (1 − p̄)·P̃);
/// - λ₂(E) ≥ (1 − p̄)·λ₂ + p̄/(1/λ₂ + 1/R) (E ⪰ (1 − p̄)·P̃ + p̄·(P̃⁻¹ + I/R)⁻¹, a function of P̃
///   increasing in each eigenvalue);
/// - det E = λ₁(E)·λ₂(E) ≥ m₁'·m₂'.
///
/// It is tight for the next level (one rank-one update), which is where most nodes are cut.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EigenFloor {
    m1: f64,
    m2: f64,
}

impl EigenFloor {
    pub(crate) fn of(p: &[f64; 3]) -> Self {
        let (m1, m2) = eigenvalues(p);
        EigenFloor { m1, m2 }
    }

    /// The lower bound on the smaller eigenvalue.
    pub(crate) fn smaller(&self) -> f64 {
        self.m2
    }

    /// Advances one level; returns the bounds on (tr E, det E).
    #[inline(always)]
    pub(crate) fn step(&mut self, q_tau: f64, ping: Ping) -> (f64, f64) {
        let (l1, l2) = (self.m1 + q_tau, self.m2 + q_tau);
        let (iota, lost) = (ping.iota, 1.0 - ping.success);
        // λR/(λ + R) with 1/R = ι, and what a lost ping keeps of the reduction λ − λR/(λ + R).
        let (kept1, kept2) = (l1 / (1.0 + l1 * iota), l2 / (1.0 + l2 * iota));
        let trace = l2 + kept1 + lost * (l1 - kept1);
        self.m2 = kept2 + lost * (l2 - kept2);
        self.m1 = l2.max(0.5 * trace).max(lost * l1);
        (trace, self.m1 * self.m2)
    }
}

/// Lower bounds (radial, tangential) with P ⪰ diag(radial, tangential) in the frame of the last
/// ping's horizontal direction, whatever the path: the bound that follows how fast the line of
/// sight can turn. One level, with D = diag(radial + qτ, tangential + qτ) = diag(1/α, 1/β):
/// - the ping's direction turns from the last by Δ with sin²Δ ≤ T (the line of sight moves by at
///   most the reach r while at least D_h long: T = (r/D_h)², or 1);
/// - E ⪰ (1 − p̄)·D + p̄·G (module header) and, in the frame (h, n) of the new ping, G ⪰ Y⁻¹ with
///   Y = D⁻¹ rotated by Δ plus diag(ι, 0) ([`Ping`]); with t = sin²Δ: Y_hh = α − t(α − β) + ι,
///   Y_nn = β + t(α − β), Y_hn² = t(1 − t)(α − β)², so tr Y = α + β + ι and
///   det Y = αβ + ι·Y_nn(t);
/// - tr E ≥ tr Y / det Y and det E ≥ 1 / det Y are smallest where Y_nn is largest: t = T when
///   α > β, else t = 0;
/// - Y ⪯ diag(Y_hh + Y_hn²/(ρ·Y_nn), (1 + ρ)·Y_nn) (ρ = [`TANGENTIAL_SLACK`], as in
///   `diagonal_floor`), and over t ≤ T: Y_hh ≤ α + ι + T·max(β − α, 0), Y_nn ≤ β + T·max(α − β, 0)
///   and Y_hn²/Y_nn = t(1 − t)(α − β)²/(β + t(α − β)) ≤ T(α − β)²/(β + T(α − β)) (increasing in
///   t), which gives G's (radial, tangential) in the new ping's frame;
/// - the lost share: (1 − p̄)·D ⪰ (1 − p̄)·min(1/α, 1/β)·I in any frame, added to p̄ times G's
///   diagonal for the next level; tr E ≥ (1 − p̄)·tr D + p̄·tr G and, by Minkowski's determinant
///   inequality (√det is superadditive on 2×2 semi-definite matrices),
///   det E ≥ ((1 − p̄)·√det D + p̄·√det G)².
///
/// Near AUVs gain most: their line of sight may leave any cone within a few levels, but it still
/// turns at most asin(r/D_h) per level, so the tangential variance keeps growing.
#[derive(Debug, Clone, Copy)]
struct TurnFloor {
    radial: f64,
    tangential: f64,
}

impl TurnFloor {
    /// Advances one level with sin²Δ ≤ `turn_max`; returns the bounds on (tr E, det E).
    #[inline(always)]
    fn step(&mut self, q_tau: f64, turn_max: f64, ping: Ping) -> (f64, f64) {
        let (a, b) = (self.radial + q_tau, self.tangential + q_tau);
        let (iota, lost) = (ping.iota, 1.0 - ping.success);
        if !(a > 0.0 && b > 0.0) {
            // A singular floor: nothing is known beyond E ⪰ 0.
            *self = TurnFloor { radial: 0.0, tangential: 0.0 };
            return (0.0, 0.0);
        }
        let (alpha, beta) = (1.0 / a, 1.0 / b);
        let excess = alpha - beta;
        // Y_nn at the largest turn (≥ min(α, β) > 0), and its largest value over the turns.
        let y_nn_turned = beta + turn_max * excess;
        let y_nn_max = y_nn_turned.max(beta);
        let y_hh_max = alpha + iota + turn_max * (-excess).max(0.0);
        // radial = 1/(Y_hh,max + T(α − β)²/(ρ·Y_nn(T))) and tangential = 1/((1 + ρ)·Y_nn,max), both
        // from one division (it is on the chain's critical path).
        let radial_den = TANGENTIAL_SLACK * y_nn_turned * y_hh_max + turn_max * excess * excess;
        let tangential_den = (1.0 + TANGENTIAL_SLACK) * y_nn_max;
        let inv = 1.0 / (radial_den * tangential_den);
        self.radial = TANGENTIAL_SLACK * y_nn_turned * tangential_den * inv;
        self.tangential = radial_den * inv;
        let inv_det = 1.0 / (alpha * beta + iota * y_nn_max);
        let (trace, det) = ((alpha + beta + iota) * inv_det, inv_det);
        if lost <= 0.0 {
            return (trace, det);
        }
        let kept = lost * a.min(b);
        let p = ping.success;
        self.radial = p * self.radial + kept;
        self.tangential = p * self.tangential + kept;
        let root_det = lost * (a * b).sqrt() + p * det.sqrt();
        (lost * (a + b) + p * trace, root_det * root_det)
    }
}

/// Eigenvalues of the symmetric 2×2 [[a, b], [b, c]], larger first, clamped at 0.
pub(crate) fn eigenvalues(p: &[f64; 3]) -> (f64, f64) {
    let [a, b, c] = *p;
    let mean = 0.5 * (a + c);
    let radius = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    ((mean + radius).max(0.0), (mean - radius).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A link whose success falls linearly from 1 at 0 m to 0 at `.0` m.
    struct Linear(f64);

    impl LinkModel for Linear {
        fn success(&self, r: f64) -> f64 {
            (1.0 - r / self.0).max(0.0)
        }
    }

    /// A lossy link below a plateau that falls with range and, with a tail, rises again (so p̄ is
    /// not the success itself).
    struct Dipping {
        plateau: f64,
        mid: f64,
        tail: f64,
    }

    impl LinkModel for Dipping {
        fn success(&self, r: f64) -> f64 {
            let fall = 1.0 / (1.0 + (r / self.mid).powi(4));
            self.plateau * ((1.0 - self.tail) * fall + self.tail * r / (r + self.mid))
        }
    }

    /// No reach cost-to-go: every AUV is within reach.
    const NO_REACH: Reach = Reach { useful_range_m: f64::INFINITY, step_m: 1.0 };

    /// A perfect link, an exactly known CNA and no bias table: `spec`'s terms alone.
    fn perfect(spec: EstimatorSpec, q_tau: Vec<f64>, reach: Reach) -> EkfCost {
        EkfCost {
            spec,
            q_tau,
            link: LinkTable::perfect(),
            cna_variance: 0.0,
            reach,
            bias: None,
            drift: [0.0; 3],
            slot_reach: Vec::new(),
        }
    }

    fn biased(aggregate: Aggregate, q_tau: Vec<f64>, bias_per_km_m: f64) -> EkfCost {
        perfect(EstimatorSpec { aggregate, bias_per_km_m, ..EstimatorSpec::default() }, q_tau, NO_REACH)
    }

    fn model(aggregate: Aggregate, q_tau: Vec<f64>, link: LinkTable) -> EkfCost {
        let spec = EstimatorSpec { aggregate, ..EstimatorSpec::default() };
        EkfCost {
            spec,
            q_tau,
            link,
            cna_variance: 0.0,
            reach: NO_REACH,
            bias: None,
            drift: [0.0; 3],
            slot_reach: Vec::new(),
        }
    }

    #[test]
    fn a_ping_is_the_ekf_range_update() {
        // P = [[4, 1], [1, 2]], AUV at (300, 400, 0) from the CNA: h = (0.6, 0.8), P̃h = (3.2, 2.2),
        // hᵀP̃h = 3.68, R = 0.15² + 0.5² = 0.2725, innovation 3.9525.
        let m = model(Aggregate::TraceSum, vec![0.0], LinkTable::perfect());
        let (p, cost) = m.update(0, &[4.0, 1.0, 2.0], [0.0; 3], [300.0, 400.0, 0.0]);
        let want = [4.0 - 10.24 / 3.9525, 1.0 - 7.04 / 3.9525, 2.0 - 4.84 / 3.9525];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < 1e-12, "{p:?} vs {want:?}");
        }
        assert!((cost - (want[0] + want[2])).abs() < 1e-12);
    }

    #[test]
    fn the_cnas_own_variance_adds_to_the_range_variance_by_the_horizontal_share() {
        // As above with σ_c² = 4 m²: level geometry, |h_xy|² = 1, innovation 3.9525 + 4.
        let mut m = model(Aggregate::TraceSum, vec![0.0], LinkTable::perfect());
        m.cna_variance = 4.0;
        let (p, _) = m.update(0, &[4.0, 1.0, 2.0], [0.0; 3], [300.0, 400.0, 0.0]);
        let want = [4.0 - 10.24 / 7.9525, 1.0 - 7.04 / 7.9525, 2.0 - 4.84 / 7.9525];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < 1e-12, "{p:?} vs {want:?}");
        }
        // Slant: AUV 300 m east and 400 m below, r = 500 m, h_xy = (0.6, 0), |h_xy|² = 0.36.
        // P̃h = (2.4, 0.6), hᵀP̃h = 1.44, R = 0.15² + 0.5² = 0.2725, plus 0.36·4 = 1.44: 3.1525.
        let (p, _) = m.update(0, &[4.0, 1.0, 2.0], [0.0; 3], [300.0, 0.0, 400.0]);
        let want = [4.0 - 5.76 / 3.1525, 1.0 - 1.44 / 3.1525, 2.0 - 0.36 / 3.1525];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < 1e-12, "{p:?} vs {want:?}");
        }
    }

    #[test]
    fn a_lost_ping_leaves_only_the_growth_and_half_a_ping_half_the_reduction() {
        struct Never;
        impl LinkModel for Never {
            fn success(&self, _: f64) -> f64 {
                0.0
            }
        }
        struct Half;
        impl LinkModel for Half {
            fn success(&self, _: f64) -> f64 {
                0.5
            }
        }
        let start = [4.0, 1.0, 2.0];
        let (cna, auv) = ([0.0; 3], [300.0, 400.0, 50.0]);
        let lost =
            model(Aggregate::TraceSum, vec![0.5], LinkTable::sample(&Never).unwrap()).update(0, &start, cna, auv);
        assert_eq!(lost.0, [4.5, 1.0, 2.5]);
        let full = model(Aggregate::TraceSum, vec![0.5], LinkTable::perfect()).update(0, &start, cna, auv).1;
        let half =
            model(Aggregate::TraceSum, vec![0.5], LinkTable::sample(&Half).unwrap()).update(0, &start, cna, auv).1;
        assert!((half - 0.5 * (full + lost.1)).abs() < 1e-12);
    }

    #[test]
    fn the_range_bias_adds_beta_squared_to_the_trace_and_grows_with_range() {
        // k_b = 2 m/km: β(500 m)² = 1 m², β(1000 m)² = 4 m²; the covariance itself is unchanged.
        let (plain, bias) = (biased(Aggregate::TraceSum, vec![0.0], 0.0), biased(Aggregate::TraceSum, vec![0.0], 2.0));
        let start = [4.0, 1.0, 2.0];
        for (auv, beta2) in [([300.0, 400.0, 0.0], 1.0), ([600.0, 800.0, 0.0], 4.0)] {
            let (p0, c0) = plain.update(0, &start, [0.0; 3], auv);
            let (p1, c1) = bias.update(0, &start, [0.0; 3], auv);
            assert_eq!(p0, p1);
            assert!((c1 - c0 - beta2).abs() < 1e-12, "{c1} - {c0} vs {beta2}");
        }
        // Log-det: det(E + β²/2·I) = det E + β²/2·tr E + β⁴/4.
        let (plain, bias) = (biased(Aggregate::LogDet, vec![0.0], 0.0), biased(Aggregate::LogDet, vec![0.0], 2.0));
        let (p, c0) = plain.update(0, &start, [0.0; 3], [600.0, 800.0, 0.0]);
        let det = p[0] * p[2] - p[1] * p[1];
        let want = (det + 2.0 * (p[0] + p[2]) + 4.0).ln_1p();
        assert!((bias.update(0, &start, [0.0; 3], [600.0, 800.0, 0.0]).1 - want).abs() < 1e-12);
        assert!(want > c0);
    }

    /// The table returns its function at the samples, is exact between them for a function linear
    /// in each depth, holds its edges beyond, and the bias term is k_b's plus f²r²/|h_xy|².
    #[test]
    fn a_bias_table_interpolates_its_scale_error_and_prices_the_line_of_sight() {
        let f = |zc: f64, za: f64| 1e-3 + 2e-5 * zc - 3e-5 * za + 1e-7 * zc * za;
        let t = BiasTable::sample(100.0, f).unwrap();
        // Bilinear interpolation is exact for a bilinear function, at samples and between them.
        for (zc, za) in [(0.0, 0.0), (10.0, 60.0), (100.0, 34.0), (1.3, 7.7), (55.5, 0.4), (99.9, 99.1)] {
            assert!((t.scale_error(zc, za) - f(zc, za)).abs() < 1e-15, "{zc} {za}");
        }
        assert_eq!(t.scale_error(-5.0, 250.0), t.scale_error(0.0, 100.0));
        // The bounds' floor: between the AUV samples at 0 and 2 m f spans [f(0, 2), f(100, 0)] =
        // [9.4e-4, 3e-3] > 0; at the AUV's 40 m f(0, 40) = −2e-4 and f(100, 40) = 3.4e-3 change sign,
        // so none.
        assert!((t.floor(0.0) - 9.4e-4).abs() < 1e-15 && t.floor(1.0) == t.floor(0.0), "{}", t.floor(0.0));
        assert_eq!(t.floor(40.0), 0.0);
        for za in [0.0, 13.0, 40.0, 77.7, 150.0] {
            let smallest = (0..=1000).map(|i| t.scale_error(i as f64 * 0.1, za).abs()).fold(f64::INFINITY, f64::min);
            assert!(t.floor(za) <= smallest, "{za}: {} > {smallest}", t.floor(za));
        }
        let mut m = biased(Aggregate::TraceSum, vec![0.0], 3.0);
        m.bias = Some(t.clone());
        let (cna, auv) = ([0.0, 0.0, 10.0], [300.0, 400.0, 70.0]);
        let (r2, h2) = (250_000.0 + 3600.0, 250_000.0 / 253_600.0);
        let want = 9e-6 * r2 + f(10.0, 70.0).powi(2) * r2 / h2;
        let got = m.bias_variance(cna, auv);
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
        assert_eq!(m.bias_variance_floor(0.0, r2), (9e-6 + t.floor(0.0) * t.floor(0.0)) * r2);
        let constant = BiasTable::sample(50.0, |_, _| -0.002).unwrap();
        assert_eq!(constant.floor(25.0), 0.002);
        assert!(BiasTable::sample(f64::NAN, f).is_err());
        assert!(BiasTable::sample(10.0, |_, _| f64::INFINITY).unwrap_err().to_string().contains("not finite"));
    }

    #[test]
    fn an_unmodelled_current_grows_the_error_along_it_and_pings_along_it_pay_most() {
        // c = (0.05, 0) m/s, τ = 30 s, m = 4: m·(cτ)² = 9 m² per level on P_ee alone.
        let spec = EstimatorSpec { unmodelled_current: [0.05, 0.0], ..EstimatorSpec::default() };
        let estimates = [AuvEstimate { cov: [4.0, 0.0, 4.0], process_noise: 0.0 }];
        let m = EkfCost::new(spec, &estimates, (30.0, 2.0, 0.0), LinkTable::perfect()).unwrap();
        assert_eq!(m.drift, [9.0, 0.0, 0.0]);
        let still = EkfCost::new(EstimatorSpec::default(), &estimates, (30.0, 2.0, 0.0), LinkTable::perfect()).unwrap();
        let (east, north) = ([500.0, 0.0, 0.0], [0.0, 500.0, 0.0]);
        let cost = |m: &EkfCost, auv| m.update(0, &estimates[0].cov, [0.0; 3], auv).1;
        // Without the current the two lines of sight are alike; with it the ping along the
        // current removes most of the growth (the east range sees P_ee = 13, the north one 4).
        assert!((cost(&still, east) - cost(&still, north)).abs() < 1e-12);
        assert!(cost(&m, east) < cost(&m, north) - 5.0, "{} vs {}", cost(&m, east), cost(&m, north));
        let (p, _) = m.update(0, &estimates[0].cov, [0.0; 3], north);
        assert!((p[0] - 13.0).abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
        let bad = EstimatorSpec { unmodelled_current: [f64::NAN, 0.0], drift_levels: -1.0, ..EstimatorSpec::default() };
        let e = bad.validate("planner.cost.").unwrap_err().to_string();
        assert!(e.contains("planner.cost.unmodelled_current[0] = NaN"), "{e}");
        assert!(e.contains("planner.cost.drift_levels = -1: allowed a finite number >= 0"), "{e}");
    }

    #[test]
    fn the_terminal_cost_is_h_levels_and_settings_are_checked() {
        let spec = EstimatorSpec { terminal_levels: 3.0, ..EstimatorSpec::default() };
        let m = perfect(spec, vec![0.0], NO_REACH);
        assert_eq!(m.terminal_levels(), 3.0);
        assert_eq!(model(Aggregate::TraceSum, vec![0.0], LinkTable::perfect()).terminal_levels(), 0.0);
        for bad in [
            EstimatorSpec { terminal_levels: -1.0, ..EstimatorSpec::default() },
            EstimatorSpec { bias_per_km_m: f64::NAN, ..EstimatorSpec::default() },
        ] {
            let e = bad.validate("planner.cost.").unwrap_err().to_string();
            assert!(e.contains("planner.cost.") && e.contains("allowed a finite number >= 0"), "{e}");
        }
    }

    #[test]
    fn far_auvs_grow_until_the_cna_can_reach_them() {
        // qτ = 2 m², H = 4, s·τ = 60 m, r_u = 500 m. At 620 m: m = 2 levels, ḡ = 2·(2 − 4/8) = 3 m²;
        // at 1400 m: m ≥ H, ḡ = qτ·H/2 = 4 m²; within r_u nothing. Trace sum: term + H·(tr M + 2ḡ).
        let spec = EstimatorSpec { terminal_levels: 4.0, ..EstimatorSpec::default() };
        let m = perfect(spec, vec![2.0], Reach { useful_range_m: 500.0, step_m: 60.0 });
        let start = [4.0, 1.0, 2.0];
        for (east, growth) in [(400.0, 0.0), (620.0, 3.0), (1400.0, 4.0)] {
            let auv = [east, 0.0, 0.0];
            let (p, term) = m.update(0, &start, [0.0; 3], auv);
            let want = term + 4.0 * (p[0] + p[2] + 2.0 * growth);
            let got = m.leaf_term(0, &p, [0.0; 3], auv, term);
            assert!((got - want).abs() < 1e-9 * want, "{east} m: {got} vs {want}");
        }
        // Off (p_u = 0 or H = 0): (1 + H)·term exactly.
        let off = perfect(spec, vec![2.0], NO_REACH);
        let (p, term) = off.update(0, &start, [0.0; 3], [1400.0, 0.0, 0.0]);
        assert_eq!(off.leaf_term(0, &p, [0.0; 3], [1400.0, 0.0, 0.0], term), 5.0 * term);
    }

    #[test]
    fn the_useful_range_is_where_the_link_falls_below_the_threshold() {
        let t = LinkTable::sample(&Linear(4000.0)).unwrap();
        assert!((t.useful_range(0.75) - 1000.0).abs() < 1e-9);
        assert!((t.useful_range(0.5) - 2000.0).abs() < 1e-9);
        assert_eq!(t.useful_range(0.0), f64::INFINITY);
        assert_eq!(LinkTable::perfect().useful_range(1.0), f64::INFINITY);
        let spec = EstimatorSpec { reach_success: 1.5, ..EstimatorSpec::default() };
        let e = spec.validate("planner.cost.").unwrap_err().to_string();
        assert!(e.contains("planner.cost.reach_success"), "{e}");
    }

    #[test]
    fn a_cna_overhead_teaches_nothing_horizontally() {
        let m = model(Aggregate::TraceSum, vec![0.0], LinkTable::perfect());
        let (p, _) = m.update(0, &[4.0, 1.0, 2.0], [10.0, 20.0, 0.0], [10.0, 20.0, 90.0]);
        assert_eq!(p, [4.0, 1.0, 2.0]);
    }

    #[test]
    fn far_pings_are_noisier_and_bad_settings_are_named() {
        let n = RangeNoise::default();
        assert!(n.variance(2000.0) > n.variance(500.0));
        let bad = EstimatorSpec { range_noise: RangeNoise { sigma_m: 0.0, per_km_m: 1.0 }, ..Default::default() };
        let e = bad.validate("planner.cost.").unwrap_err().to_string();
        assert!(e.contains("planner.cost.range_noise.sigma_m = 0: allowed a finite number > 0"), "{e}");
        let e = EkfCost::new(
            EstimatorSpec::default(),
            &[AuvEstimate { cov: [1.0, 2.0, 1.0], process_noise: 0.1 }],
            (10.0, 2.0, 0.0),
            LinkTable::perfect(),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("AUV 0") && e.contains("positive semi-definite"), "{e}");
        let ok = [AuvEstimate { cov: [1.0, 0.0, 1.0], process_noise: 0.1 }];
        let e = EkfCost::new(EstimatorSpec::default(), &ok, (10.0, 2.0, -1.0), LinkTable::perfect()).err().unwrap();
        assert!(e.to_string().contains("the CNA's own horizontal variance -1"), "{e}");
    }

    #[test]
    fn the_best_success_beyond_a_range_bounds_the_link_there() {
        let d = Dipping { plateau: 0.8, mid: 500.0, tail: 0.5 };
        let t = LinkTable::sample(&d).unwrap();
        // The largest interpolated success from `r` on (samples every 5 m: a 2.5 m sweep hits them).
        let sweep = |r: f64| (0..8000).map(|i| t.success(r + i as f64 * 2.5)).fold(0.0, f64::max);
        for r in [0.0, 3.0, 420.0, 777.7, 1500.0, 9000.0, 19_999.0] {
            let (bound, beyond) = (t.best_beyond(r), sweep(r));
            assert!(bound >= beyond, "{r} m: {bound} < {beyond}");
            // No looser than the sample at or below r.
            let below = r - r % LinkTable::STEP_M;
            assert!(bound <= sweep(below) + 1e-12, "{r} m: {bound} above the samples from {below} m");
        }
        // Falling, then the tail rising to its last value, which holds beyond the table.
        assert!(t.best_beyond(0.0) > t.best_beyond(1500.0) && t.best_beyond(1500.0) > d.success(1500.0));
        assert_eq!(t.best_beyond(1e9), t.success(1e9));
        assert_eq!(LinkTable::perfect().best_beyond(123.0), 1.0);
    }

    #[test]
    fn the_link_table_interpolates_and_holds_its_last_value() {
        let t = LinkTable::sample(&Linear(40_000.0)).unwrap();
        assert!((t.success(1234.5) - (1.0 - 1234.5 / 40_000.0)).abs() < 1e-12);
        assert_eq!(t.success(1e9), 0.5);
        struct Broken;
        impl LinkModel for Broken {
            fn success(&self, _: f64) -> f64 {
                1.5
            }
        }
        assert!(LinkTable::sample(&Broken).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// The bound below a node never exceeds the cost of any path below it: the CNA takes
        /// random steps of at most `step` (or, with `circle`, full steps across the line of
        /// sight, turning it as fast as it can) while the AUV moves on a line, and the levels'
        /// costs are compared with `bound_rest` given the same reaches.
        #[test]
        fn the_bound_below_a_node_is_never_above_a_real_path(
            ve in 0.01f64..50.0, vn in 0.01f64..50.0, rho in -0.99f64..0.99, q in 0.0f64..3.0,
            agg in 0usize..4, bias in prop_oneof![Just(0.0), 0.0f64..10.0], cna_variance in prop_oneof![Just(0.0), 0.0f64..60.0],
            reach in prop_oneof![Just(None), (0.0f64..8.0, 0.0f64..900.0).prop_map(Some)], auv0 in (-800.0f64..800.0, -800.0f64..800.0, 0.0f64..150.0),
            vel in (-3.0f64..3.0, -3.0f64..3.0), step in 1.0f64..60.0,
            moves in prop::collection::vec((-3.2f64..3.2, 0.0f64..1.0, -1.0f64..1.0), 1..8), circle in any::<bool>(),
            link in prop_oneof![Just(None), (0.0f64..1.0, 20.0f64..1500.0, 0.0f64..1.0).prop_map(Some)],
            drift in prop_oneof![Just((0.0, 0.0, 0.0)), (-3.0f64..3.0, -3.0f64..3.0, 0.0f64..8.0)],
        ) {
            let aggregate = [Aggregate::TraceSum, Aggregate::WorstAuv, Aggregate::LogDet, Aggregate::SigmaSum][agg];
            let mut m = biased(aggregate, vec![q], bias);
            m.cna_variance = cna_variance;
            let (de, dn, levels) = drift;
            m.drift = [de * de * levels, de * dn * levels, dn * dn * levels];
            if let Some((plateau, mid, tail)) = link {
                m.link = LinkTable::sample(&Dipping { plateau, mid, tail }).unwrap();
            }
            if let Some((h, useful_range_m)) = reach {
                m.spec.terminal_levels = h;
                m.reach = Reach { useful_range_m, step_m: step };
            }
            let p0 = [ve, rho * (ve * vn).sqrt(), vn];
            let mut cna = [0.0, 0.0, 20.0];
            let mut auv = [auv0.0, auv0.1, auv0.2];
            let mut bound = vec![0.0; moves.len()];
            let mut below = Vec::new();
            let mut actual = Vec::new();
            let (node_cna, node_auv) = (cna, auv);
            let mut p = p0;
            for &(heading, frac, dz) in &moves {
                let across = (auv[1] - cna[1]).atan2(auv[0] - cna[0]) + std::f64::consts::FRAC_PI_2;
                let (heading, frac, dz) = if circle { (across + 0.1 * heading, 1.0, 0.0) } else { (heading, frac, dz) };
                let len = step * frac;
                let dz = dz * len;
                let horizontal = (len * len - dz * dz).max(0.0).sqrt();
                cna = [cna[0] + horizontal * heading.cos(), cna[1] + horizontal * heading.sin(), cna[2] + dz];
                auv = [auv[0] + vel.0, auv[1] + vel.1, auv[2]];
                let (turn, spread) = ((vel.0 * vel.0 + vel.1 * vel.1).sqrt() + step, (below.len() + 1) as f64 * step);
                below.push(Below { auv, spread, turn });
                let (next, term) = m.update(0, &p, cna, auv);
                p = next;
                actual.push(term);
            }
            // The leaf's bound slot stands for its term with the cost-to-go over 1 + H (step 7).
            if let Some(last) = actual.last_mut() {
                *last = m.leaf_term(0, &p, cna, auv, *last) / (1.0 + m.spec.terminal_levels);
            }
            m.bound_rest(0, &p0, node_cna, node_auv, below.into_iter(), &mut bound);
            for (j, (b, a)) in bound.iter().zip(&actual).enumerate() {
                prop_assert!(*b <= *a * (1.0 + 1e-9) + 1e-12, "level {}: bound {} above cost {}", j, b, a);
            }
            let floors = m.level_floors(&[p0], moves.len());
            for (j, (f, a)) in floors.iter().zip(&actual).enumerate() {
                prop_assert!(*f <= *a * (1.0 + 1e-9) + 1e-12, "level {}: floor {} above cost {}", j, f, a);
            }
        }
    }
}
