//! The references a tune of a synthetic log is judged against (docs/models.md#post-tuning), for
//! logs whose noise and truth are known:
//!
//! - [`true_noise`]: the post-processing config with the noise the log was written with (range
//!   σ and its τ-proportional part, the speed log's scale and SD, the compass's offset and SD),
//!   no unmodelled E/N motion, and the configured initial variance. It is what a user who knew
//!   the sensors exactly would run.
//! - [`truth_tuned_cross_validated`]: the five values the tuner searches, chosen by Nelder–Mead to
//!   minimise the smoothed RMS error against the truth of one half of the log and scored on the
//!   other half, each half in turn. Tuned and scored on the same truth the search fits that
//!   truth's noise (mean NEES near 0: decimetres of error with metres of claimed σ), so the
//!   in-sample value is a bound no estimator without the truth could approach; the held-out one
//!   is what the truth can teach about the settings, which is the ceiling a tune is held to.

use crate::fieldlog::LogRow;
use crate::post::{postprocess_rows, PostConfig, PostError, PostResult};
use crate::synthetic::SyntheticSpec;
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;

/// The E/N process noise of the true-noise reference (m² per step): the tuner's lower bound,
/// since the synthetic AUV moves exactly as its speed through the water and heading say.
pub const TRUE_Q_EN: f64 = 1e-8;

/// `base` with the noise `spec` writes.
pub fn true_noise(spec: &SyntheticSpec, base: &PostConfig) -> PostConfig {
    let mut c = base.clone();
    let rn = &mut c.auv.range_noise;
    rn.sigma_time = spec.range_sd_m / rn.sound_speed;
    rn.sigma_sound_speed = spec.sigma_sound_speed;
    c.speed_scale = spec.speed_scale;
    c.heading_bias_deg = spec.heading_bias_deg;
    c.auv.sigma_speed = spec.speed_sd;
    c.auv.sigma_heading = spec.heading_sd_deg.to_radians();
    (c.auv.q[0], c.auv.q[1]) = (TRUE_Q_EN, TRUE_Q_EN);
    c
}

/// `base` at search coordinates (ln range σ, ln q_en, speed scale, compass offset, ln p0_en), as
/// the tuner applies them.
fn at(base: &PostConfig, u: &[f64]) -> PostConfig {
    let mut c = base.clone();
    c.auv.range_noise.sigma_time = u[0].exp() / c.auv.range_noise.sound_speed;
    (c.auv.q[0], c.auv.q[1]) = (u[1].exp(), u[1].exp());
    (c.speed_scale, c.heading_bias_deg) = (u[2], u[3]);
    (c.auv.p0[0], c.auv.p0[1]) = (u[4].exp(), u[4].exp());
    c
}

/// Squared smoothed errors and NEES at the truth points within `[from, to)` s.
fn errors(r: &PostResult, from: f64, to: f64) -> (Vec<f64>, Vec<f64>) {
    let mut sq = Vec::new();
    let mut nees = Vec::new();
    for s in r.samples.iter().filter(|s| (from..to).contains(&s.t)) {
        let Some(tr) = s.truth else { continue };
        let (de, dn) = (s.smoothed[0] - tr[0], s.smoothed[1] - tr[1]);
        sq.push(de * de + dn * dn);
        let (a, c, b) = (s.smoothed_sd[0].powi(2), s.smoothed_sd[1].powi(2), s.smoothed_cov_en);
        let det = a * c - b * b;
        if det > 0.0 {
            nees.push((c * de * de - 2.0 * b * de * dn + a * dn * dn) / det);
        }
    }
    (sq, nees)
}

struct HalfRms<'a> {
    rows: &'a [LogRow],
    base: &'a PostConfig,
    from: f64,
    to: f64,
}

impl CostFunction for HalfRms<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let Ok(r) = postprocess_rows(self.rows, &at(self.base, u)) else { return Ok(1e9) };
        let (sq, _) = errors(&r, self.from, self.to);
        Ok(if sq.is_empty() { 1e9 } else { (sq.iter().sum::<f64>() / sq.len() as f64).sqrt() })
    }
}

/// One half's truth-tuned values and what they give on the other half.
#[derive(Debug, Clone, PartialEq)]
pub struct HalfFit {
    /// The truth used to choose the values: `[from, to)` s.
    pub tuned_on_s: (f64, f64),
    /// The chosen config's search coordinates (ln range σ, ln q_en, speed scale, compass offset,
    /// ln p0_en).
    pub values: Vec<f64>,
    /// RMS on the half it was tuned on (in-sample) and on the other half (held out) (m).
    pub rms_in_sample_m: f64,
    pub rms_held_out_m: f64,
}

/// The cross-validated truth-tuned reference: the two halves' held-out errors pooled.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthTuned {
    pub halves: [HalfFit; 2],
    /// RMS error over every truth point, each scored with the values tuned on the other half (m).
    pub rms_m: f64,
    /// Mean position NEES over the same points (2 when consistent).
    pub mean_nees: f64,
}

/// Nelder–Mead from `base`'s own values, steps and tolerance of the tuner's search, at most
/// `max_iters` iterations.
fn fit(rows: &[LogRow], base: &PostConfig, from: f64, to: f64, max_iters: u64) -> Result<Vec<f64>, PostError> {
    let origin = vec![
        (base.auv.range_noise.sound_speed * base.auv.range_noise.sigma_time).ln(),
        base.auv.q[0].ln(),
        base.speed_scale,
        base.heading_bias_deg,
        base.auv.p0[0].ln(),
    ];
    let mut simplex = vec![origin.clone()];
    for (i, step) in [0.5, 1.5, 0.03, 2.0, 1.0].into_iter().enumerate() {
        let mut v = origin.clone();
        v[i] += step;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(1e-4).expect("a simplex of 6 distinct vertices");
    let res = Executor::new(HalfRms { rows, base, from, to }, solver)
        .configure(|s| s.max_iters(max_iters))
        .run()
        .expect("the cost never fails");
    Ok(res.state().get_best_param().cloned().unwrap_or(origin))
}

/// The truth-tuned reference, cross-validated over the two halves of the log's truth in time
/// (split at the midpoint of the first and last truth rows).
pub fn truth_tuned_cross_validated(
    rows: &[LogRow],
    base: &PostConfig,
    max_iters: u64,
) -> Result<TruthTuned, PostError> {
    let run = postprocess_rows(rows, base)?;
    let times: Vec<f64> = run.samples.iter().filter(|s| s.truth.is_some()).map(|s| s.t).collect();
    let (first, last) = (times.first().copied().unwrap_or(0.0), times.last().copied().unwrap_or(0.0));
    let mid = 0.5 * (first + last);
    let halves = [(f64::NEG_INFINITY, mid), (mid, f64::INFINITY)];
    let mut fits = Vec::new();
    let (mut sq, mut nees) = (Vec::new(), Vec::new());
    for (i, &(from, to)) in halves.iter().enumerate() {
        let (ofrom, oto) = halves[1 - i];
        let values = fit(rows, base, from, to, max_iters)?;
        let r = postprocess_rows(rows, &at(base, &values))?;
        let rms = |v: &[f64]| (v.iter().sum::<f64>() / v.len().max(1) as f64).sqrt();
        let (own, _) = errors(&r, from, to);
        let (other, other_nees) = errors(&r, ofrom, oto);
        fits.push(HalfFit { tuned_on_s: (from, to), values, rms_in_sample_m: rms(&own), rms_held_out_m: rms(&other) });
        sq.extend(other);
        nees.extend(other_nees);
    }
    let n = sq.len().max(1) as f64;
    let [a, b]: [HalfFit; 2] = fits.try_into().expect("two halves");
    Ok(TruthTuned {
        halves: [a, b],
        rms_m: (sq.iter().sum::<f64>() / n).sqrt(),
        mean_nees: nees.iter().sum::<f64>() / nees.len().max(1) as f64,
    })
}
