//! Tuning the post-processing filter from the log itself (issue 12 item 4): the range σ, the
//! E/N process noise, the speed log's scale and the compass bias that maximise the innovation
//! log-likelihood of the ranges (`PostSummary::range_log_likelihood`), by a Nelder–Mead search
//! (argmin) in log/linear coordinates, with cross-validation: every k-th range is left out of the
//! filter during tuning and only predicted, so its residual before and after tuning is an honest
//! out-of-sample figure beside the in-sample one.

use crate::fieldlog::LogRow;
use crate::post::{run, Pass, PostConfig, PostError, PostSummary};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::{Deserialize, Serialize};

/// How to tune.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TuneOptions {
    /// Leave every k-th range out (≥ 2).
    pub hold_out_every: usize,
    /// Nelder–Mead iterations at most.
    pub max_iters: u64,
}

impl Default for TuneOptions {
    fn default() -> Self {
        TuneOptions { hold_out_every: 5, max_iters: 80 }
    }
}

/// The tuned quantities.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tuned {
    /// Range SD at zero range, c·σ_τ (m).
    pub range_sd_m: f64,
    /// Per-step E and N process noise q[0] = q[1] (m²).
    pub q_en: f64,
    pub speed_scale: f64,
    pub heading_bias_deg: f64,
}

/// Bounds of the search (invented, issue 12): wide enough for any working sensor.
const RANGE_SD_M: (f64, f64) = (0.05, 50.0);
const Q_EN: (f64, f64) = (1e-8, 3.0);
const SPEED_SCALE: (f64, f64) = (0.7, 1.4);
const HEADING_BIAS_DEG: (f64, f64) = (-30.0, 30.0);

impl Tuned {
    fn of(cfg: &PostConfig) -> Tuned {
        Tuned {
            range_sd_m: cfg.auv.range_noise.sound_speed * cfg.auv.range_noise.sigma_time,
            q_en: cfg.auv.q[0],
            speed_scale: cfg.speed_scale,
            heading_bias_deg: cfg.heading_bias_deg,
        }
    }
    fn apply(&self, cfg: &PostConfig) -> PostConfig {
        let mut c = cfg.clone();
        c.auv.range_noise.sigma_time = self.range_sd_m / c.auv.range_noise.sound_speed;
        c.auv.q[0] = self.q_en;
        c.auv.q[1] = self.q_en;
        c.speed_scale = self.speed_scale;
        c.heading_bias_deg = self.heading_bias_deg;
        c
    }
    /// Search coordinates: logs of the variances' scales, the others as they are.
    fn to_search(self) -> Vec<f64> {
        vec![self.range_sd_m.ln(), self.q_en.ln(), self.speed_scale, self.heading_bias_deg]
    }
    /// Back from search coordinates, clamped into the bounds; also how far outside they were.
    fn from_search(u: &[f64]) -> (Tuned, f64) {
        let clamp = |v: f64, (lo, hi): (f64, f64)| (v.clamp(lo, hi), (v - v.clamp(lo, hi)).abs());
        let (range_sd_m, a) = clamp(u[0].exp(), RANGE_SD_M);
        let (q_en, b) = clamp(u[1].exp(), Q_EN);
        let (speed_scale, c) = clamp(u[2], SPEED_SCALE);
        let (heading_bias_deg, d) = clamp(u[3], HEADING_BIAS_DEG);
        (Tuned { range_sd_m, q_en, speed_scale, heading_bias_deg }, a + b + c + d)
    }
}

/// The figures of one configuration, all with the same ranges held out.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scored {
    pub values: Tuned,
    /// Innovation log-likelihood of the ranges the filter used.
    pub log_likelihood: f64,
    /// RMS residual of the used ranges: innovation, and against the smoothed track (in-sample).
    pub in_sample_rms_filter_m: Option<f64>,
    pub in_sample_rms_smoothed_m: Option<f64>,
    /// RMS residual of the held-out ranges against the filter's prediction and the smoothed track.
    pub held_out_rms_filter_m: Option<f64>,
    pub held_out_rms_smoothed_m: Option<f64>,
}

impl Scored {
    fn of(values: Tuned, s: &PostSummary) -> Scored {
        Scored {
            values,
            log_likelihood: s.range_log_likelihood,
            in_sample_rms_filter_m: s.residual_rms_filter_m,
            in_sample_rms_smoothed_m: s.residual_rms_smoothed_m,
            held_out_rms_filter_m: s.held_out_rms_filter_m,
            held_out_rms_smoothed_m: s.held_out_rms_smoothed_m,
        }
    }
}

/// Before and after tuning, and the tuned config.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TuneReport {
    pub before: Scored,
    pub after: Scored,
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
    #[error("tuning: the log has no range the filter could use")]
    NoRanges,
    #[error("tuning: optimiser: {0}")]
    Optimiser(String),
}

struct Problem<'a> {
    rows: &'a [LogRow],
    base: &'a PostConfig,
    hold_out_every: usize,
}

impl Problem<'_> {
    /// Negative log-likelihood of the forward filter, plus a penalty outside the bounds.
    fn cost(&self, u: &[f64]) -> Result<f64, PostError> {
        let (values, outside) = Tuned::from_search(u);
        let pass = Pass { smooth: false, hold_out_every: self.hold_out_every };
        let r = run(self.rows, &values.apply(self.base), pass)?;
        Ok(-r.summary.range_log_likelihood + 1e3 * outside)
    }
    fn score(&self, values: Tuned) -> Result<Scored, PostError> {
        let pass = Pass { smooth: true, hold_out_every: self.hold_out_every };
        let r = run(self.rows, &values.apply(self.base), pass)?;
        Ok(Scored::of(values, &r.summary))
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(Problem::cost(self, u)?)
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
    cfg.validate()?;
    let problem = Problem { rows, base: cfg, hold_out_every: opts.hold_out_every };
    let start = Tuned::of(cfg);
    let before = problem.score(start)?;
    if before.in_sample_rms_filter_m.is_none() {
        return Err(TuneError::NoRanges);
    }
    // Initial simplex: the start and one vertex per coordinate, a step typical of its scale.
    let origin = start.to_search();
    let steps = [0.5, 1.5, 0.03, 2.0];
    let mut simplex = vec![origin.clone()];
    for (i, step) in steps.iter().enumerate() {
        let mut v = origin.clone();
        v[i] += step;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(1e-3).map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(opts.max_iters))
        .run()
        .map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let state = res.state();
    let best = state.get_best_param().cloned().unwrap_or(origin);
    let evaluations = state.get_func_counts().get("cost_count").copied().unwrap_or(0);
    let iterations = state.get_iter();
    let (values, _) = Tuned::from_search(&best);
    let problem = Problem { rows, base: cfg, hold_out_every: opts.hold_out_every };
    let after = problem.score(values)?;
    Ok(TuneReport {
        before,
        after,
        hold_out_every: opts.hold_out_every,
        iterations,
        evaluations,
        config: values.apply(cfg),
    })
}
