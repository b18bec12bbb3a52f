//! Tuning the post-processing filter from the log itself, for prediction: the range σ, the E/N
//! process noise, the speed log's scale, the compass bias and the initial E/N variance that best
//! predict the ranges the smoothed track did not use (docs/models.md#post-tuning).
//!
//! The score is cross-validated over ranges: the ranges are split into `hold_out_every` folds
//! (every k-th range, each phase in turn); for each fold the filter and smoother run without it,
//! and each held-out range is scored by its log predictive density under the smoothed track,
//! N(r; 0, R + h Pˢ hᵀ) (`PostSummary::held_out_log_predictive`). The search (Nelder–Mead,
//! argmin) minimises the negative total plus a Gaussian prior that keeps a weakly identified value
//! near its starting one, within physical bounds: the range σ may not fall below what the
//! smoothed track's own residuals on the ranges it used show, and the initial variance may only
//! widen from the configured one.
//!
//! A guard ([`Guard`]) keeps the starting values when the result predicts the held-out ranges
//! worse than they do or rejects more ranges at the gate, and flags a search that stopped at its
//! cap. The tuned values carry an SD from the score's curvature, and the filter's compass-bias
//! state starts no narrower than the tuned bias's SD.
//!
//! Speed: the search runs over the log with its dead-reckoning rows averaged in blocks
//! (`dead_reckoning_block_s`) and predicted in steps of that length; the before/after figures are
//! always full-rate runs.

use crate::auv::{VelocityFrame, BIAS};
use crate::fieldlog::{LogRow, Observation};
use crate::post::{run, Pass, PostConfig, PostError, PostResult};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::cell::RefCell;

/// How to tune.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TuneOptions {
    /// Folds of the cross-validation: every k-th range is held out, each phase in turn (≥ 2).
    pub hold_out_every: usize,
    /// Nelder–Mead iterations at most. Invented default: 300 (docs/models.md#post-tuning).
    pub max_iters: u64,
    /// During the search, the yaw-rate, speed, heading, DVL and depth rows are averaged over blocks
    /// of this many seconds and the filter predicts in steps of that length (0: every row at full
    /// rate). Invented default: 1 s keeps the tuned values within the bands `tests/post_tune.rs`
    /// states of the full-rate ones, at a fraction of the time.
    pub dead_reckoning_block_s: f64,
}

impl Default for TuneOptions {
    fn default() -> Self {
        TuneOptions { hold_out_every: 5, max_iters: 300, dead_reckoning_block_s: 1.0 }
    }
}

/// The tuned quantities.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tuned {
    /// Range SD at zero range, c·σ_τ (m).
    pub range_sd_m: f64,
    /// Per-step E and N process noise `q[0] = q[1]` (m²).
    pub q_en: f64,
    pub speed_scale: f64,
    pub heading_bias_deg: f64,
    /// Initial E and N variance `p0[0] = p0[1]` (m²): how far the start may be off.
    pub p0_en: f64,
}

/// The tuned quantities' SDs (None where the score is not curved upwards there), from the
/// diagonal of the score's curvature at the result: each one's spread with the others held.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TunedSd {
    pub range_sd_m: Option<f64>,
    pub q_en: Option<f64>,
    pub speed_scale: Option<f64>,
    pub heading_bias_deg: Option<f64>,
    pub p0_en: Option<f64>,
}

/// Outer bounds of the search (invented, docs/models.md#post-tuning): wide enough for any
/// working sensor. The range σ's lower bound is only the outermost one: the floor that matters is
/// the consistency floor of [`Problem::cost`].
const RANGE_SD_M: (f64, f64) = (0.05, 50.0);
const Q_EN: (f64, f64) = (1e-8, 3.0);
const SPEED_SCALE: (f64, f64) = (0.7, 1.4);
const HEADING_BIAS_DEG: (f64, f64) = (-30.0, 30.0);
const P0_EN_MAX: f64 = 1e4;

/// The prior's SDs in search coordinates (invented, docs/models.md#post-tuning): a factor of 3 on
/// the range σ, of 100 on the process noise, 0.05 on the speed scale, 5° on the compass bias and a
/// factor of 10 on the initial variance.
const PRIOR_SD: [f64; 5] = [1.0986, 4.6052, 0.05, 5.0, 2.3026];

/// Steps of the initial simplex and of the curvature's differences, in search coordinates
/// (invented, docs/models.md#post-tuning).
const SIMPLEX_STEPS: [f64; 5] = [0.5, 1.5, 0.03, 2.0, 1.0];
const CURVATURE_STEPS: [f64; 5] = [0.1, 0.3, 0.005, 0.2, 0.3];

impl Tuned {
    fn of(cfg: &PostConfig) -> Tuned {
        Tuned {
            range_sd_m: cfg.auv.range_noise.sound_speed * cfg.auv.range_noise.sigma_time,
            q_en: cfg.auv.q[0],
            speed_scale: cfg.speed_scale,
            heading_bias_deg: cfg.heading_bias_deg,
            p0_en: cfg.auv.p0[0],
        }
    }
    fn apply(&self, cfg: &PostConfig) -> PostConfig {
        let mut c = cfg.clone();
        c.auv.range_noise.sigma_time = self.range_sd_m / c.auv.range_noise.sound_speed;
        c.auv.q[0] = self.q_en;
        c.auv.q[1] = self.q_en;
        c.speed_scale = self.speed_scale;
        c.heading_bias_deg = self.heading_bias_deg;
        c.auv.p0[0] = self.p0_en;
        c.auv.p0[1] = self.p0_en;
        c
    }
    /// Search coordinates: logs of the variances' scales, the others as they are.
    fn to_search(self) -> Vec<f64> {
        vec![self.range_sd_m.ln(), self.q_en.ln(), self.speed_scale, self.heading_bias_deg, self.p0_en.ln()]
    }
}

/// The search's bounds for one log and start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    pub range_sd_m: (f64, f64),
    pub q_en: (f64, f64),
    pub speed_scale: (f64, f64),
    pub heading_bias_deg: (f64, f64),
    /// From the configured initial variance (the start only widens) up.
    pub p0_en: (f64, f64),
}

impl Bounds {
    fn of(start: &Tuned) -> Bounds {
        Bounds {
            range_sd_m: RANGE_SD_M,
            q_en: Q_EN,
            speed_scale: SPEED_SCALE,
            heading_bias_deg: HEADING_BIAS_DEG,
            p0_en: (start.p0_en, P0_EN_MAX.max(start.p0_en)),
        }
    }
    /// Back from search coordinates, clamped into the bounds; also how far outside they were.
    fn from_search(&self, u: &[f64]) -> (Tuned, f64) {
        let clamp = |v: f64, (lo, hi): (f64, f64)| (v.clamp(lo, hi), (v - v.clamp(lo, hi)).abs());
        let (range_sd_m, a) = clamp(u[0].exp(), self.range_sd_m);
        let (q_en, b) = clamp(u[1].exp(), self.q_en);
        let (speed_scale, c) = clamp(u[2], self.speed_scale);
        let (heading_bias_deg, d) = clamp(u[3], self.heading_bias_deg);
        let (p0_en, e) = clamp(u[4].exp(), self.p0_en);
        (Tuned { range_sd_m, q_en, speed_scale, heading_bias_deg, p0_en }, a + b + c + d + e)
    }
}

/// The cross-validated figures of one configuration: every range held out once, predicted by
/// the track smoothed without its fold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CrossValidation {
    pub folds: usize,
    /// Held-out ranges scored (those with a fix and usable geometry).
    pub ranges: usize,
    /// Σ of the held-out ranges' log predictive densities (higher is better).
    pub log_predictive: f64,
    /// RMS residual of the held-out ranges against the filter's prediction and the smoothed track.
    pub rms_filter_m: Option<f64>,
    pub rms_smoothed_m: Option<f64>,
    /// Mean r²/(R + h Pˢ hᵀ) of the held-out ranges: 1 when the smoothed track's claimed
    /// uncertainty and the range noise are right, above 1 when they are too small.
    pub mean_nis_smoothed: Option<f64>,
}

/// The figures of one configuration: cross-validated, and of the full run that uses every range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scored {
    pub values: Tuned,
    /// Innovation log-likelihood of the ranges the full run used.
    pub log_likelihood: f64,
    /// RMS residual of the used ranges: innovation, and against the smoothed track (in-sample).
    pub in_sample_rms_filter_m: Option<f64>,
    pub in_sample_rms_smoothed_m: Option<f64>,
    /// Ranges the full run's innovation gate rejected.
    pub ranges_gated: usize,
    /// The compass's whole bias (deg, clockwise): `heading_bias_deg` and the mean of the full
    /// run's smoothed bias state, which takes up what the fixed offset leaves.
    pub compass_bias_deg: f64,
    /// The held-out ranges' RMS residuals and log predictive density (as in `cross_validation`).
    pub held_out_rms_filter_m: Option<f64>,
    pub held_out_rms_smoothed_m: Option<f64>,
    pub held_out_log_predictive: f64,
    pub cross_validation: CrossValidation,
}

/// Which values the run keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kept {
    /// The search converged to values that predict the held-out ranges better.
    Tuned,
    /// A candidate the search evaluated that predicts the held-out ranges better than the
    /// starting values and rejects no more ranges: the search's result when it stopped at its cap,
    /// or, when that result is not valid, the valid candidate with the best score.
    BestCandidate,
    /// The starting (configured) values: no candidate checked was better.
    Start,
}

/// What the guard decided, and why in one sentence (None when the tuning converged and won).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Guard {
    pub kept: Kept,
    pub converged: bool,
    /// Other candidates of the search scored at full rate because its result was not valid (the
    /// best-scored first, at most [`MAX_CANDIDATES_CHECKED`]).
    pub candidates_checked: usize,
    pub warning: Option<String>,
}

/// Other candidates scored at full rate when the search's result is not valid (invented,
/// docs/models.md#post-tuning): each costs a cross-validation and a full run.
pub const MAX_CANDIDATES_CHECKED: usize = 8;

/// A candidate's values in one phrase.
fn describe(v: &Tuned) -> String {
    format!(
        "range σ {:.3} m, q_en {:.3e} m², speed scale {:.4}, compass offset {:.2}°, p0_en {:.1} m²",
        v.range_sd_m, v.q_en, v.speed_scale, v.heading_bias_deg, v.p0_en
    )
}

impl Guard {
    /// Whether `s` predicts the held-out ranges better than `before` and rejects no more ranges.
    fn valid(before: &Scored, s: &Scored) -> bool {
        s.held_out_log_predictive > before.held_out_log_predictive && s.ranges_gated <= before.ranges_gated
    }

    /// `after` is the search's result; `alternative` the best-scored other valid candidate found
    /// among the `checked` scored when `after` is not valid.
    fn judge(
        before: &Scored,
        after: &Scored,
        alternative: Option<&Scored>,
        checked: usize,
        converged: bool,
        max_iters: u64,
    ) -> Guard {
        let cap = format!("the search stopped at its cap of {max_iters} iterations before converging");
        let also = if converged { String::new() } else { format!(", and {cap}") };
        let (kept, warning) = if Guard::valid(before, after) {
            if converged {
                (Kept::Tuned, None)
            } else {
                let w = format!(
                    "tuning: {cap}; kept its best candidate, which predicts the held-out ranges better than the starting values and rejects no more ranges"
                );
                (Kept::BestCandidate, Some(w))
            }
        } else {
            let why = if !(after.held_out_log_predictive > before.held_out_log_predictive) {
                format!(
                    "the search's result predicts the held-out ranges no better than the starting values (log predictive density {:.2} against {:.2})",
                    after.held_out_log_predictive, before.held_out_log_predictive
                )
            } else {
                format!(
                    "the search's result rejects {} range(s) at the gate where the starting values reject {}",
                    after.ranges_gated, before.ranges_gated
                )
            };
            match alternative {
                Some(a) => (
                    Kept::BestCandidate,
                    Some(format!(
                        "tuning: kept the best-scored other candidate of the search ({}), which predicts the held-out ranges better than the starting values (log predictive density {:.2} against {:.2}) and rejects {} range(s) where they reject {}: {why}{also}",
                        describe(&a.values),
                        a.held_out_log_predictive,
                        before.held_out_log_predictive,
                        a.ranges_gated,
                        before.ranges_gated
                    )),
                ),
                None => {
                    let others = if checked == 0 {
                        "no other candidate of the search predicted them better while rejecting no more ranges".to_string()
                    } else {
                        format!("none of the {checked} best-scored other candidates checked did better")
                    };
                    (Kept::Start, Some(format!("tuning: kept the starting values: {why}, and {others}{also}")))
                }
            }
        };
        Guard { kept, converged, candidates_checked: checked, warning }
    }
}

/// Before and after tuning, the guard's choice and the config the run uses.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TuneReport {
    pub before: Scored,
    /// The search's result (kept or not: see `guard`).
    pub after: Scored,
    /// The figures of the values the run keeps (`before`, `after` or another candidate).
    pub kept: Scored,
    /// The SDs of the search's result.
    pub sd: TunedSd,
    pub bounds: Bounds,
    pub guard: Guard,
    /// The values the run uses: `kept`'s.
    pub chosen: Tuned,
    pub hold_out_every: usize,
    pub iterations: u64,
    pub evaluations: u64,
    #[serde(skip)]
    pub config: PostConfig,
}

#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    #[error(transparent)]
    Post(#[from] PostError),
    #[error("tuning: hold_out_every = {0}; it must be ≥ 2 (every k-th range is left out)")]
    HoldOut(usize),
    #[error("tuning: max_iters must be ≥ 1")]
    NoIterations,
    #[error("tuning: dead_reckoning_block_s = {0}; it must be a finite number ≥ 0 (0: full rate)")]
    Block(f64),
    #[error("tuning: the log has no range the filter could use")]
    NoRanges,
    #[error("tuning: optimiser: {0}")]
    Optimiser(String),
}

/// Sums over the folds' held-out ranges, and over the ranges each fold used.
#[derive(Debug, Default)]
struct Folds {
    log_predictive: f64,
    held_out: Vec<(f64, f64, f64)>,
    /// Σ r²/R and count over the used ranges (R the range noise alone).
    used_excess: (f64, usize),
    /// Ranges the folds' gates rejected, summed over the folds.
    gated: usize,
}

impl Folds {
    fn add(&mut self, r: &PostResult) {
        self.log_predictive += r.summary.held_out_log_predictive;
        self.gated += r.summary.ranges_gated;
        for x in &r.residuals {
            if x.held_out && !x.smoothed.is_nan() {
                self.held_out.push((x.innovation, x.smoothed, x.smoothed_sd));
            } else if x.applied && !x.smoothed.is_nan() && x.noise_sd > 0.0 {
                self.used_excess.0 += (x.smoothed / x.noise_sd).powi(2);
                self.used_excess.1 += 1;
            }
        }
    }
    fn cross_validation(&self, folds: usize) -> CrossValidation {
        let rms = |f: &dyn Fn(&(f64, f64, f64)) -> f64| {
            let n = self.held_out.len();
            (n > 0).then(|| (self.held_out.iter().map(|x| f(x).powi(2)).sum::<f64>() / n as f64).sqrt())
        };
        CrossValidation {
            folds,
            ranges: self.held_out.len(),
            log_predictive: self.log_predictive,
            rms_filter_m: rms(&|x| x.0),
            rms_smoothed_m: rms(&|x| x.1),
            mean_nis_smoothed: rms(&|x| x.1 / x.2).map(|v| v * v),
        }
    }
}

/// Runs the `folds` cross-validation passes of `cfg` over `rows` (predicting in steps of `step_s`).
fn folds(rows: &[LogRow], cfg: &PostConfig, folds: usize, step_s: Option<f64>) -> Result<Folds, PostError> {
    let mut sum = Folds::default();
    for phase in 0..folds {
        let pass = Pass { hold_out_every: folds, hold_out_phase: phase, prediction_step_s: step_s, ..Pass::FULL };
        sum.add(&run(rows, cfg, pass)?);
    }
    Ok(sum)
}

/// The full-rate cross-validation of `cfg` over `rows` in `folds` folds (≥ 2): what a run with
/// these values says about its own accuracy on ranges it did not use.
pub fn cross_validate(rows: &[LogRow], cfg: &PostConfig, k: usize) -> Result<CrossValidation, TuneError> {
    if k < 2 {
        return Err(TuneError::HoldOut(k));
    }
    Ok(folds(rows, cfg, k, None)?.cross_validation(k))
}

/// The search: its rows (block-averaged or the log's own) and prediction step (None: `auv.step_s`).
struct Problem<'a> {
    rows: Cow<'a, [LogRow]>,
    step_s: Option<f64>,
    base: &'a PostConfig,
    start: Tuned,
    bounds: Bounds,
    hold_out_every: usize,
    /// Every candidate the search evaluated, in order.
    searched: RefCell<Vec<Candidate>>,
}

/// One candidate the search evaluated: its search coordinates, cost, and its folds' held-out log
/// predictive density and gated ranges (on the search's rows).
#[derive(Debug, Clone, PartialEq)]
struct Candidate {
    u: Vec<f64>,
    cost: f64,
    log_predictive: f64,
    gated: usize,
}

/// The cost of a run the filter or smoother could not complete (a singular covariance at an
/// extreme candidate): worse than any completed one.
const FAILED: f64 = 1e12;

impl Problem<'_> {
    /// Negative cross-validated log predictive density, plus the prior, the consistency floor
    /// and a penalty outside the bounds.
    fn cost(&self, u: &[f64]) -> f64 {
        let (values, outside) = self.bounds.from_search(u);
        let Ok(f) = folds(&self.rows, &values.apply(self.base), self.hold_out_every, self.step_s) else {
            return FAILED;
        };
        let cost = -f.log_predictive + self.prior(&values) + floor_penalty(f.used_excess) + 1e3 * outside;
        let c = Candidate { u: u.to_vec(), cost, log_predictive: f.log_predictive, gated: f.gated };
        self.searched.borrow_mut().push(c);
        cost
    }

    /// −log of the Gaussian prior about the start, in search coordinates.
    fn prior(&self, values: &Tuned) -> f64 {
        let (v, s) = (values.to_search(), self.start.to_search());
        v.iter().zip(&s).zip(PRIOR_SD).map(|((v, s), sd)| 0.5 * ((v - s) / sd).powi(2)).sum()
    }

    /// The diagonal SDs of the cost's curvature at `u` (search coordinates), in the values' units.
    fn sd(&self, u: &[f64], values: &Tuned) -> TunedSd {
        let c0 = self.cost(u);
        let mut sd = [None; 5];
        for (i, step) in CURVATURE_STEPS.iter().enumerate() {
            let at = |d: f64| {
                let mut v = u.to_vec();
                v[i] += d;
                // At a bound the curvature is the penalty's, not the log's: no SD.
                (self.bounds.from_search(&v).1 == 0.0).then(|| self.cost(&v))
            };
            let (Some(up), Some(down)) = (at(*step), at(-*step)) else { continue };
            let curvature = (up - 2.0 * c0 + down) / (step * step);
            sd[i] = (curvature > 0.0 && curvature.is_finite()).then(|| 1.0 / curvature.sqrt());
        }
        // Log coordinates: an SD s of ln v is about v·s in v.
        TunedSd {
            range_sd_m: sd[0].map(|s| s * values.range_sd_m),
            q_en: sd[1].map(|s| s * values.q_en),
            speed_scale: sd[2],
            heading_bias_deg: sd[3],
            p0_en: sd[4].map(|s| s * values.p0_en),
        }
    }
}

/// The range σ's consistency floor: the smoothed track's residuals on the ranges it used have
/// variance R − h Pˢ hᵀ ≤ R when the noise is right, so a mean r²/R above 1 says the range σ is
/// set below what the log shows. Each range's excess costs as much as a unit of log density
/// (invented weight, docs/models.md#post-tuning).
fn floor_penalty((sum, n): (f64, usize)) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mean = sum / n as f64;
    n as f64 * (mean - 1.0).max(0.0)
}

/// The full-rate figures of `values`: the cross-validation and the full run.
fn score(rows: &[LogRow], base: &PostConfig, k: usize, values: Tuned) -> Result<Scored, PostError> {
    let cfg = values.apply(base);
    let cv = folds(rows, &cfg, k, None)?.cross_validation(k);
    let full = run(rows, &cfg, Pass::FULL)?;
    let s = &full.summary;
    let n = full.samples.len().max(1) as f64;
    let bias_state = full.samples.iter().map(|x| x.smoothed_heading_bias).sum::<f64>() / n;
    Ok(Scored {
        // b is the reading's offset in math heading (counter-clockwise), the compass's is clockwise.
        compass_bias_deg: values.heading_bias_deg - bias_state.to_degrees(),
        values,
        log_likelihood: s.range_log_likelihood,
        in_sample_rms_filter_m: s.residual_rms_filter_m,
        in_sample_rms_smoothed_m: s.residual_rms_smoothed_m,
        ranges_gated: s.ranges_gated,
        held_out_rms_filter_m: cv.rms_filter_m,
        held_out_rms_smoothed_m: cv.rms_smoothed_m,
        held_out_log_predictive: cv.log_predictive,
        cross_validation: cv,
    })
}

/// A running mean of one dead-reckoning kind within a block: the first row's time, the sums of
/// times, values and variances.
#[derive(Debug, Clone, Copy, Default)]
struct BlockMean {
    n: usize,
    first_t: f64,
    sum_t: f64,
    sum: [f64; 2],
    sum_variance: f64,
}

impl BlockMean {
    fn add(&mut self, t: f64, v: [f64; 2], sd: f64) {
        if self.n == 0 {
            self.first_t = t;
        }
        self.n += 1;
        self.sum_t += t;
        self.sum = [self.sum[0] + v[0], self.sum[1] + v[1]];
        self.sum_variance += sd * sd;
    }
    /// (first time, mean time, mean value, SD of the mean) of the rows added since the last take.
    fn take(&mut self) -> Option<(f64, f64, [f64; 2], f64)> {
        let m = std::mem::take(self);
        let n = m.n as f64;
        (m.n > 0).then(|| (m.first_t, m.sum_t / n, [m.sum[0] / n, m.sum[1] / n], m.sum_variance.sqrt() / n))
    }
}

/// The block means of every dead-reckoning kind.
#[derive(Debug, Default)]
struct DeadReckoningBlock {
    yaw_rate: BlockMean,
    speed: BlockMean,
    /// Compass readings as (sin, cos): the circular mean needs no unwrapping across north.
    heading: BlockMean,
    dvl_body: BlockMean,
    dvl_earth: BlockMean,
    depth: BlockMean,
}

impl DeadReckoningBlock {
    /// Adds a dead-reckoning row (false for any other kind). The SDs are the rows' own or the
    /// config's, so that each mean carries the SD of an average of independent readings.
    fn add(&mut self, row: &LogRow, cfg: &PostConfig) -> bool {
        let t = row.t;
        match row.obs {
            Observation::YawRate { compass_deg_s } => self.yaw_rate.add(t, [compass_deg_s, 0.0], 0.0),
            Observation::Speed(s) => self.speed.add(t, [s, 0.0], row.sigma.unwrap_or(cfg.auv.sigma_speed)),
            Observation::Heading { compass_deg } => {
                let c = compass_deg.to_radians();
                self.heading.add(t, [c.sin(), c.cos()], row.sigma.unwrap_or(cfg.auv.sigma_heading.to_degrees()))
            }
            Observation::Velocity { frame, v } => {
                let sd = row.sigma.unwrap_or(cfg.velocity_sd_m_s);
                match frame {
                    VelocityFrame::Body => self.dvl_body.add(t, v, sd),
                    VelocityFrame::Earth => self.dvl_earth.add(t, v, sd),
                }
            }
            Observation::Depth(z) => self.depth.add(t, [z, 0.0], 0.0),
            _ => return false,
        }
        true
    }

    /// The block's averaged rows. The yaw rate's mean goes at the block's first yaw-rate time, so
    /// that held until the next block's it integrates to the same heading change; the readings go
    /// at their mean time.
    fn flush(&mut self, out: &mut Vec<LogRow>) {
        let row = |t, obs, sigma| LogRow { t, obs, sigma };
        if let Some((first, _, v, _)) = self.yaw_rate.take() {
            out.push(row(first, Observation::YawRate { compass_deg_s: v[0] }, None));
        }
        if let Some((_, t, v, sd)) = self.speed.take() {
            out.push(row(t, Observation::Speed(v[0]), Some(sd)));
        }
        if let Some((_, t, v, sd)) = self.heading.take() {
            let compass_deg = v[0].atan2(v[1]).to_degrees().rem_euclid(360.0);
            out.push(row(t, Observation::Heading { compass_deg }, Some(sd)));
        }
        for (mean, frame) in [(&mut self.dvl_body, VelocityFrame::Body), (&mut self.dvl_earth, VelocityFrame::Earth)] {
            if let Some((_, t, v, sd)) = mean.take() {
                out.push(row(t, Observation::Velocity { frame, v }, Some(sd)));
            }
        }
        if let Some((_, t, v, _)) = self.depth.take() {
            out.push(row(t, Observation::Depth(v[0]), None));
        }
    }
}

/// The rows with the dead reckoning averaged over blocks of `block_s` seconds counted from the
/// first `init` row (so no block straddles the filter's start); every other row as it is.
fn block_averaged(rows: &[LogRow], block_s: f64, cfg: &PostConfig) -> Vec<LogRow> {
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| rows[a].t.total_cmp(&rows[b].t));
    let start =
        order.iter().map(|&i| &rows[i]).find(|r| matches!(r.obs, Observation::Init { .. })).map_or(0.0, |r| r.t);
    let mut out = Vec::new();
    let mut block = DeadReckoningBlock::default();
    let mut current = None;
    for row in order.iter().map(|&i| &rows[i]) {
        let index = ((row.t - start) / block_s).floor();
        if current != Some(index) {
            block.flush(&mut out);
            current = Some(index);
        }
        if !block.add(row, cfg) {
            out.push(*row);
        }
    }
    block.flush(&mut out);
    out
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(Problem::cost(self, u))
    }
}

/// Tunes `cfg` on the log, starting from its own values.
pub fn tune(rows: &[LogRow], cfg: &PostConfig, opts: &TuneOptions) -> Result<TuneReport, TuneError> {
    if opts.hold_out_every < 2 {
        return Err(TuneError::HoldOut(opts.hold_out_every));
    }
    if opts.max_iters == 0 {
        return Err(TuneError::NoIterations);
    }
    let block_s = opts.dead_reckoning_block_s;
    if !(block_s.is_finite() && block_s >= 0.0) {
        return Err(TuneError::Block(block_s));
    }
    cfg.validate()?;
    let start = Tuned::of(cfg);
    let k = opts.hold_out_every;
    let before = score(rows, cfg, k, start)?;
    if before.in_sample_rms_filter_m.is_none() {
        return Err(TuneError::NoRanges);
    }
    let (rows_searched, step_s) = if block_s > cfg.auv.step_s {
        (Cow::Owned(block_averaged(rows, block_s, cfg)), Some(block_s))
    } else {
        (Cow::Borrowed(rows), None)
    };
    let bounds = Bounds::of(&start);
    let problem = Problem {
        rows: rows_searched,
        step_s,
        base: cfg,
        start,
        bounds,
        hold_out_every: k,
        searched: RefCell::new(Vec::new()),
    };
    // The start's figures on the search's rows, for the other candidates' pre-selection.
    let start_folds = folds(&problem.rows, cfg, k, step_s)?;
    // Initial simplex: the start and one vertex per coordinate, a step typical of its scale.
    let origin = start.to_search();
    let mut simplex = vec![origin.clone()];
    for (i, step) in SIMPLEX_STEPS.iter().enumerate() {
        let mut v = origin.clone();
        v[i] += step;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(1e-3).map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(opts.max_iters))
        .run()
        .map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let problem = res.problem.problem.as_ref().ok_or_else(|| TuneError::Optimiser("no problem returned".into()))?;
    let state = res.state();
    let best = state.get_best_param().cloned().unwrap_or(origin);
    let evaluations = state.get_func_counts().get("cost_count").copied().unwrap_or(0);
    let iterations = state.get_iter();
    let converged = iterations < opts.max_iters;
    let searched = problem.searched.take();
    let (values, _) = bounds.from_search(&best);
    let sd = problem.sd(&best, &values);
    let after = score(rows, cfg, k, values)?;
    // When the result is not valid, the other candidates that beat the start on the search's own
    // folds, best-scored first and each set of values once, are scored at full rate in turn.
    let mut alternative = None;
    let mut checked = 0;
    if !Guard::valid(&before, &after) {
        let mut pool: Vec<(Tuned, f64)> = searched
            .iter()
            .filter(|c| {
                c.cost < FAILED && c.log_predictive > start_folds.log_predictive && c.gated <= start_folds.gated
            })
            .map(|c| (bounds.from_search(&c.u).0, c.cost))
            .filter(|(v, _)| *v != values && *v != start)
            .collect();
        pool.sort_by(|a, b| a.1.total_cmp(&b.1));
        pool.dedup_by(|a, b| a.0 == b.0);
        for (v, _) in pool.into_iter().take(MAX_CANDIDATES_CHECKED) {
            checked += 1;
            let s = score(rows, cfg, k, v)?;
            if Guard::valid(&before, &s) {
                alternative = Some(s);
                break;
            }
        }
    }
    let guard = Guard::judge(&before, &after, alternative.as_ref(), checked, converged, opts.max_iters);
    let kept = match (guard.kept, alternative) {
        (Kept::Start, _) => before,
        (Kept::BestCandidate, Some(a)) => a,
        _ => after,
    };
    let chosen = kept.values;
    let mut config = chosen.apply(cfg);
    if let (Some(s), true) = (sd.heading_bias_deg, guard.kept != Kept::Start) {
        // The compass-bias state starts no narrower than the tuned bias is known.
        config.auv.p0[BIAS] = config.auv.p0[BIAS].max(s.to_radians().powi(2));
    }
    Ok(TuneReport {
        before,
        after,
        kept,
        sd,
        bounds,
        guard,
        chosen,
        hold_out_every: k,
        iterations,
        evaluations,
        config,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t: f64, obs: Observation, sigma: Option<f64>) -> LogRow {
        LogRow { t, obs, sigma }
    }

    #[test]
    fn blocks_average_each_dead_reckoning_kind_and_keep_other_rows() {
        let cfg = PostConfig::default();
        let init = row(0.0, Observation::Init { e: 0.0, n: 0.0, speed: 1.0, compass_deg: 0.0 }, None);
        let range = row(0.55, Observation::Range { beacon: 3, travel_time: 0.2 }, None);
        let mut rows = vec![init, range];
        for (i, compass_deg) in [359.0, 359.5, 0.5, 1.0].into_iter().enumerate() {
            let t = 0.1 + 0.2 * i as f64;
            rows.push(row(t, Observation::YawRate { compass_deg_s: i as f64 }, None));
            rows.push(row(t, Observation::Speed(1.0 + 0.1 * i as f64), None));
            rows.push(row(t, Observation::Heading { compass_deg }, Some(0.4)));
            rows.push(row(t, Observation::Velocity { frame: VelocityFrame::Earth, v: [i as f64, 1.0] }, None));
        }
        rows.push(row(1.2, Observation::Speed(2.0), Some(0.3)));
        let out = block_averaged(&rows, 1.0, &cfg);
        let of = |f: &dyn Fn(&Observation) -> bool| out.iter().filter(|r| f(&r.obs)).copied().collect::<Vec<_>>();
        assert_eq!(of(&|o| matches!(o, Observation::Init { .. } | Observation::Range { .. })), vec![init, range]);
        let yaw = of(&|o| matches!(o, Observation::YawRate { .. }));
        assert_eq!(yaw, vec![row(0.1, Observation::YawRate { compass_deg_s: 1.5 }, None)]);
        let speed = of(&|o| matches!(o, Observation::Speed(_)));
        assert_eq!(speed.len(), 2);
        assert!((speed[0].t - 0.4).abs() < 1e-12);
        assert!(matches!(speed[0].obs, Observation::Speed(s) if (s - 1.15).abs() < 1e-12));
        assert!((speed[0].sigma.unwrap() - cfg.auv.sigma_speed / 2.0).abs() < 1e-12);
        assert_eq!(speed[1], row(1.2, Observation::Speed(2.0), Some(0.3)));
        // Across north the circular mean is 0°, not 180°.
        let heading = of(&|o| matches!(o, Observation::Heading { .. }));
        let Observation::Heading { compass_deg } = heading[0].obs else { unreachable!() };
        assert!(compass_deg.min(360.0 - compass_deg) < 1e-9, "{compass_deg}");
        assert!((heading[0].sigma.unwrap() - 0.2).abs() < 1e-12);
        let dvl = of(&|o| matches!(o, Observation::Velocity { .. }));
        let Observation::Velocity { frame: VelocityFrame::Earth, v } = dvl[0].obs else { unreachable!() };
        assert_eq!((dvl.len(), v), (1, [1.5, 1.0]));
        assert!((dvl[0].sigma.unwrap() - cfg.velocity_sd_m_s / 2.0).abs() < 1e-12);
    }

    fn scored(held_out_log_predictive: f64, ranges_gated: usize) -> Scored {
        let values = Tuned::of(&PostConfig::default());
        let cross_validation = CrossValidation {
            folds: 5,
            ranges: 50,
            log_predictive: held_out_log_predictive,
            rms_filter_m: None,
            rms_smoothed_m: None,
            mean_nis_smoothed: None,
        };
        Scored {
            values,
            log_likelihood: 0.0,
            in_sample_rms_filter_m: None,
            in_sample_rms_smoothed_m: None,
            ranges_gated,
            compass_bias_deg: 0.0,
            held_out_rms_filter_m: None,
            held_out_rms_smoothed_m: None,
            held_out_log_predictive,
            cross_validation,
        }
    }

    #[test]
    fn the_guard_keeps_the_start_unless_the_result_predicts_better_and_rejects_no_more() {
        let start = scored(-100.0, 2);
        let g = Guard::judge(&start, &scored(-80.0, 2), None, 0, true, 50);
        assert_eq!((g.kept, g.warning), (Kept::Tuned, None));
        let g = Guard::judge(&start, &scored(-80.0, 2), None, 0, false, 50);
        assert_eq!(g.kept, Kept::BestCandidate);
        assert!(g.warning.unwrap().contains("cap of 50 iterations"));
        let g = Guard::judge(&start, &scored(-120.0, 2), None, 8, true, 50);
        assert_eq!(g.kept, Kept::Start);
        let w = g.warning.unwrap();
        assert!(w.contains("no better") && w.contains("none of the 8"), "{w}");
        let g = Guard::judge(&start, &scored(-100.0, 2), None, 0, true, 50);
        assert_eq!(g.kept, Kept::Start, "equal is not better");
        let g = Guard::judge(&start, &scored(-80.0, 3), None, 3, false, 50);
        assert_eq!(g.kept, Kept::Start);
        let w = g.warning.unwrap();
        assert!(w.contains("rejects 3 range(s)") && w.contains("reject 2") && w.contains("cap of 50"), "{w}");
        assert_eq!(w.matches("tuning:").count(), 1, "one warning: {w}");
    }

    #[test]
    fn the_guard_keeps_a_valid_other_candidate_and_says_which_and_why() {
        let start = scored(-100.0, 2);
        let other = scored(-90.0, 2);
        let g = Guard::judge(&start, &scored(-80.0, 4), Some(&other), 2, true, 50);
        assert_eq!((g.kept, g.candidates_checked), (Kept::BestCandidate, 2));
        let w = g.warning.unwrap();
        assert!(w.contains("range σ 1.800 m") && w.contains("-90.00 against -100.00"), "{w}");
        assert!(w.contains("rejects 2 range(s) where they reject 2") && w.contains("rejects 4 range(s)"), "{w}");
        assert_eq!(w.matches("tuning:").count(), 1, "one warning: {w}");
    }

    #[test]
    fn the_floor_costs_only_residuals_larger_than_the_noise() {
        assert_eq!(floor_penalty((40.0, 50)), 0.0);
        assert_eq!(floor_penalty((0.0, 0)), 0.0);
        assert!((floor_penalty((100.0, 50)) - 50.0).abs() < 1e-12);
    }

    #[test]
    fn a_bad_block_length_is_refused() {
        let opts = TuneOptions { dead_reckoning_block_s: -1.0, ..TuneOptions::default() };
        let e = tune(&[], &PostConfig::default(), &opts).unwrap_err().to_string();
        assert!(e.contains("dead_reckoning_block_s = -1") && e.contains("≥ 0"), "{e}");
    }
}
