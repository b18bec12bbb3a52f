//! Tuning the post-processing filter from the log itself: the range σ, the
//! E/N process noise, the speed log's scale and the compass bias that maximise the innovation
//! log-likelihood of the ranges (`PostSummary::range_log_likelihood`), by a Nelder–Mead search
//! (argmin) in log/linear coordinates, with cross-validation: every k-th range is left out of the
//! filter during tuning and only predicted, so its residual before and after tuning is an honest
//! out-of-sample figure beside the in-sample one.
//!
//! Speed: the search runs the forward filter only, over the log with its dead-reckoning rows
//! averaged in blocks (`dead_reckoning_block_s`) and predicted in steps of that length; the
//! likelihood needs only the range innovations, and the dead reckoning between two ranges carries
//! the same information averaged. The before/after figures are always the full-rate smoothed runs.

use crate::auv::VelocityFrame;
use crate::fieldlog::{LogRow, Observation};
use crate::post::{run, Pass, PostConfig, PostError, PostSummary};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// How to tune.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TuneOptions {
    /// Leave every k-th range out (≥ 2).
    pub hold_out_every: usize,
    /// Nelder–Mead iterations at most.
    pub max_iters: u64,
    /// During the search, the yaw-rate, speed, heading, DVL and depth rows are averaged over blocks
    /// of this many seconds and the filter predicts in steps of this length (0: every row at full
    /// rate). Invented default: 1 s keeps the tuned values within the bands `tests/post_tune.rs`
    /// states of the full-rate ones, at a fraction of the time.
    pub dead_reckoning_block_s: f64,
}

impl Default for TuneOptions {
    fn default() -> Self {
        TuneOptions { hold_out_every: 5, max_iters: 80, dead_reckoning_block_s: 1.0 }
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
}

/// Bounds of the search (invented): wide enough for any working sensor.
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
    #[error("tuning: dead_reckoning_block_s = {0}; it must be a finite number ≥ 0 (0: full rate)")]
    Block(f64),
    #[error("tuning: the log has no range the filter could use")]
    NoRanges,
    #[error("tuning: optimiser: {0}")]
    Optimiser(String),
}

/// The search: its rows (block-averaged or the log's own) and prediction step (None: `auv.step_s`).
struct Problem<'a> {
    rows: Cow<'a, [LogRow]>,
    step_s: Option<f64>,
    base: &'a PostConfig,
    hold_out_every: usize,
}

impl Problem<'_> {
    /// Negative log-likelihood of the forward filter, plus a penalty outside the bounds.
    fn cost(&self, u: &[f64]) -> Result<f64, PostError> {
        let (values, outside) = Tuned::from_search(u);
        let pass = Pass { smooth: false, hold_out_every: self.hold_out_every, prediction_step_s: self.step_s };
        let r = run(&self.rows, &values.apply(self.base), pass)?;
        Ok(-r.summary.range_log_likelihood + 1e3 * outside)
    }
}

/// The full-rate smoothed figures of `values` (before and after the search).
fn score(rows: &[LogRow], base: &PostConfig, hold_out_every: usize, values: Tuned) -> Result<Scored, PostError> {
    let pass = Pass { smooth: true, hold_out_every, prediction_step_s: None };
    let r = run(rows, &values.apply(base), pass)?;
    Ok(Scored::of(values, &r.summary))
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
    let block_s = opts.dead_reckoning_block_s;
    if !(block_s.is_finite() && block_s >= 0.0) {
        return Err(TuneError::Block(block_s));
    }
    cfg.validate()?;
    let start = Tuned::of(cfg);
    let before = score(rows, cfg, opts.hold_out_every, start)?;
    if before.in_sample_rms_filter_m.is_none() {
        return Err(TuneError::NoRanges);
    }
    let problem = if block_s > cfg.auv.step_s {
        let rows = Cow::Owned(block_averaged(rows, block_s, cfg));
        Problem { rows, step_s: Some(block_s), base: cfg, hold_out_every: opts.hold_out_every }
    } else {
        Problem { rows: Cow::Borrowed(rows), step_s: None, base: cfg, hold_out_every: opts.hold_out_every }
    };
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
    let after = score(rows, cfg, opts.hold_out_every, values)?;
    Ok(TuneReport {
        before,
        after,
        hold_out_every: opts.hold_out_every,
        iterations,
        evaluations,
        config: values.apply(cfg),
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

    #[test]
    fn a_bad_block_length_is_refused() {
        let opts = TuneOptions { dead_reckoning_block_s: -1.0, ..TuneOptions::default() };
        let e = tune(&[], &PostConfig::default(), &opts).unwrap_err().to_string();
        assert!(e.contains("dead_reckoning_block_s = -1") && e.contains("≥ 0"), "{e}");
    }
}
