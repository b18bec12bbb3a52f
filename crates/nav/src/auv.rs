//! The survey AUV's EKF (Gill 2013, §2.2.1): the thesis's 5 states [E, N, S, ψ, b] (`AuvEkf`, the
//! default), or 7 with a water current [.., c_E, c_N] (`AuvEkf<7>`, field logs); heading-rate
//! input, speed and compass updates, and OWTT range updates from *any* transponder whose position
//! at transmit time the caller supplies (ship outrigger, buoy, or a CNA that carries its position
//! in its message), optionally with that position's own uncertainty.
//!
//! Three opt-in options against a filter that runs away under range-only geometry (each off by
//! default, the thesis's filter unchanged; docs/models.md#gill-filter-extensions): a Gauss–Markov current
//! ([`CurrentParams::decay`]), the iterated range update ([`IteratedRange`]) and a recovery from
//! a gate lock-out ([`GateRecovery`]).
//!
//! ψ is the direction the vehicle moves through the water and b the compass's offset from it, so
//! b is the heading-bias (crab-angle) state: a vehicle that crabs 8° needs a prior `p0[4]` wide
//! enough to reach 8°. Headings inside are math convention (0 = east, counter-clockwise), so E
//! advances with cos ψ and N with sin ψ; the thesis writes the same model clockwise from north.

use crate::consistency::{sigma_point_range, NisWindow, RangeHealth};
use crate::ekf::{propagate_covariance, wrap_angle, Ekf, Gate, SparseRows, UnitReading, UpdateOutcome};
use crate::range::{RangeMeasurement, RangeNoise};
use coopnav_core::validation::{CheckFields, InvalidFields, Problems};
use coopnav_core::Vec3;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

pub type AuvState = SVector<f64, 5>;
pub const E: usize = 0;
pub const N: usize = 1;
pub const S: usize = 2;
pub const PSI: usize = 3;
pub const BIAS: usize = 4;
/// Water current east and north (m/s), in the 7-state filter only.
pub const CURRENT_E: usize = 5;
pub const CURRENT_N: usize = 6;

/// The current states of the 7-state filter: a random walk (constant when `q` = 0), or a
/// first-order Gauss–Markov process with `correlation_time_s`. Invented parameters (the thesis has
/// no current state, Gill 2013, §2.2.1; for field logs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurrentParams {
    /// The current (east, north, m/s) the team states before the dive, from an ADCP (a CNA's or
    /// the ship's) or the site's tide tables: the filter's initial current and, for a
    /// Gauss–Markov current, the mean it returns to. Default [0, 0]. Written only when set.
    #[serde(skip_serializing_if = "is_still")]
    pub mean: [f64; 2],
    /// Initial variance of each current component ((m/s)²): how well `mean` is known. Default
    /// (0.03 m/s)², an ADCP's average over the site (invented, docs/models.md#current-prior): a
    /// dead-reckoning filter's position spreads by about 110 m an hour from it, where (0.3 m/s)²
    /// spread it by 1.1 km.
    pub p0: f64,
    /// Per-step process noise of each component ((m/s)² per `step_s`). Default (0.03 m/s per
    /// hour)², a tidal current's change (invented, docs/models.md#current-prior).
    pub q: f64,
    /// Whether the ranges estimate the current (false, the default) or only consider it (true):
    /// the Schmidt–Kalman treatment of a weakly observable state, in which a range update leaves
    /// the current's mean and variance at the team's statement and carries its correlation with
    /// the position ([`crate::ekf::Ekf::update_scalar_considering`]). Ranges from one bearing
    /// observe the current along that bearing only, and a filter that estimates it from them can
    /// end worse than one that keeps the stated current (docs/models.md#range-consistency).
    /// Written only when set.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub consider: bool,
    /// Correlation time T (s) of a first-order Gauss–Markov current, ċ = −c/T + w; absent (the
    /// default): a random walk. See [`CurrentParams::decay`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub correlation_time_s: Option<f64>,
}

impl Default for CurrentParams {
    fn default() -> Self {
        let (p0, q) = (0.03 * 0.03, 0.03 * 0.03 / 36_000.0);
        CurrentParams { mean: [0.0, 0.0], p0, q, consider: false, correlation_time_s: None }
    }
}

/// Whether a stated current is zero (the default, left out when written).
fn is_still(mean: &[f64; 2]) -> bool {
    *mean == [0.0, 0.0]
}

impl CurrentParams {
    /// The factor φ = e^(−h/T) by which a Gauss–Markov current's mean decays over an `h`-second
    /// step (None for the random walk).
    ///
    /// Why (an extension of Gill 2013, §2.2.1, which has no current state): a random walk's variance
    /// grows without bound while nothing observes the current, and a range-only fix from a CNA
    /// that stays at one bearing observes it only along that bearing; a filter linearised about
    /// a wrong position then walks the unobserved component anywhere, faster than the vehicle
    /// moves. The Gauss–Markov process c_{k+1} = φ c_k + w_k, Var w_k =
    /// q·h/step_s (the random walk's noise), pulls an unsupported estimate back to zero with time
    /// constant T and holds the variance at q·T/(2·step_s)·(1 + O(h/T)) (from σ² = φ²σ² + q·h/step_s,
    /// 1 − φ² ≈ 2h/T): with q = (0.3 m/s per hour)², T = 1 h holds σ near 0.21 m/s and T = 600 s
    /// near 0.087 m/s; with the default, (0.03 m/s per hour)², a tenth of those. T is invented (docs/models.md#gill-filter-extensions): the
    /// shorter it is, the fewer filters of a spread fleet run away.
    pub fn decay(&self, h: f64) -> Option<f64> {
        self.correlation_time_s.map(|t| (-h / t).exp())
    }
}

impl CheckFields for CurrentParams {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.finite(&format!("{prefix}mean[0]"), self.mean[0]);
        p.finite(&format!("{prefix}mean[1]"), self.mean[1]);
        p.positive(&format!("{prefix}p0"), self.p0);
        p.non_negative(&format!("{prefix}q"), self.q);
        if let Some(t) = self.correlation_time_s {
            p.positive(&format!("{prefix}correlation_time_s"), t);
        }
    }
}

/// The AUV filter's state vector: `{ kind = "thesis" }` (5 states) or `{ kind = "current", p0, q }`
/// (7, with a water current; optionally `correlation_time_s`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AuvModel {
    /// [E, N, S, ψ, b]: the thesis's filter (Gill 2013, §2.2.1).
    #[default]
    Thesis,
    /// [E, N, S, ψ, b, c_E, c_N]: with a water current (field logs).
    Current(CurrentParams),
}

impl CheckFields for AuvModel {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let AuvModel::Current(c) = self {
            c.check_fields(prefix, p);
        }
    }
}

/// Coefficients of the AUV filter. Variances are per *nominal step* `step_s` (Gill 2013, App. A:
/// Q is added once per predict); a prediction over h seconds adds Q·h/step_s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuvParams {
    /// Nominal filter step Δt (s) the Q values refer to. Invented: 0.1 s (docs/models.md#gill-coefficients).
    pub step_s: f64,
    /// Initial variances [E m², N m², S (m/s)², ψ rad², b rad²]. Invented: docs/models.md#gill-coefficients.
    pub p0: [f64; 5],
    /// Per-step process noise. Q_E = Q_N = 0.255448 is Gill 2013, Table 3; S, ψ, b invented
    /// (docs/models.md#gill-coefficients).
    pub q: [f64; 5],
    /// Speed-measurement SD (m/s). Invented: docs/models.md#gill-coefficients.
    pub sigma_speed: f64,
    /// Compass SD (rad). Invented: 0.5° (docs/models.md#gill-coefficients).
    pub sigma_heading: f64,
    pub range_noise: RangeNoise,
    pub range_gate: Gate,
    /// How a range updates the state: `{ kind = "ekf" }` (the default, the thesis's one
    /// linearisation) or `{ kind = "iterated", iterations, tolerance_m }` ([`IteratedRange`]).
    #[serde(skip_serializing_if = "RangeLinearisation::is_ekf")]
    pub range_update: RangeLinearisation,
    /// What the filter does after `range_gate` has rejected several ranges in a row; absent (the
    /// default): nothing, every range is judged by the gate alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range_gate_recovery: Option<GateRecovery>,
    /// Long outliers the filter expects among its ranges ([`RangeOutliers`]); absent (the
    /// default): every range is Gaussian, as in the thesis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range_outliers: Option<RangeOutliers>,
    /// The windowed NIS check that detects a filter which has left its bounds and recovers it
    /// ([`RangeHealth`]); absent (the default): no check, as in the thesis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range_health: Option<RangeHealth>,
    /// The water current (east, north, m/s) the team states before the dive (an ADCP, the
    /// site's tide tables), in which the thesis's 5-state filter dead-reckons as a known drift
    /// without estimating it: each step moves the position by the current times the step, the
    /// Jacobian unchanged. Default [0, 0], still water (the thesis's filter, Gill 2013, §2.2.1).
    /// The 7-state filter states its current as `model.mean` and ignores this field.
    /// Why: a filter dead-reckoning in a current it neither models nor is told of drifts by the
    /// current times the time since its last fix, which no random-walk process noise can match
    /// both in a still sea and in a current (docs/models.md#stated-current). Written only when set.
    #[serde(skip_serializing_if = "is_still")]
    pub stated_current: [f64; 2],
}

/// Long ranges the filter expects besides its Gaussian noise, an extension of Gill 2013, §2.2.1
/// (the thesis's filter has no outlier rejection, while its simulation makes 5 % of ranges 5–10 m
/// too long and drops 10 %, Gill 2013, §2.4.1; the closed loop's `gill_mixture` channel draws
/// 5.55 % of the ranges received).
///
/// A range is an inlier, innovation y ~ N(0, S), with probability 1 − p, or an outlier, y = e + v
/// with e ~ U(min_m, max_m) and v ~ N(0, S), with probability p. Its inlier probability is
/// w = (1 − p)·N(y; 0, S) / [(1 − p)·N(y; 0, S) + p·(Φ((y − min)/√S) − Φ((y − max)/√S))/(max − min)],
/// and an outlier is taken to carry no information (its 5 m spread is wider than the position σ it
/// would inform). How w enters the update is [`OutlierUpdate`]. Why: a filter that takes a 5–10 m
/// outlier as Gaussian moves its estimate most of the way to it, and from a steady line of sight
/// the next pings do not undo it. The class figures are the thesis's; using them in the filter is
/// invented (docs/models.md#gill-filter-extensions).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeOutliers {
    /// Probability p that a range is an outlier (0 ≤ p < 1).
    pub probability: f64,
    /// How much longer than the true range an outlier is, at least and at most (m; min < max).
    pub min_m: f64,
    pub max_m: f64,
    /// How the inlier probability enters the update (default: weighted).
    #[serde(default)]
    pub update: OutlierUpdate,
}

/// How a range's inlier probability w ([`RangeOutliers`]) enters the Kalman update, K = P⁻hᵀ/S.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutlierUpdate {
    /// The Kalman update with the range variance R raised to R + (1/w − 1)·S: x⁺ = x⁻ + w·K·y,
    /// P⁺ = P⁻ − w·K·S·Kᵀ, the robust Kalman filters' reweighting with the mixture's weight. The
    /// default: it did better than [`OutlierUpdate::Pda`] in the closed loop (below).
    #[default]
    Weighted,
    /// The probabilistic-data-association update: the weighted one plus the hypotheses' spread
    /// w(1 − w)·(K·y)(K·y)ᵀ as process noise, which moment-matches the two posteriors. A CNA
    /// parked over an AUV's estimate, whose ranges are all long as an outlier is, sees the spread
    /// inflate P along a move the linearisation gets wrong there, and the error grows.
    Pda,
}

impl RangeOutliers {
    /// Gill's simulated outliers as the closed loop's channel draws them: 5.55 % of ranges, 5–10 m long.
    pub const GILL: RangeOutliers =
        RangeOutliers { probability: 0.0555, min_m: 5.0, max_m: 10.0, update: OutlierUpdate::Weighted };

    /// The probability w that a range with innovation `y` (m) is an inlier, its inlier
    /// innovation variance being `s` (m²).
    pub fn inlier_probability(&self, y: f64, s: f64) -> f64 {
        let sd = s.sqrt();
        let inlier = (1.0 - self.probability) * (-0.5 * y * y / s).exp() / (sd * (2.0 * std::f64::consts::PI).sqrt());
        let below = |v: f64| 0.5 * libm::erfc(-v / (sd * std::f64::consts::SQRT_2));
        let outlier = self.probability * (below(y - self.min_m) - below(y - self.max_m)) / (self.max_m - self.min_m);
        let w = inlier / (inlier + outlier);
        if w.is_finite() {
            w
        } else {
            // Both densities underflowed: y is far from the inliers and the outliers alike.
            0.0
        }
    }
}

impl CheckFields for RangeOutliers {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if !(0.0..1.0).contains(&self.probability) {
            p.push(format!("{prefix}probability"), self.probability.to_string(), "a probability in [0, 1)");
        }
        p.finite(&format!("{prefix}min_m"), self.min_m);
        if !(self.max_m > self.min_m && self.max_m.is_finite()) {
            p.push(format!("{prefix}max_m"), self.max_m.to_string(), "a finite length above min_m");
        }
    }
}

/// Below this inlier probability a range expected to be an outlier is refused outright: its
/// raised variance would be S/w, beyond any use (and past f64 as w → 0).
const OUTLIER_ONLY: f64 = 1e-9;

/// Recovery from a gate lock-out (invented; the thesis has no gate, docs/models.md#gill-filter-extensions).
///
/// A gate protects a consistent filter from outliers, but a filter that has become
/// over-confident (linearised about a wrong estimate, its σ well under its true error) rejects
/// every good range that follows and dead-reckons on. After `after` consecutive rejections the next
/// rejected range is taken as evidence that the filter, not the range, is wrong: the horizontal
/// position covariance is inflated isotropically by a = (y²/ν − S)/‖h_EN‖², the smallest addition
/// that makes that range's NIS y²/(S + a‖h_EN‖²) equal `target_nis` ν, and the range is then
/// applied. With independent outliers at rate p (Gill's mixture: 5.6 %), `after` = 3 mistakes
/// an outlier run for a lock-out with probability about p³ = 1.7·10⁻⁴ per range. Invented
/// parameters. It ends the lock-outs of a spread fleet, but with a CNA parked over one AUV it can
/// let a filter run away that the gate alone held: the inflated covariance accepts a range
/// linearised about a wrong bearing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GateRecovery {
    /// Consecutive rejected ranges that trigger the inflation (≥ 1). Default 3.
    pub after: u32,
    /// The NIS the inflated covariance gives the triggering range (> 0). Default 1.
    pub target_nis: f64,
}

impl Default for GateRecovery {
    fn default() -> Self {
        GateRecovery { after: 3, target_nis: 1.0 }
    }
}

impl CheckFields for GateRecovery {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if self.after == 0 {
            p.push(format!("{prefix}after"), "0", "a whole number >= 1");
        }
        p.positive(&format!("{prefix}target_nis"), self.target_nis);
    }
}

/// The linearisation of the range update (eq. 9).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RangeLinearisation {
    /// One linearisation about the prior: the thesis's EKF (Gill 2013, §2.2.1).
    #[default]
    Ekf,
    /// The iterated EKF: relinearised about the updated estimate ([`IteratedRange`]).
    Iterated(IteratedRange),
    /// The sigma-point (unscented) update over the position prior
    /// ([`crate::consistency::sigma_point_range`]): the range's mean, regression row and the
    /// variance its curvature adds are taken over the prior's spread, not at its mean, so a wide
    /// prior or a transponder overhead does not make the filter over-confident
    /// (docs/models.md#range-consistency).
    Unscented,
}

impl RangeLinearisation {
    pub fn is_ekf(&self) -> bool {
        *self == RangeLinearisation::Ekf
    }
}

/// The iterated EKF range update (Gauss–Newton on the update's cost), an extension of Gill 2013,
/// §2.2.1 (the thesis linearises once).
///
/// The EKF linearises r = ‖p − p_T‖ about the prior p⁻; when p⁻ is tens of metres off at a
/// range of a few hundred, the gradient (the unit vector to the transponder) points along a
/// wrong bearing, and the update moves the estimate along that bearing and shrinks P across the
/// true one, so the filter ends far off and over-confident. The update
/// is the minimiser of J(x) = ‖x − x⁻‖²_{P⁻¹} + (z − h(x))²/R; Gauss–Newton from x₀ = x⁻ gives
/// x_{i+1} = x⁻ + K_i (z − h(x_i) − H_i (x⁻ − x_i)), K_i = P⁻H_iᵀ (H_i P⁻ H_iᵀ + R_i)⁻¹, with
/// H_i (and R_i, whose transponder term depends on the line of sight) evaluated at x_i; the
/// covariance is the Joseph update of P⁻ with the last K_i and H_i (Bell & Cathey 1993). One
/// iteration is the EKF exactly. The gate tests the prior's innovation, as the EKF's does.
/// Invented parameters (docs/models.md#gill-filter-extensions): `iterations` and `tolerance_m`.
/// It keeps a filter from running away under a parked CNA; it does not make the filter
/// consistent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IteratedRange {
    /// At most this many linearisations (≥ 1; 1 is the EKF). Default 5.
    pub iterations: u32,
    /// Stop once an iteration moves the horizontal estimate less than this (m). Default 0.01 m.
    pub tolerance_m: f64,
}

impl Default for IteratedRange {
    fn default() -> Self {
        IteratedRange { iterations: 5, tolerance_m: 0.01 }
    }
}

impl CheckFields for RangeLinearisation {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let RangeLinearisation::Iterated(it) = self {
            if it.iterations == 0 {
                p.push(format!("{prefix}iterations"), "0", "a whole number >= 1 (1 is the EKF)");
            }
            p.non_negative(&format!("{prefix}tolerance_m"), it.tolerance_m);
        }
    }
}

impl Default for AuvParams {
    fn default() -> Self {
        let deg = std::f64::consts::PI / 180.0;
        AuvParams {
            step_s: 0.1,
            p0: [16.0, 16.0, 0.0025, 0.01, (0.5 * deg).powi(2)],
            q: [0.255448, 0.255448, 1e-4, (0.2 * deg).powi(2), (0.01 * deg).powi(2)],
            sigma_speed: 0.05,
            sigma_heading: 0.5 * deg,
            range_noise: RangeNoise::default(),
            range_gate: Gate::OFF,
            range_update: RangeLinearisation::Ekf,
            range_gate_recovery: None,
            range_outliers: None,
            range_health: None,
            stated_current: [0.0, 0.0],
        }
    }
}

/// Bad filter coefficients: every bad field, named with its prefix.
pub type ParamError = InvalidFields;

/// Checks every coefficient; each problem names the field (prefixed by `prefix`).
impl CheckFields for AuvParams {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.positive(&format!("{prefix}step_s"), self.step_s);
        for (i, v) in self.p0.iter().enumerate() {
            p.positive(&format!("{prefix}p0[{i}]"), *v);
        }
        for (i, v) in self.q.iter().enumerate() {
            p.non_negative(&format!("{prefix}q[{i}]"), *v);
        }
        p.positive(&format!("{prefix}sigma_speed"), self.sigma_speed);
        p.positive(&format!("{prefix}sigma_heading"), self.sigma_heading);
        self.range_noise.check_fields(&format!("{prefix}range_noise."), p);
        self.range_gate.check_fields(&format!("{prefix}range_gate."), p);
        self.range_update.check_fields(&format!("{prefix}range_update."), p);
        if let Some(r) = &self.range_gate_recovery {
            r.check_fields(&format!("{prefix}range_gate_recovery."), p);
        }
        if let Some(o) = &self.range_outliers {
            o.check_fields(&format!("{prefix}range_outliers."), p);
        }
        if let Some(h) = &self.range_health {
            h.check_fields(&format!("{prefix}range_health."), p);
        }
        p.finite(&format!("{prefix}stated_current[0]"), self.stated_current[0]);
        p.finite(&format!("{prefix}stated_current[1]"), self.stated_current[1]);
    }
}

/// Dead reckoning over `h` seconds with the heading changing by `turn` rad (eq. 7, Euler step),
/// plus the drift of the current states when there are 7: the mean map the EKF linearises and the
/// unscented smoother pushes sigma points through.
pub fn transition<const M: usize>(x: &SVector<f64, M>, h: f64, turn: f64) -> SVector<f64, M> {
    transition_at(x, h, turn, x[PSI].sin_cos())
}

/// [`transition`] with (sin ψ, cos ψ) of `x` already computed (the filter's step shares them
/// with its Jacobian).
#[inline(always)]
fn transition_at<const M: usize>(x: &SVector<f64, M>, h: f64, turn: f64, (sin, cos): (f64, f64)) -> SVector<f64, M> {
    let mut next = *x;
    next[E] += h * x[S] * cos;
    next[N] += h * x[S] * sin;
    if M > CURRENT_N {
        next[E] += h * x[CURRENT_E];
        next[N] += h * x[CURRENT_N];
    }
    next[PSI] = wrap_angle(x[PSI] + turn);
    next
}

/// ∂transition/∂x at `x` (Gill 2013, §2.2.1, F^A).
pub fn transition_jacobian<const M: usize>(x: &SVector<f64, M>, h: f64) -> SMatrix<f64, M, M> {
    let mut f = SMatrix::<f64, M, M>::identity();
    for (i, entries) in transition_jacobian_entries(x, h, x[PSI].sin_cos()) {
        entries.iter().for_each(|&(j, v)| f[(i, j)] += v);
    }
    f
}

/// The non-identity entries of [`transition_jacobian`], by row: E and N, each with its entries
/// (column, value) at S and ψ, and at its current state when there are 7 (zero-valued at itself
/// when `M` = 5, so the rows have one length); (sin ψ, cos ψ) of `x` given.
#[inline(always)]
fn transition_jacobian_entries<const M: usize>(
    x: &SVector<f64, M>,
    h: f64,
    (sin, cos): (f64, f64),
) -> SparseRows<2, 3> {
    let drift = if M > CURRENT_N { h } else { 0.0 };
    let (ce, cn) = if M > CURRENT_N { (CURRENT_E, CURRENT_N) } else { (E, N) };
    [(E, [(S, h * cos), (PSI, -h * x[S] * sin), (ce, drift)]), (N, [(S, h * sin), (PSI, h * x[S] * cos), (cn, drift)])]
}

/// A step's mean `x_new` and Jacobian rows `g` with a Gauss–Markov current decaying by `phi`
/// over the step: c ← φ c (the position drift used the current at the start of the step), and
/// the current states' rows, φ − 1 on their diagonal, added to G (F = I + G). 7-state filter
/// only. The new rows carry two zero entries each, so every row has the position rows' length.
fn decayed<const M: usize>(
    x_new: SVector<f64, M>,
    g: SparseRows<2, 3>,
    phi: f64,
    mean: [f64; 2],
) -> (SVector<f64, M>, SparseRows<4, 3>) {
    let [e, n] = g;
    let decay = |c| (c, [(c, phi - 1.0), (c, 0.0), (c, 0.0)]);
    (decayed_mean(x_new, phi, mean), [e, n, decay(CURRENT_E), decay(CURRENT_N)])
}

/// The current states of `x` decayed by `phi` towards the stated `mean`: c ← m + φ (c − m)
/// (exactly φ c for the default, still water).
fn decayed_mean<const M: usize>(mut x: SVector<f64, M>, phi: f64, mean: [f64; 2]) -> SVector<f64, M> {
    x[CURRENT_E] = mean[0] + (x[CURRENT_E] - mean[0]) * phi;
    x[CURRENT_N] = mean[1] + (x[CURRENT_N] - mean[1]) * phi;
    x
}

/// The frame of a logged velocity over ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityFrame {
    /// (forward, starboard) in the vehicle's frame.
    Body,
    /// (east, north).
    Earth,
}

/// A range update's outcome with its innovation (m) and innovation variance S (m²), the terms
/// of the innovation likelihood.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeUpdate {
    pub outcome: UpdateOutcome,
    pub innovation: f64,
    pub variance: f64,
}

impl RangeUpdate {
    /// A range with no line of sight (directly overhead in 2-D): nothing to update.
    const UNUSABLE: RangeUpdate =
        RangeUpdate { outcome: UpdateOutcome::Unusable, innovation: f64::NAN, variance: f64::NAN };
}

/// The AUV navigation filter with `M` = 5 (thesis) or 7 (with current) states.
#[derive(Debug, Clone)]
pub struct AuvEkf<const M: usize = 5> {
    ekf: Ekf<M>,
    params: AuvParams,
    /// The current states' parameters (None when `M` = 5).
    current: Option<CurrentParams>,
    /// Ranges rejected by the gate since the last one applied ([`GateRecovery`]).
    gated_in_row: u32,
    /// The last ranges' NIS ([`RangeHealth`]).
    nis_window: NisWindow,
    /// The recoveries [`RangeHealth`] made.
    recoveries: Recoveries,
}

/// How often a filter's [`RangeHealth`] check found it out of its bounds and recovered it, and
/// when first and last (filter time, s).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Recoveries {
    pub count: u32,
    pub first_s: Option<f64>,
    pub last_s: Option<f64>,
}

impl AuvEkf<5> {
    /// Starts at time `t0` from position (e, n), speed, math heading ψ and zero compass bias.
    pub fn new(t0: f64, e: f64, n: f64, speed: f64, psi: f64, params: AuvParams) -> Self {
        let x0 = AuvState::from([e, n, speed, psi, 0.0]);
        let p0 = SMatrix::<f64, 5, 5>::from_diagonal(&SVector::from(params.p0));
        let ekf = Ekf::new(t0, x0, p0, [false, false, false, true, true]);
        AuvEkf {
            ekf,
            params,
            current: None,
            gated_in_row: 0,
            nis_window: NisWindow::default(),
            recoveries: Recoveries::default(),
        }
    }
}

impl AuvEkf<7> {
    /// The 7-state filter: as [`AuvEkf::new`], with zero current of prior variance `current.p0`.
    pub fn with_current(
        t0: f64,
        e: f64,
        n: f64,
        speed: f64,
        psi: f64,
        params: AuvParams,
        current: CurrentParams,
    ) -> Self {
        let [ce, cn] = current.mean;
        let x0 = SVector::<f64, 7>::from([e, n, speed, psi, 0.0, ce, cn]);
        let [pe, pn, ps, ppsi, pb] = params.p0;
        let p0 = SMatrix::<f64, 7, 7>::from_diagonal(&SVector::from([pe, pn, ps, ppsi, pb, current.p0, current.p0]));
        let angles = [false, false, false, true, true, false, false];
        let ekf = Ekf::new(t0, x0, p0, angles);
        let (nis_window, recoveries) = (NisWindow::default(), Recoveries::default());
        AuvEkf { ekf, params, current: Some(current), gated_in_row: 0, nis_window, recoveries }
    }
}

impl<const M: usize> AuvEkf<M> {
    pub fn ekf(&self) -> &Ekf<M> {
        &self.ekf
    }
    pub fn ekf_mut(&mut self) -> &mut Ekf<M> {
        &mut self.ekf
    }
    pub fn params(&self) -> &AuvParams {
        &self.params
    }
    pub fn state(&self) -> &SVector<f64, M> {
        self.ekf.x()
    }
    pub fn position(&self) -> (f64, f64) {
        (self.ekf.x()[E], self.ekf.x()[N])
    }
    /// A range's scalar update, the Schmidt–Kalman one when the current is only considered
    /// ([`CurrentParams::consider`]).
    fn range_scalar(&mut self, innovation: f64, h: SMatrix<f64, 1, M>, r: f64, gate: &Gate) -> UpdateOutcome {
        match self.current {
            Some(c) if c.consider => {
                let considered = std::array::from_fn(|i| i == CURRENT_E || i == CURRENT_N);
                self.ekf.update_scalar_considering(innovation, h, r, gate, &considered)
            }
            _ => self.ekf.update_scalar(innovation, h, r, gate),
        }
    }

    /// The recoveries its [`RangeHealth`] check made.
    pub fn recoveries(&self) -> Recoveries {
        self.recoveries
    }

    /// Dead-reckons to time `t` with the measured heading rate `yaw_rate` (rad/s, math sense)
    /// held over the interval (eq. 7). Does nothing if `t` is not after the filter time.
    #[inline(always)]
    pub fn predict_to(&mut self, t: f64, yaw_rate: f64) -> bool {
        let h = t - self.ekf.t();
        if !(h > 0.0) {
            return false;
        }
        let (x_new, g, q) = self.step_model(h, yaw_rate);
        match self.current_decay(h) {
            None => self.ekf.predict_sparse(t, x_new, &g, &q),
            Some(phi) => {
                let (x_new, g) = decayed(x_new, g, phi, self.stated_current());
                self.ekf.predict_sparse(t, x_new, &g, &q)
            }
        }
    }

    /// One filter-rate step: [`Self::predict_to`] `t`, then [`Self::update_speed`] with `speed`
    /// and [`Self::update_heading`] with `heading`, bit for bit, run as one
    /// ([`Ekf::predict_and_read`]). Returns whether it predicted and the two updates' outcomes.
    #[inline(always)]
    pub fn dead_reckoning_step(
        &mut self,
        t: f64,
        yaw_rate: f64,
        speed: f64,
        heading: f64,
    ) -> (bool, [UpdateOutcome; 2]) {
        let speed = speed_reading(speed, self.params.sigma_speed);
        let compass = compass_reading(heading, self.params.sigma_heading);
        let h = t - self.ekf.t();
        if !(h > 0.0) {
            return (false, [self.ekf.update_reading(&speed), self.ekf.update_reading(&compass)]);
        }
        let (x_new, g, q) = self.step_model(h, yaw_rate);
        match self.current_decay(h) {
            None => self.ekf.predict_and_read(t, x_new, &g, &q, &speed, &compass),
            Some(phi) => {
                let (x_new, g) = decayed(x_new, g, phi, self.stated_current());
                self.ekf.predict_and_read(t, x_new, &g, &q, &speed, &compass)
            }
        }
    }

    /// The mean, the Jacobian's rows and the process noise of an `h`-second step at heading rate
    /// `yaw_rate`, before a Gauss–Markov current's decay.
    #[inline(always)]
    fn step_model(&self, h: f64, yaw_rate: f64) -> (SVector<f64, M>, SparseRows<2, 3>, SVector<f64, M>) {
        let x = *self.ekf.x();
        let sin_cos = x[PSI].sin_cos();
        let x_new = self.drifted(transition_at(&x, h, h * yaw_rate, sin_cos), h);
        (x_new, transition_jacobian_entries(&x, h, sin_cos), self.step_q(h))
    }

    /// `x_new` moved by the stated current over `h` seconds ([`AuvParams::stated_current`]): the
    /// thesis's states only, and only when a current is stated (else `x_new` unchanged, bit for bit).
    #[inline(always)]
    fn drifted(&self, mut x_new: SVector<f64, M>, h: f64) -> SVector<f64, M> {
        let [ce, cn] = self.params.stated_current;
        if M <= CURRENT_N && (ce != 0.0 || cn != 0.0) {
            x_new[E] += h * ce;
            x_new[N] += h * cn;
        }
        x_new
    }

    /// The Gauss–Markov current's decay over `h` seconds ([`CurrentParams::decay`]); None for
    /// the thesis's states and for a random-walk current.
    #[inline(always)]
    fn current_decay(&self, h: f64) -> Option<f64> {
        self.current.and_then(|c| c.decay(h))
    }

    /// The current the team stated ([`CurrentParams::mean`]); zero for the thesis's states.
    #[inline(always)]
    fn stated_current(&self) -> [f64; 2] {
        self.current.map_or([0.0, 0.0], |c| c.mean)
    }

    /// The mean map of a step from `x` over `h` seconds at heading rate `yaw_rate`: [`transition`]
    /// with the Gauss–Markov current's decay (the unscented smoother pushes sigma points through it).
    pub fn mean_step(&self, x: &SVector<f64, M>, h: f64, yaw_rate: f64) -> SVector<f64, M> {
        let x_new = self.drifted(transition(x, h, h * yaw_rate), h);
        self.current_decay(h).map_or(x_new, |phi| decayed_mean(x_new, phi, self.stated_current()))
    }

    /// The prediction from `x` over `h` seconds at heading rate `yaw_rate`: the propagated mean,
    /// the Jacobian F and the process noise Q, as the forward pass uses them (its covariance step
    /// is [`Self::prior_covariance`]).
    pub fn prediction(
        &self,
        x: &SVector<f64, M>,
        h: f64,
        yaw_rate: f64,
    ) -> (SVector<f64, M>, SMatrix<f64, M, M>, SMatrix<f64, M, M>) {
        let q = SMatrix::<f64, M, M>::from_diagonal(&self.step_q(h));
        let mut f = transition_jacobian(x, h);
        if let Some(phi) = self.current_decay(h) {
            f[(CURRENT_E, CURRENT_E)] = phi;
            f[(CURRENT_N, CURRENT_N)] = phi;
        }
        (self.mean_step(x, h, yaw_rate), f, q)
    }

    /// The prior covariance of the step from the filtered (`x`, `p`) over `h` seconds: the same
    /// sparse arithmetic as [`Self::predict_to`], so a smoother that stores only filtered states
    /// recomputes each prior bit for bit.
    pub fn prior_covariance(&self, x: &SVector<f64, M>, p: &SMatrix<f64, M, M>, h: f64) -> SMatrix<f64, M, M> {
        let mut p = *p;
        let g = transition_jacobian_entries(x, h, x[PSI].sin_cos());
        match self.current_decay(h) {
            None => propagate_covariance(&mut p, &g, &self.step_q(h)),
            Some(phi) => propagate_covariance(&mut p, &decayed(*x, g, phi, self.stated_current()).1, &self.step_q(h)),
        }
        p
    }

    /// The process noise of an `h`-second step, per state (Q is given per nominal step).
    #[inline(always)]
    fn step_q(&self, h: f64) -> SVector<f64, M> {
        let scale = h / self.params.step_s;
        // The states after the thesis's five are the current's, with its per-step noise.
        let extra_q = self.current.map_or(0.0, |c| c.q);
        SVector::<f64, M>::from_fn(|i, _| self.params.q.get(i).copied().unwrap_or(extra_q) * scale)
    }

    /// Speed-sensor update (m/s).
    #[inline(always)]
    pub fn update_speed(&mut self, measured: f64) -> UpdateOutcome {
        self.update_speed_sd(measured, self.params.sigma_speed)
    }

    /// Speed update with its own SD (m/s), e.g. from a log row.
    #[inline(always)]
    pub fn update_speed_sd(&mut self, measured: f64, sd: f64) -> UpdateOutcome {
        self.ekf.update_reading(&speed_reading(measured, sd))
    }

    /// Compass update: the compass reads ψ + b (math convention, rad).
    #[inline(always)]
    pub fn update_heading(&mut self, measured: f64) -> UpdateOutcome {
        self.update_heading_sd(measured, self.params.sigma_heading)
    }

    /// Compass update with its own SD (rad).
    #[inline(always)]
    pub fn update_heading_sd(&mut self, measured: f64, sd: f64) -> UpdateOutcome {
        self.ekf.update_reading(&compass_reading(measured, sd))
    }

    /// Position fix of the vehicle itself (GPS at the surface), SD `sd` m on each axis.
    pub fn update_position(&mut self, e: f64, n: f64, sd: f64) -> UpdateOutcome {
        let mut h = SMatrix::<f64, 2, M>::zeros();
        h[(0, E)] = 1.0;
        h[(1, N)] = 1.0;
        let x = self.ekf.x();
        let y = nalgebra::Vector2::new(e - x[E], n - x[N]);
        self.ekf.update(y, h, nalgebra::Matrix2::identity() * (sd * sd), &Gate::OFF)
    }

    /// Velocity over ground (a DVL in bottom lock), SD `sd` m/s per component. Over ground the
    /// vehicle moves at S(cos ψ, sin ψ) through the water plus the current (7 states); the body
    /// frame turns that by the compass heading θ = ψ + b: forward = v·(cos θ, sin θ), starboard =
    /// v·(sin θ, −cos θ) (math convention, starboard is to the right).
    pub fn update_velocity(&mut self, frame: VelocityFrame, measured: [f64; 2], sd: f64) -> UpdateOutcome {
        let x = self.ekf.x();
        let (sin, cos) = x[PSI].sin_cos();
        // Earth-frame velocity and its Jacobian rows.
        let mut ve = x[S] * cos;
        let mut vn = x[S] * sin;
        let (mut je, mut jn) = (SMatrix::<f64, 1, M>::zeros(), SMatrix::<f64, 1, M>::zeros());
        (je[S], je[PSI], jn[S], jn[PSI]) = (cos, -x[S] * sin, sin, x[S] * cos);
        if M > CURRENT_N {
            ve += x[CURRENT_E];
            vn += x[CURRENT_N];
            (je[CURRENT_E], jn[CURRENT_N]) = (1.0, 1.0);
        }
        let (predicted, h) = match frame {
            VelocityFrame::Earth => ([ve, vn], [je, jn]),
            VelocityFrame::Body => {
                let (st, ct) = (x[PSI] + x[BIAS]).sin_cos();
                let (fwd, stbd) = (ve * ct + vn * st, ve * st - vn * ct);
                let (mut jf, mut js) = (je * ct + jn * st, je * st - jn * ct);
                // Both rotate with θ = ψ + b.
                for i in [PSI, BIAS] {
                    jf[i] += -ve * st + vn * ct;
                    js[i] += ve * ct + vn * st;
                }
                ([fwd, stbd], [jf, js])
            }
        };
        let mut hm = SMatrix::<f64, 2, M>::zeros();
        hm.set_row(0, &h[0]);
        hm.set_row(1, &h[1]);
        let y = nalgebra::Vector2::new(measured[0] - predicted[0], measured[1] - predicted[1]);
        self.ekf.update(y, hm, nalgebra::Matrix2::identity() * (sd * sd), &Gate::OFF)
    }

    /// OWTT range update (eq. 9). `auv_depth` = Some(z) uses the 3-D slant range to the
    /// transponder's depth (field mode); None the horizontal range (simulation mode, Gill 2013,
    /// §2.4.1: depth treated as constant).
    pub fn update_range(&mut self, m: &RangeMeasurement, auv_depth: Option<f64>) -> UpdateOutcome {
        self.update_range_from_uncertain(m, auv_depth, 0.0)
    }

    /// As [`Self::update_range`], with the transponder's horizontal position uncertain by
    /// `transponder_sd` (m, each axis): its variance along the line of sight is added to the range
    /// noise (the position error projects onto the range through the same unit vector).
    pub fn update_range_from_uncertain(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        transponder_sd: f64,
    ) -> UpdateOutcome {
        let range_variance = self.params.range_noise.variance(m.travel_time);
        let gate = self.params.range_gate;
        if let Some(up) = self.health_check(m, auv_depth, range_variance, transponder_sd) {
            self.gated_in_row = 0;
            return up.outcome;
        }
        let up = match self.params.range_outliers {
            None => self.update_range_unchecked(m, auv_depth, range_variance, transponder_sd, &gate),
            Some(outliers) => {
                self.update_range_expecting(outliers, m, auv_depth, range_variance, transponder_sd, &gate)
            }
        };
        let Some(recovery) = self.params.range_gate_recovery else { return up.outcome };
        if !matches!(up.outcome, UpdateOutcome::Gated { .. }) {
            self.gated_in_row = 0;
            return up.outcome;
        }
        self.gated_in_row += 1;
        if self.gated_in_row < recovery.after {
            return up.outcome;
        }
        self.gated_in_row = 0;
        self.inflate_position(&up, &m.transponder, auv_depth, recovery);
        self.update_range_unchecked(m, auv_depth, range_variance, transponder_sd, &Gate::OFF).outcome
    }

    /// The [`RangeHealth`] check of a range about to be applied: its innovation and variance (as
    /// the filter's update kind predicts them) join the window; when the window leaves its bound
    /// the filter recovers ([`Self::recover`]) and applies the range without the gate, which is
    /// returned. None (nothing done yet) without a check or inside the bound.
    fn health_check(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
    ) -> Option<RangeUpdate> {
        let health = self.params.range_health?;
        let (y, s) = self.predicted_innovation(m, auv_depth, range_variance, transponder_sd)?;
        let added = self.nis_window.push(&health, y, s)?;
        self.recover(added);
        Some(self.update_range_unchecked(m, auv_depth, range_variance, transponder_sd, &Gate::OFF))
    }

    /// A range's innovation and its variance as the update kind predicts them: at the prior mean
    /// (EKF, iterated) or over its sigma points (unscented). None when it is unusable.
    fn predicted_innovation(
        &self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
    ) -> Option<(f64, f64)> {
        match self.params.range_update {
            RangeLinearisation::Unscented => {
                let (h, r, _) = self.sigma_prior(m, auv_depth, range_variance, transponder_sd)?;
                let (y, s) = (r.0, (h * self.ekf.p() * h.transpose())[(0, 0)] + r.1);
                Some((y, s))
            }
            _ => {
                let (_, _, prior) = self.range_prior(m, auv_depth, range_variance, transponder_sd)?;
                Some((prior.value, prior.variance))
            }
        }
    }

    /// Recovery from a filter out of its bounds ([`RangeHealth`]): `added` m² on each horizontal
    /// position variance and the current states' variances raised to their prior, as process
    /// noise at the filter's time (the smoother sees it as a step).
    fn recover(&mut self, added: f64) {
        let mut q = SVector::<f64, M>::zeros();
        (q[E], q[N]) = (added, added);
        if let (Some(c), true) = (self.current, M > CURRENT_N) {
            let p = self.ekf.p();
            (q[CURRENT_E], q[CURRENT_N]) =
                ((c.p0 - p[(CURRENT_E, CURRENT_E)]).max(0.0), (c.p0 - p[(CURRENT_N, CURRENT_N)]).max(0.0));
        }
        let (t, x) = (self.ekf.t(), *self.ekf.x());
        let no_transition: SparseRows<0, 1> = [];
        self.ekf.predict_sparse(t, x, &no_transition, &q);
        let r = &mut self.recoveries;
        r.count += 1;
        r.first_s.get_or_insert(t);
        r.last_s = Some(t);
    }

    /// The range update of a filter that expects `outliers` ([`RangeOutliers`]): the Kalman update
    /// with the range variance raised by (1/w − 1)·S, then for [`OutlierUpdate::Pda`] the spread
    /// w(1 − w)·(K·y)(K·y)ᵀ as process noise. A range with w below `OUTLIER_ONLY` is refused as
    /// [`UpdateOutcome::Gated`].
    fn update_range_expecting(
        &mut self,
        outliers: RangeOutliers,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        if self.params.range_update == RangeLinearisation::Unscented {
            return self.update_range_unscented_expecting(outliers, m, auv_depth, range_variance, transponder_sd, gate);
        }
        let Some((h, _, Innovation { value: y, variance: s })) =
            self.range_prior(m, auv_depth, range_variance, transponder_sd)
        else {
            return RangeUpdate::UNUSABLE;
        };
        let w = outliers.inlier_probability(y, s);
        if !(w >= OUTLIER_ONLY) {
            return RangeUpdate { outcome: UpdateOutcome::Gated { nis: y * y / s }, innovation: y, variance: s };
        }
        // The PDA's spread is K·y of the prior, so it is taken before the update moves P.
        let shift = (outliers.update == OutlierUpdate::Pda).then(|| self.ekf.p() * h.transpose() * (y / s));
        let raised = range_variance + (1.0 / w - 1.0) * s;
        let prior = self.prior_along(h, y, raised, transponder_sd);
        let up = self.apply_range_prior(m, auv_depth, raised, transponder_sd, gate, prior);
        if let Some(shift) = shift.filter(|_| up.outcome.applied() && w < 1.0) {
            let (t, x) = (self.ekf.t(), *self.ekf.x());
            let spread = shift * shift.transpose() * (w * (1.0 - w));
            self.ekf.predict(t, x, SMatrix::identity(), spread);
        }
        up
    }

    /// [`Self::update_range_expecting`] with the sigma-point statistics: the weighted update of
    /// the regression row, its noise variance raised by (1/w − 1)·S (the PDA's spread as there).
    fn update_range_unscented_expecting(
        &mut self,
        outliers: RangeOutliers,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        let Some((h, (y, r), _)) = self.sigma_prior(m, auv_depth, range_variance, transponder_sd) else {
            return RangeUpdate::UNUSABLE;
        };
        let s = (h * self.ekf.p() * h.transpose())[(0, 0)] + r;
        let w = outliers.inlier_probability(y, s);
        if !(w >= OUTLIER_ONLY) {
            return RangeUpdate { outcome: UpdateOutcome::Gated { nis: y * y / s }, innovation: y, variance: s };
        }
        let shift = (outliers.update == OutlierUpdate::Pda).then(|| self.ekf.p() * h.transpose() * (y / s));
        let outcome = self.range_scalar(y, h, r + (1.0 / w - 1.0) * s, gate);
        if let Some(shift) = shift.filter(|_| outcome.applied() && w < 1.0) {
            let (t, x) = (self.ekf.t(), *self.ekf.x());
            self.ekf.predict(t, x, SMatrix::identity(), shift * shift.transpose() * (w * (1.0 - w)));
        }
        RangeUpdate { outcome, innovation: y, variance: s }
    }

    /// Adds the isotropic horizontal position variance that makes the rejected range `up` a
    /// `recovery.target_nis` event ([`GateRecovery`]), as process noise at the filter's time.
    fn inflate_position(
        &mut self,
        up: &RangeUpdate,
        transponder: &Vec3,
        auv_depth: Option<f64>,
        recovery: GateRecovery,
    ) {
        let Some((_, h)) = self.range_jacobian(transponder, auv_depth) else { return };
        let horizontal = h[E] * h[E] + h[N] * h[N];
        let added = (up.innovation * up.innovation / recovery.target_nis - up.variance) / horizontal;
        if !(added > 0.0 && added.is_finite()) {
            return;
        }
        let mut q = SVector::<f64, M>::zeros();
        (q[E], q[N]) = (added, added);
        let (t, x) = (self.ekf.t(), *self.ekf.x());
        let no_transition: SparseRows<0, 1> = [];
        self.ekf.predict_sparse(t, x, &no_transition, &q);
    }

    /// The range update with the range variance (m²), the transponder's horizontal SD (m, each
    /// axis) and the gate given by the caller (a log row with its own σ, a tuned noise), after
    /// the [`RangeHealth`] check when the filter has one.
    pub fn update_range_with(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        if let Some(up) = self.health_check(m, auv_depth, range_variance, transponder_sd) {
            return up;
        }
        self.update_range_unchecked(m, auv_depth, range_variance, transponder_sd, gate)
    }

    /// [`Self::update_range_with`] without the health check.
    fn update_range_unchecked(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        if self.params.range_update == RangeLinearisation::Unscented {
            return self.update_range_unscented(m, auv_depth, range_variance, transponder_sd, gate);
        }
        let Some(prior) = self.range_prior(m, auv_depth, range_variance, transponder_sd) else {
            return RangeUpdate::UNUSABLE;
        };
        self.apply_range_prior(m, auv_depth, range_variance, transponder_sd, gate, prior)
    }

    /// [`Self::update_range_with`] from the range's prior ([`Self::range_prior`]) at that variance.
    fn apply_range_prior(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
        (h, r, prior): (SMatrix<f64, 1, M>, f64, Innovation),
    ) -> RangeUpdate {
        let Innovation { value: innovation, variance } = prior;
        let outcome = match self.params.range_update {
            RangeLinearisation::Ekf => self.range_scalar(innovation, h, r, gate),
            RangeLinearisation::Iterated(it) => {
                self.update_range_iterated(m, auv_depth, range_variance, transponder_sd, gate, it, prior)
            }
            // The expecting update raises the variance of the prior it was given: the regression
            // row and the curvature's variance are in `h` and `r` ([`Self::sigma_prior`]).
            RangeLinearisation::Unscented => self.range_scalar(innovation, h, r, gate),
        };
        RangeUpdate { outcome, innovation, variance }
    }

    /// The sigma-point range update ([`RangeLinearisation::Unscented`]): the scalar Joseph update
    /// with the regression row and the range variance plus the curvature's, gated on the NIS of
    /// the sigma-point innovation.
    fn update_range_unscented(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        let Some((h, (y, r), _)) = self.sigma_prior(m, auv_depth, range_variance, transponder_sd) else {
            return RangeUpdate::UNUSABLE;
        };
        let variance = (h * self.ekf.p() * h.transpose())[(0, 0)] + r;
        let outcome = self.range_scalar(y, h, r, gate);
        RangeUpdate { outcome, innovation: y, variance }
    }

    /// A range's sigma-point statistics over the position prior: the regression row h (position
    /// columns only), (innovation z − z̄, the variance R + Ω the row leaves to the noise: the
    /// range's, the transponder's along the line of sight at the mean, and the curvature's), and
    /// the line of sight at the mean. None when the prior's position block is not positive
    /// definite.
    fn sigma_prior(
        &self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
    ) -> Option<(SMatrix<f64, 1, M>, (f64, f64), Option<SMatrix<f64, 1, M>>)> {
        let (x, p) = (self.ekf.x(), self.ekf.p());
        let mean = nalgebra::Vector2::new(x[E], x[N]);
        let block = nalgebra::Matrix2::new(p[(E, E)], p[(E, N)], p[(N, E)], p[(N, N)]);
        let sigma = sigma_point_range(mean, block, &m.transponder, auv_depth)?;
        let line_of_sight = range_gradient::<M>((x[E], x[N]), &m.transponder, auv_depth).map(|g| g.1);
        // Overhead in 2-D the transponder's error is all along the (unknown) line of sight.
        let r = match &line_of_sight {
            Some(los) => with_transponder_variance(range_variance, transponder_sd, los),
            None => range_variance + transponder_sd.powi(2),
        };
        let mut h = SMatrix::<f64, 1, M>::zeros();
        (h[E], h[N]) = (sigma.h[0], sigma.h[1]);
        Some((h, (m.range - sigma.predicted, r + sigma.unexplained), line_of_sight))
    }

    /// A range's line of sight h, its noise variance with the transponder's term, and its
    /// innovation z − h(x⁻) with variance h P⁻ hᵀ + R; None directly overhead in 2-D.
    fn range_prior(
        &self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
    ) -> Option<(SMatrix<f64, 1, M>, f64, Innovation)> {
        let (predicted, h) = self.range_jacobian(&m.transponder, auv_depth)?;
        Some(self.prior_along(h, m.range - predicted, range_variance, transponder_sd))
    }

    /// [`Self::range_prior`] for a line of sight `h` and `innovation` already found: the
    /// expecting update raises only the variance, so it need not find the line of sight again.
    fn prior_along(
        &self,
        h: SMatrix<f64, 1, M>,
        innovation: f64,
        range_variance: f64,
        transponder_sd: f64,
    ) -> (SMatrix<f64, 1, M>, f64, Innovation) {
        let r = with_transponder_variance(range_variance, transponder_sd, &h);
        let variance = (h * self.ekf.p() * h.transpose())[(0, 0)] + r;
        (h, r, Innovation { value: innovation, variance })
    }

    /// The iterated EKF range update ([`IteratedRange`]), gated on the `prior` innovation.
    #[allow(clippy::too_many_arguments)]
    fn update_range_iterated(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
        it: IteratedRange,
        prior: Innovation,
    ) -> UpdateOutcome {
        let nis = prior.value * prior.value / prior.variance;
        if !gate.admits(&[prior.value], nis) {
            return UpdateOutcome::Gated { nis };
        }
        let (x0, p) = (*self.ekf.x(), *self.ekf.p());
        let mut at = (x0[E], x0[N]);
        let mut last = None;
        for _ in 0..it.iterations.max(1) {
            let Some((predicted, h)) = range_gradient::<M>(at, &m.transponder, auv_depth) else {
                return UpdateOutcome::Unusable;
            };
            let r = with_transponder_variance(range_variance, transponder_sd, &h);
            let s = (h * p * h.transpose())[(0, 0)] + r;
            // z − h(x_i) − H_i (x⁻ − x_i): only the position columns of H_i are non-zero.
            let y = m.range - predicted - (h[E] * (x0[E] - at.0) + h[N] * (x0[N] - at.1));
            let gain = |i: usize| (p[(i, E)] * h[E] + p[(i, N)] * h[N]) / s;
            let next = (x0[E] + gain(E) * y, x0[N] + gain(N) * y);
            let moved = (next.0 - at.0).hypot(next.1 - at.1);
            (at, last) = (next, Some((y, h, r)));
            if moved < it.tolerance_m {
                break;
            }
        }
        let Some((y, h, r)) = last else { return UpdateOutcome::Unusable };
        match self.range_scalar(y, h, r, &Gate::OFF) {
            UpdateOutcome::Applied { .. } => UpdateOutcome::Applied { nis },
            other => other,
        }
    }

    /// The predicted range to a transponder and its Jacobian row; None directly overhead in 2-D,
    /// where the range has no gradient (no information, no update).
    pub fn range_jacobian(&self, transponder: &Vec3, auv_depth: Option<f64>) -> Option<(f64, SMatrix<f64, 1, M>)> {
        let x = self.ekf.x();
        range_gradient((x[E], x[N]), transponder, auv_depth)
    }

    /// Predicted range from the current estimate to a transponder (for residual bookkeeping).
    pub fn predicted_range(&self, transponder: &Vec3, auv_depth: Option<f64>) -> f64 {
        let x = self.ekf.x();
        let dz = auv_depth.map_or(0.0, |z| z - transponder.z);
        ((x[E] - transponder.x).powi(2) + (x[N] - transponder.y).powi(2) + dz * dz).sqrt()
    }
}

/// A speed log's reading (m/s) of S, with its SD.
#[inline(always)]
fn speed_reading(measured: f64, sd: f64) -> UnitReading<1> {
    UnitReading { columns: [S], value: measured, variance: sd.powi(2), angle: false }
}

/// A compass reading (math heading, rad) of ψ + b, with its SD.
#[inline(always)]
fn compass_reading(measured: f64, sd: f64) -> UnitReading<2> {
    UnitReading { columns: [PSI, BIAS], value: measured, variance: sd.powi(2), angle: true }
}

/// A range's innovation z − h(x⁻) and its variance H P⁻ Hᵀ + R.
#[derive(Debug, Clone, Copy)]
struct Innovation {
    value: f64,
    variance: f64,
}

/// The range from horizontal position `at` (e, n) to a transponder and its Jacobian row; None
/// directly overhead in 2-D, where the range has no gradient.
fn range_gradient<const M: usize>(
    at: (f64, f64),
    transponder: &Vec3,
    auv_depth: Option<f64>,
) -> Option<(f64, SMatrix<f64, 1, M>)> {
    let de = at.0 - transponder.x;
    let dn = at.1 - transponder.y;
    let dz = auv_depth.map_or(0.0, |z| z - transponder.z);
    let predicted = (de * de + dn * dn + dz * dz).sqrt();
    if !(predicted > 1e-6) {
        return None;
    }
    let mut h = SMatrix::<f64, 1, M>::zeros();
    h[E] = de / predicted;
    h[N] = dn / predicted;
    Some((predicted, h))
}

/// The range variance with the transponder's horizontal position variance (`transponder_sd`²
/// per axis) projected onto the line of sight `h`.
fn with_transponder_variance<const M: usize>(range_variance: f64, transponder_sd: f64, h: &SMatrix<f64, 1, M>) -> f64 {
    let mut r = range_variance;
    if transponder_sd > 0.0 {
        r += transponder_sd.powi(2) * (h[E] * h[E] + h[N] * h[N]);
    }
    r
}

/// An AUV filter of either state vector, chosen at run time by an [`AuvModel`]: what a
/// simulator holds for each vehicle. The engine reads the navigation states (E, N, S, ψ), the
/// horizontal covariance block and the current estimate, whichever the model.
#[derive(Debug, Clone)]
pub enum AuvFilter {
    Thesis(AuvEkf<5>),
    Current(AuvEkf<7>),
}

/// Calls `$body` with `$f` bound to the filter, whichever its state vector.
macro_rules! each_model {
    ($self:expr, $f:ident => $body:expr) => {
        match $self {
            AuvFilter::Thesis($f) => $body,
            AuvFilter::Current($f) => $body,
        }
    };
}

impl AuvFilter {
    /// As [`AuvEkf::new`], with the state vector of `model`.
    pub fn new(model: &AuvModel, t0: f64, e: f64, n: f64, speed: f64, psi: f64, params: AuvParams) -> Self {
        match model {
            AuvModel::Thesis => AuvFilter::Thesis(AuvEkf::new(t0, e, n, speed, psi, params)),
            AuvModel::Current(c) => AuvFilter::Current(AuvEkf::with_current(t0, e, n, speed, psi, params, *c)),
        }
    }

    // The engine reads these for every vehicle at every truth step: inlined across crates.
    #[inline]
    pub fn position(&self) -> (f64, f64) {
        each_model!(self, f => f.position())
    }
    /// Estimated speed through the water (m/s) and math heading ψ (rad).
    #[inline]
    pub fn speed_heading(&self) -> (f64, f64) {
        each_model!(self, f => (f.state()[S], f.state()[PSI]))
    }
    /// Estimated water current (east, north) m/s: zero for the thesis model.
    pub fn current(&self) -> (f64, f64) {
        match self {
            AuvFilter::Thesis(_) => (0.0, 0.0),
            AuvFilter::Current(f) => (f.state()[CURRENT_E], f.state()[CURRENT_N]),
        }
    }
    /// The horizontal covariance block [P_EE, P_EN, P_NN].
    pub fn position_cov(&self) -> [f64; 3] {
        each_model!(self, f => {
            let p = f.ekf().p();
            [p[(E, E)], p[(E, N)], p[(N, N)]]
        })
    }
    /// The recoveries its range health check made ([`AuvEkf::recoveries`]).
    pub fn recoveries(&self) -> Recoveries {
        each_model!(self, f => f.recoveries())
    }
    /// Every state and covariance entry finite ([`Ekf::is_finite`]).
    #[inline]
    pub fn is_finite(&self) -> bool {
        each_model!(self, f => f.ekf().is_finite())
    }
    #[inline]
    pub fn predict_to(&mut self, t: f64, yaw_rate: f64) -> bool {
        each_model!(self, f => f.predict_to(t, yaw_rate))
    }
    #[inline(always)]
    pub fn update_speed(&mut self, measured: f64) -> UpdateOutcome {
        each_model!(self, f => f.update_speed(measured))
    }
    #[inline(always)]
    pub fn update_heading(&mut self, measured: f64) -> UpdateOutcome {
        each_model!(self, f => f.update_heading(measured))
    }
    /// [`AuvEkf::dead_reckoning_step`].
    #[inline(always)]
    pub fn dead_reckoning_step(
        &mut self,
        t: f64,
        yaw_rate: f64,
        speed: f64,
        heading: f64,
    ) -> (bool, [UpdateOutcome; 2]) {
        each_model!(self, f => f.dead_reckoning_step(t, yaw_rate, speed, heading))
    }
    pub fn update_range(&mut self, m: &RangeMeasurement, auv_depth: Option<f64>) -> UpdateOutcome {
        each_model!(self, f => f.update_range(m, auv_depth))
    }
    /// A horizontal position fix (e, n) with σ `sd` per axis (GPS at the surface): two scalar
    /// updates, exact for the diagonal noise.
    pub fn update_position_fix(&mut self, fix: (f64, f64), sd: f64) -> [UpdateOutcome; 2] {
        each_model!(self, f => [
            f.update_axis(E, fix.0, sd * sd),
            f.update_axis(N, fix.1, sd * sd),
        ])
    }
}

impl<const M: usize> AuvEkf<M> {
    /// A direct measurement of state `i` with variance `r`.
    fn update_axis(&mut self, i: usize, measured: f64, r: f64) -> UpdateOutcome {
        let y = measured - self.ekf.x()[i];
        self.ekf.update_units(y, [i], r, &Gate::OFF)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::is_positive_definite;
    use coopnav_core::wrap_pi;

    fn meas(range: f64, at: Vec3) -> RangeMeasurement {
        RangeMeasurement { range, travel_time: range / 1500.0, transponder: at }
    }

    #[test]
    fn dead_reckoning_follows_heading_and_rate() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 1.0, 0.0, AuvParams::default());
        for k in 1..=10 {
            f.predict_to(k as f64 * 0.1, 0.0);
        }
        assert!((f.position().0 - 1.0).abs() < 1e-12 && f.position().1.abs() < 1e-12);
        f.predict_to(2.0, std::f64::consts::FRAC_PI_2 / 1.0);
        assert!(f.state()[PSI] > 1.0, "heading integrates the rate input");
    }

    #[test]
    fn range_update_pulls_towards_the_measured_circle() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams::default());
        let out = f.update_range(&meas(95.0, Vec3::new(100.0, 0.0, 0.0)), None);
        assert!(out.applied());
        assert!(f.position().0 > 3.0, "moved towards the transponder: {:?}", f.position());
        assert!(f.position().1.abs() < 1e-9, "no information across the line of sight");
        assert!(f.ekf().p()[(E, E)] < 16.0 && (f.ekf().p()[(N, N)] - 16.0).abs() < 1e-9);
    }

    #[test]
    fn transponder_uncertainty_adds_its_line_of_sight_variance() {
        // Line of sight along E: the posterior E variance is P·R/(P + R) with R = σ_r² + σ_b².
        let at = Vec3::new(100.0, 0.0, 0.0);
        let r0 = AuvParams::default().range_noise.variance(95.0 / 1500.0);
        for sd in [0.0, 3.0] {
            let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams::default());
            assert!(f.update_range_from_uncertain(&meas(95.0, at), None, sd).applied());
            let r = r0 + sd * sd;
            assert!((f.ekf().p()[(E, E)] - 16.0 * r / (16.0 + r)).abs() < 1e-9, "sd {sd}: {}", f.ekf().p()[(E, E)]);
        }
    }

    #[test]
    fn current_states_carry_the_vehicle_and_start_still() {
        let mut f = AuvEkf::with_current(0.0, 0.0, 0.0, 1.0, 0.0, AuvParams::default(), CurrentParams::default());
        f.ekf_mut().predict(
            1.0,
            SVector::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.2, -0.1]),
            SMatrix::identity(),
            SMatrix::zeros(),
        );
        f.predict_to(11.0, 0.0);
        // 10 s at 1 m/s east through the water plus (0.2, −0.1) m/s of current.
        assert!((f.position().0 - 12.0).abs() < 1e-9 && (f.position().1 + 1.0).abs() < 1e-9, "{:?}", f.position());
        assert!(f.ekf().p()[(E, CURRENT_E)] > 0.0, "position and current are correlated by the drift");
    }

    #[test]
    fn overhead_transponder_is_harmless() {
        let mut f = AuvEkf::new(0.0, 5.0, 5.0, 0.0, 0.0, AuvParams::default());
        assert_eq!(f.update_range(&meas(0.0, Vec3::new(5.0, 5.0, 1.5)), None), UpdateOutcome::Unusable);
        let out = f.update_range(&meas(8.5, Vec3::new(5.0, 5.0, 1.5)), Some(10.0));
        assert!(out.applied());
        assert!(f.state().iter().all(|v| v.is_finite()));
        assert!(is_positive_definite(f.ekf().p()));
    }

    #[test]
    fn compass_update_splits_heading_and_bias_and_wraps() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, std::f64::consts::PI - 0.01, AuvParams::default());
        f.update_heading(-std::f64::consts::PI + 0.01);
        // The innovation is +0.02 rad across the ±π seam, not −6.26.
        let est = f.state()[PSI] + f.state()[BIAS];
        assert!(wrap_pi(est - (std::f64::consts::PI - 0.01)) > 0.0);
        assert!(wrap_pi(est - (std::f64::consts::PI - 0.01)) < 0.021);
    }

    /// The update's cost J(e, n) = Σ (x − x⁻)²/P⁻ + (z − ‖x‖)²/R for a diagonal prior and a
    /// transponder at the origin: what the iterated update minimises.
    fn update_cost(at: (f64, f64), prior: (f64, f64), p: (f64, f64), z: f64, r: f64) -> f64 {
        (at.0 - prior.0).powi(2) / p.0 + (at.1 - prior.1).powi(2) / p.1 + (z - at.0.hypot(at.1)).powi(2) / r
    }

    fn iterated(iterations: u32) -> AuvParams {
        let range_update = RangeLinearisation::Iterated(IteratedRange { iterations, tolerance_m: 1e-3 });
        AuvParams { range_update, ..AuvParams::default() }
    }

    #[test]
    fn one_iteration_is_the_ekf_bit_for_bit() {
        let (mut ekf, mut one) = (AuvParams::default(), iterated(1));
        ekf.p0[1] = 400.0;
        one.p0[1] = 400.0;
        let c = CurrentParams::default();
        let (mut a, mut b) = (
            AuvEkf::with_current(0.0, 3.0, -4.0, 1.5, 0.3, ekf, c),
            AuvEkf::with_current(0.0, 3.0, -4.0, 1.5, 0.3, one, c),
        );
        a.predict_to(30.0, 0.01);
        b.predict_to(30.0, 0.01);
        let m = meas(180.0, Vec3::new(150.0, 90.0, 0.0));
        assert_eq!(
            a.update_range_from_uncertain(&m, Some(20.0), 2.0),
            b.update_range_from_uncertain(&m, Some(20.0), 2.0)
        );
        assert_eq!((a.state(), a.ekf().p()), (b.state(), b.ekf().p()));
    }

    #[test]
    fn iterated_update_reaches_the_minimum_the_ekf_overshoots() {
        // A prior long along N (σ 50 m) and tight along E (σ 2 m), 20 m east of a transponder
        // whose range says 30 m: the minimum lies near (20, 22.3) on the 30 m circle. The EKF
        // steps along the gradient at the prior (almost pure N) to a point 47 m out.
        let (prior, p, z, r) = ((20.0, 5.0), (4.0, 2500.0), 30.0, 1.0);
        let run = |params: AuvParams| {
            let params = AuvParams { p0: [p.0, p.1, 0.0025, 0.01, 1e-4], ..params };
            let mut f = AuvEkf::new(0.0, prior.0, prior.1, 0.0, 0.0, params);
            let up = f.update_range_with(&meas(z, Vec3::new(0.0, 0.0, 0.0)), None, r, 0.0, &Gate::OFF);
            assert!(up.outcome.applied(), "{up:?}");
            f.position()
        };
        let (ekf, iekf) = (run(AuvParams::default()), run(iterated(10)));
        let cost = |at| update_cost(at, prior, p, z, r);
        assert!(ekf.0.hypot(ekf.1) - z > 10.0 && cost(ekf) > 100.0, "EKF {ekf:?}, J {}", cost(ekf));
        assert!((iekf.0.hypot(iekf.1) - z).abs() < 0.1 && cost(iekf) < 0.2, "IEKF {iekf:?}, J {}", cost(iekf));
        // No point of a fine grid around it does better.
        let best = (150..300)
            .flat_map(|e| (150..300).map(move |n| (f64::from(e) / 10.0, f64::from(n) / 10.0)))
            .map(cost)
            .fold(f64::INFINITY, f64::min);
        assert!(cost(iekf) <= best + 1e-9, "grid minimum {best}");
    }

    #[test]
    fn a_gauss_markov_current_decays_and_its_variance_settles_where_a_random_walk_grows() {
        let t_corr = 600.0;
        let gm = CurrentParams { correlation_time_s: Some(t_corr), ..CurrentParams::default() };
        let walk = CurrentParams::default();
        let run = |c: CurrentParams| {
            let mut f = AuvEkf::with_current(0.0, 0.0, 0.0, 1.0, 0.0, AuvParams::default(), c);
            let x = SVector::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.2, -0.1]);
            f.ekf_mut().predict(0.0, x, SMatrix::identity(), SMatrix::zeros());
            for k in 1..=36_000 {
                f.predict_to(k as f64 * 0.1, 0.0);
            }
            f
        };
        let (decayed, walked) = (run(gm), run(walk));
        // One hour = 6 T: the mean is e⁻⁶ of where it started.
        let e6 = (-6.0f64).exp();
        assert!((decayed.state()[CURRENT_E] - 0.2 * e6).abs() < 1e-9, "{}", decayed.state()[CURRENT_E]);
        assert!((decayed.state()[CURRENT_N] + 0.1 * e6).abs() < 1e-9);
        assert_eq!(walked.state()[CURRENT_E], 0.2);
        // Steady state of σ² = φ²σ² + q: q/(1 − φ²), φ = e^(−0.1/T).
        let q = walk.q;
        let steady = q / (1.0 - (-0.2 / t_corr).exp());
        let p_gm = decayed.ekf().p()[(CURRENT_E, CURRENT_E)];
        assert!((p_gm / steady - 1.0).abs() < 1e-3, "{p_gm} vs {steady}");
        let p_walk = walked.ekf().p()[(CURRENT_E, CURRENT_E)];
        assert!((p_walk - (walk.p0 + 36_000.0 * q)).abs() < 1e-9, "{p_walk}");
        // The smoother's mean map and Jacobian decay the same way.
        let f = run(gm);
        let x = *f.state();
        let (mean, jac, _) = f.prediction(&x, 0.1, 0.0);
        let phi = (-0.1 / t_corr).exp();
        assert_eq!((mean[CURRENT_E], jac[(CURRENT_E, CURRENT_E)]), (x[CURRENT_E] * phi, phi));
    }

    #[test]
    fn gate_recovery_ends_a_lock_out_and_leaves_isolated_outliers_gated() {
        // The filter believes (0, 0) to 1 m; the vehicle is at (0, 100); a transponder 300 m
        // north measures 200 m, 100 m short: NIS in the thousands, every range gated.
        let gate = Gate { max_abs_residual: None, max_nis: Some(10.83) };
        let tight = AuvParams { p0: [1.0, 1.0, 0.0025, 0.01, 1e-4], range_gate: gate, ..AuvParams::default() };
        let recovering = AuvParams { range_gate_recovery: Some(GateRecovery::default()), ..tight.clone() };
        let at = Vec3::new(0.0, 300.0, 0.0);
        let mut locked = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, tight);
        let mut recovers = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, recovering.clone());
        let outcomes: Vec<bool> = (0..6).map(|_| recovers.update_range(&meas(200.0, at), None).applied()).collect();
        for _ in 0..6 {
            assert!(matches!(locked.update_range(&meas(200.0, at), None), UpdateOutcome::Gated { .. }));
        }
        assert_eq!(locked.position(), (0.0, 0.0), "locked out");
        assert_eq!(outcomes, [false, false, true, true, true, true], "the third rejection inflates and applies");
        assert!((recovers.position().1 - 100.0).abs() < 5.0, "{:?}", recovers.position());
        // An outlier between good ranges is gated each time and never inflates P.
        let mut f = AuvEkf::new(0.0, 0.0, 100.0, 0.0, 0.0, recovering);
        for k in 0..9 {
            let range = if k % 2 == 0 { 200.0 } else { 260.0 };
            assert_eq!(f.update_range(&meas(range, at), None).applied(), k % 2 == 0, "range {k}");
        }
        assert!(f.ekf().p()[(N, N)] < 1.0);
    }

    #[test]
    fn the_new_options_are_written_only_when_set() {
        let plain = toml::to_string(&AuvParams::default()).unwrap();
        assert!(!plain.contains("range_update") && !plain.contains("range_gate_recovery"), "{plain}");
        assert!(!toml::to_string(&CurrentParams::default()).unwrap().contains("correlation"));
        let set: AuvParams = toml::from_str(
            "range_update = { kind = \"iterated\", iterations = 3 }\nrange_gate_recovery = { after = 2 }\n",
        )
        .unwrap();
        assert_eq!(set.range_update, RangeLinearisation::Iterated(IteratedRange { iterations: 3, tolerance_m: 0.01 }));
        assert_eq!(set.range_gate_recovery, Some(GateRecovery { after: 2, target_nis: 1.0 }));
        assert_eq!(toml::from_str::<AuvParams>(&toml::to_string(&set).unwrap()).unwrap(), set, "round trip");
        let bad = AuvParams {
            range_update: RangeLinearisation::Iterated(IteratedRange { iterations: 0, tolerance_m: 0.01 }),
            range_gate_recovery: Some(GateRecovery { after: 0, target_nis: -1.0 }),
            ..AuvParams::default()
        };
        let e = bad.validate("filter.").unwrap_err().to_string();
        for field in [
            "filter.range_update.iterations",
            "filter.range_gate_recovery.after",
            "filter.range_gate_recovery.target_nis",
        ] {
            assert!(e.contains(field), "{e}");
        }
        let t = CurrentParams { correlation_time_s: Some(0.0), ..CurrentParams::default() };
        assert!(AuvModel::Current(t).validate("model.").unwrap_err().to_string().contains("model.correlation_time_s"));
    }

    /// Runs `steps` filter steps on two copies of `filter`, one by [`AuvEkf::dead_reckoning_step`]
    /// and one by its three calls, with readings from `reading(k)` = (dt, yaw rate, speed,
    /// heading), and asserts every step's outcomes, states, covariances and counts agree bit for bit.
    fn fused_equals_three_calls<const M: usize>(
        filter: AuvEkf<M>,
        steps: usize,
        mut reading: impl FnMut(usize) -> (f64, f64, f64, f64),
    ) {
        let (mut fused, mut calls) = (filter.clone(), filter);
        let bits = |f: &AuvEkf<M>| f.state().iter().chain(f.ekf().p().iter()).map(|v| v.to_bits()).collect::<Vec<_>>();
        let mut t = fused.ekf().t();
        for k in 0..steps {
            let (dt, yaw_rate, speed, heading) = reading(k);
            t += dt;
            let one = fused.dead_reckoning_step(t, yaw_rate, speed, heading);
            let three = (calls.predict_to(t, yaw_rate), [calls.update_speed(speed), calls.update_heading(heading)]);
            assert_eq!(one, three, "step {k}");
            assert_eq!(bits(&fused), bits(&calls), "step {k}");
            assert_eq!((fused.ekf().t(), fused.ekf().counts()), (calls.ekf().t(), calls.ekf().counts()), "step {k}");
        }
    }

    #[test]
    fn the_fused_filter_step_is_its_three_calls_bit_for_bit() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut readings = move |k: usize| {
            // A turning vehicle crossing the ±π seam; every 97th step repeats the filter's time
            // (no prediction), every 89th reads a NaN speed (the speed update is unusable).
            let dt = if k % 97 == 5 { 0.0 } else { 0.1 };
            let speed = if k % 89 == 7 { f64::NAN } else { 1.5 + 0.1 * uniform() };
            let heading = wrap_angle(3.0 + 0.02 * k as f64 + 0.05 * uniform());
            (dt, 0.2 + 0.01 * uniform(), speed, heading)
        };
        let params = AuvParams::default();
        fused_equals_three_calls(AuvEkf::new(0.0, 10.0, -5.0, 1.5, 3.0, params.clone()), 3000, &mut readings);
        let walk = CurrentParams::default();
        fused_equals_three_calls(
            AuvEkf::with_current(0.0, 0.0, 0.0, 1.5, 3.0, params.clone(), walk),
            3000,
            &mut readings,
        );
        let gauss_markov = CurrentParams { correlation_time_s: Some(600.0), ..walk };
        let current = AuvEkf::with_current(0.0, 0.0, 0.0, 1.5, 3.0, params.clone(), gauss_markov);
        fused_equals_three_calls(current, 3000, &mut readings);
        // A filter recording its history runs the three calls, and records them.
        let mut recording = AuvEkf::new(0.0, 10.0, -5.0, 1.5, 3.0, params);
        recording.ekf_mut().record_history();
        fused_equals_three_calls(recording, 50, &mut readings);
    }

    /// w by a direct sum over the outlier's length instead of Φ: the outlier density is the mean
    /// of N(y − e; 0, S) over e in [min, max].
    fn inlier_probability_by_quadrature(o: &RangeOutliers, y: f64, s: f64) -> f64 {
        let normal = |v: f64| (-0.5 * v * v / s).exp() / (2.0 * std::f64::consts::PI * s).sqrt();
        let n = 20_000;
        let step = (o.max_m - o.min_m) / n as f64;
        let mean = (0..n).map(|i| normal(y - (o.min_m + (i as f64 + 0.5) * step))).sum::<f64>() / n as f64;
        let inlier = (1.0 - o.probability) * normal(y);
        inlier / (inlier + o.probability * mean)
    }

    #[test]
    fn the_inlier_probability_is_the_mixtures_posterior_and_long_ranges_lose_it() {
        let o = RangeOutliers::GILL;
        for s in [0.5, 4.0, 25.0] {
            for y in [-8.0, -2.0, 0.0, 1.5, 3.0, 5.0, 7.5, 12.0] {
                let (w, direct) = (o.inlier_probability(y, s), inlier_probability_by_quadrature(&o, y, s));
                assert!((w - direct).abs() < 1e-7, "y {y}, S {s}: {w} vs {direct}");
            }
        }
        // With a tight prior a 7.5 m long range is an outlier, a short one never is (outliers are long).
        assert!(o.inlier_probability(7.5, 1.0) < 1e-6);
        assert!(o.inlier_probability(-7.5, 1.0) > 0.999_999);
        assert!(o.inlier_probability(0.2, 1.0) > 0.999);
        // A loose prior cannot tell: the same 7.5 m keeps a fair share.
        assert!((0.05..0.95).contains(&o.inlier_probability(7.5, 25.0)));
        // Far from both, the densities underflow and the range counts as an outlier.
        assert_eq!(o.inlier_probability(1e4, 1.0), 0.0);
    }

    #[test]
    fn an_expected_outlier_moves_the_estimate_by_its_inlier_share_and_pda_adds_the_spread() {
        let at = Vec3::new(100.0, 0.0, 0.0);
        let expecting = AuvParams { range_outliers: Some(RangeOutliers::GILL), ..AuvParams::default() };
        let pda = RangeOutliers { update: OutlierUpdate::Pda, ..RangeOutliers::GILL };
        let cases = [99.7, 94.0, 92.5, 80.0].into_iter().flat_map(|m| [(m, RangeOutliers::GILL), (m, pda)]);
        for (measured, outliers) in cases {
            let expecting = AuvParams { range_outliers: Some(outliers), ..expecting.clone() };
            let mut plain = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams::default());
            let mut robust = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, expecting.clone());
            let (p0, x0) = (*robust.ekf().p(), *robust.ekf().x());
            plain.update_range(&meas(measured, at), None);
            let outcome = robust.update_range(&meas(measured, at), None);
            // Line of sight along −E from the transponder: h = [−1, 0, …], y = z − 100 (range 100 − e).
            let r = AuvParams::default().range_noise.variance(measured / 1500.0);
            let y = measured - 100.0;
            let s = p0[(E, E)] + r;
            let w = RangeOutliers::GILL.inlier_probability(y, s);
            let k: SVector<f64, 5> = p0.column(E) * (-1.0 / s);
            let mean = x0 + k * (w * y);
            let spread = match outliers.update {
                OutlierUpdate::Weighted => 0.0,
                OutlierUpdate::Pda => w * (1.0 - w),
            };
            let cov = p0 - k * k.transpose() * (w * s) + (k * y) * (k * y).transpose() * spread;
            assert!(outcome.applied(), "{measured}: {outcome:?}");
            assert!((robust.ekf().x() - mean).amax() < 1e-9, "{measured}: {} vs {mean}", robust.ekf().x());
            assert!((robust.ekf().p() - cov).amax() < 1e-9, "{measured}: {} vs {cov}", robust.ekf().p());
            // The estimate moves towards the transponder (a short range) by w of the plain update's move.
            let (moved, plain_moved) = (robust.position().0 - x0[E], plain.position().0 - x0[E]);
            assert!((moved - w * plain_moved).abs() < 1e-9, "{measured}: {moved} vs {w}·{plain_moved}");
        }
        // 107.5 m measured where 100 m is predicted, the position known to 1 m: mostly an outlier.
        let tight = AuvParams { p0: [1.0, 1.0, 0.0025, 0.01, 1e-4], ..AuvParams::default() };
        let mut plain = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, tight.clone());
        let mut robust =
            AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams { range_outliers: expecting.range_outliers, ..tight });
        plain.update_range(&meas(107.5, at), None);
        robust.update_range(&meas(107.5, at), None);
        assert!(
            robust.position().0.abs() < 0.25 * plain.position().0.abs(),
            "{:?} vs {:?}",
            robust.position(),
            plain.position()
        );
        // 200 m long: neither an inlier nor an outlier of 5–10 m; refused, the filter untouched.
        let before = (*robust.ekf().x(), *robust.ekf().p());
        assert!(matches!(robust.update_range(&meas(300.0, at), None), UpdateOutcome::Gated { .. }));
        assert_eq!((*robust.ekf().x(), *robust.ekf().p()), before);
    }

    #[test]
    fn the_outlier_option_reads_back_and_names_bad_fields() {
        let set: AuvParams =
            toml::from_str("range_outliers = { probability = 0.0555, min_m = 5.0, max_m = 10.0 }\n").unwrap();
        assert_eq!(set.range_outliers, Some(RangeOutliers::GILL));
        assert_eq!(toml::from_str::<AuvParams>(&toml::to_string(&set).unwrap()).unwrap(), set, "round trip");
        let pda: AuvParams =
            toml::from_str("range_outliers = { probability = 0.0555, min_m = 5.0, max_m = 10.0, update = \"pda\" }\n")
                .unwrap();
        assert_eq!(pda.range_outliers.map(|o| o.update), Some(OutlierUpdate::Pda));
        let e = toml::from_str::<AuvParams>(
            "range_outliers = { probability = 0.0555, min_m = 5.0, max_m = 10.0, update = \"spread\" }\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("unknown variant `spread`, expected `weighted` or `pda`"), "{e}");
        assert!(!toml::to_string(&AuvParams::default()).unwrap().contains("range_outliers"));
        let bad = AuvParams {
            range_outliers: Some(RangeOutliers { probability: 1.0, min_m: 5.0, max_m: 5.0, ..RangeOutliers::GILL }),
            ..AuvParams::default()
        };
        let e = bad.validate("filter.").unwrap_err().to_string();
        assert!(e.contains("filter.range_outliers.probability = 1: allowed a probability in [0, 1)"), "{e}");
        assert!(e.contains("filter.range_outliers.max_m = 5: allowed a finite length above min_m"), "{e}");
    }

    #[test]
    fn bad_params_name_the_field() {
        let mut p = AuvParams::default();
        p.q[2] = -1.0;
        p.sigma_speed = f64::NAN;
        assert_eq!(
            p.validate("auv.").unwrap_err().to_string(),
            "2 bad fields:\n  field auv.q[2] = -1: allowed a finite number >= 0\n  field auv.sigma_speed = NaN: allowed a finite number > 0"
        );
    }
}
