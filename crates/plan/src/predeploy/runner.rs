//! Steps a CNA planner over a whole pre-deployment mission: every τ the planner plans from the
//! CNA's pose, the CNA moves to the planned waypoint, and each survey AUV's modelled error is
//! updated from its a-priori position (Hudson 2012, Sec. 4.1).

use super::metrics::{StepRecord, Summary};
use super::Mission;
use crate::{AuvError, AuvForecast, CnaPose, Decision, Penalty, PlanError, PlanInput, Planner, Violation};
use coopnav_core::{Track, Vec3};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum RunError {
    #[error("planning step {step} (t = {t} s) failed: {source}")]
    Plan { step: usize, t: f64, source: PlanError },
}

/// The a-priori tracks as a forecast; nothing is known past the mission end (docs/models.md#hudson-search).
pub struct TrackForecast<'a> {
    pub tracks: &'a [Track],
    pub end_time: f64,
}

impl AuvForecast for TrackForecast<'_> {
    fn n_auvs(&self) -> usize {
        self.tracks.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        (t <= self.end_time + 1e-9).then(|| self.tracks[k].at(t))
    }
}

/// Everything a run produced.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Step 0 is the start (no decision); steps 1.. follow each executed decision.
    pub steps: Vec<StepRecord>,
    pub decisions: Vec<Decision>,
    pub summary: Summary,
}

/// Runs `planner` over `mission`. `progress(step)` is called after each step.
pub fn run(
    mission: &Mission,
    planner: &mut dyn Planner,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunResult, RunError> {
    let cfg = &mission.planner;
    let tau = cfg.motion.tau;
    let forecast = TrackForecast { tracks: &mission.tracks, end_time: mission.end_time };
    let mut t = mission.start_time;
    let mut cna = mission.cna;
    let positions = |t: f64| -> Vec<Vec3> { mission.tracks.iter().map(|tr| tr.at(t)).collect() };
    let mut errors: Vec<AuvError> = positions(t)
        .iter()
        .enumerate()
        .map(|(k, p)| cfg.error.initial(mission.sigma0[k], mission.eps0[k], &cna.pos, p))
        .collect();
    let mut steps = vec![record(mission, 0, t, &cna, &errors, &positions(t))];
    let mut decisions = Vec::new();
    let n_steps = ((mission.end_time - mission.start_time) / tau + 1e-9).floor() as usize;
    for step in 1..=n_steps {
        let d = planner
            .decide(&PlanInput {
                t,
                cna,
                errors: &errors,
                estimates: &[],
                cna_variance: 0.0,
                forecast: &forecast,
                slot_reach_m: &[],
            })
            .map_err(|source| RunError::Plan { step, t, source })?;
        t = mission.start_time + step as f64 * tau;
        cna = d.next;
        let now = positions(t);
        let c = [cna.pos.x, cna.pos.y, cna.pos.z];
        for (e, p) in errors.iter_mut().zip(&now) {
            *e = cfg.error.step(e, cfg.error.los(c, [p.x, p.y, p.z]), tau);
        }
        steps.push(record(mission, step, t, &cna, &errors, &now));
        decisions.push(d);
        progress(step as u64);
    }
    let summary = Summary::from_steps(&steps, &decisions, &cfg.limits);
    Ok(RunResult { steps, decisions, summary })
}

/// Number of decisions a mission takes (for progress bars).
pub fn step_count(mission: &Mission) -> u64 {
    ((mission.end_time - mission.start_time) / mission.planner.motion.tau + 1e-9).floor() as u64
}

fn record(mission: &Mission, step: usize, t: f64, cna: &CnaPose, errors: &[AuvError], auv: &[Vec3]) -> StepRecord {
    let cfg = &mission.planner;
    let dist: Vec<f64> = auv.iter().map(|p| (p - cna.pos).norm()).collect();
    let cost: f64 = errors.iter().map(|e| cfg.error.cost_term(e.sigma2, e.eps2)).sum();
    let (dmin, dmax) = (dist.iter().cloned().fold(f64::INFINITY, f64::min), dist.iter().cloned().fold(0.0, f64::max));
    let v = Violation { too_close: (cfg.limits.min - dmin).max(0.0), too_far: (dmax - cfg.limits.max).max(0.0) };
    StepRecord {
        step,
        t,
        cna: *cna,
        auv: auv.to_vec(),
        errors: errors.to_vec(),
        distance: dist,
        cost,
        penalised_cost: cfg.penalties.primary.apply(cost, &v),
    }
}
