//! The Monte Carlo a field team needs before going to sea (`coopnav advise`): every candidate
//! CNA policy (each configured as `simulate` configures it) under every candidate ranging cycle τ
//! and status rate the scenario's schedule fits, flown `runs` times on the scenario's seed; the
//! best candidate by mean fleet true error is recommended, and its margin over the runner-up is
//! then measured on runs of the next base seed (seed + 1), paired run by run, so the CI is not
//! measured on the runs that chose it. Each candidate also keeps every survey AUV's mean and p95
//! true error and a map of the true error over the survey area.
//!
//! Runs go through rayon and are merged in job order: bit-identical on any thread count.

use crate::batch::mc::Ci;
use crate::engine::{Faults, Observer, TraceRow};
use crate::observe::metrics::run;
use crate::policy::registry::{PolicyError, PolicySpec};
use crate::scenario::world::Scenario;
use coopnav_acomms::Rate;
use coopnav_core::{run_seed, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum AdviseError {
    #[error("advise: {0}")]
    Policy(#[from] PolicyError),
    #[error("advise: no candidate setting fits the scenario's schedule:{}", .0.iter().map(|s| format!("\n  {s}")).collect::<String>())]
    NoSetting(Vec<String>),
    #[error("advise: {field} = {value}: allowed {allowed}")]
    Invalid { field: &'static str, value: String, allowed: String },
}

/// What to try.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AdviseSpec {
    /// Runs per candidate on the choosing seed, and again on the confirming seed.
    pub runs: usize,
    pub policies: Vec<String>,
    /// Candidate ranging cycles τ, s (empty: the scenario's).
    pub taus: Vec<f64>,
    /// Candidate fixed status rates (empty: the scenario's; unused with `comms.status_adaptive`).
    pub status_rates: Vec<Rate>,
    /// Mission length instead of the scenario's, s.
    pub duration_s: Option<f64>,
    /// Cells per side of the error map.
    pub map_cells: usize,
}

/// The candidate policies of [`AdviseSpec::default`]: the recommended planner and the baselines
/// a team would fly without it.
pub const DEFAULT_POLICIES: [&str; 4] = ["planner-estimator", "centroid", "zigzag", "none"];

impl Default for AdviseSpec {
    fn default() -> Self {
        AdviseSpec {
            runs: 3,
            policies: DEFAULT_POLICIES.iter().map(|p| p.to_string()).collect(),
            taus: Vec::new(),
            status_rates: Vec::new(),
            duration_s: None,
            map_cells: 24,
        }
    }
}

/// One candidate: a policy under one comms setting.
#[derive(Debug, Clone)]
pub struct Candidate {
    pub policy: String,
    pub tau: f64,
    pub status_rate: Option<Rate>,
    pub scenario: Scenario,
}

impl Candidate {
    pub fn label(&self) -> String {
        let rate = self.status_rate.map_or("adaptive".to_string(), |r| r.to_string());
        format!("{} · τ {} s · status rate {rate}", self.policy, self.tau)
    }
}

/// The settings the scenario's schedule fits (validated as a scenario file would be) and a
/// reason for each one left out; then every policy under each.
pub fn candidates(sc: &Scenario, spec: &AdviseSpec) -> Result<(Vec<Candidate>, Vec<String>), AdviseError> {
    if spec.runs < 2 {
        return Err(AdviseError::Invalid {
            field: "runs",
            value: spec.runs.to_string(),
            allowed: ">= 2 (a CI needs two runs)".into(),
        });
    }
    if spec.policies.is_empty() {
        return Err(AdviseError::Invalid { field: "policies", value: "none".into(), allowed: "one or more".into() });
    }
    if !(2..=200).contains(&spec.map_cells) {
        return Err(AdviseError::Invalid {
            field: "map_cells",
            value: spec.map_cells.to_string(),
            allowed: "2..=200".into(),
        });
    }
    let taus = if spec.taus.is_empty() { vec![sc.comms.tau] } else { spec.taus.clone() };
    let adaptive = sc.comms.status_adaptive.is_some();
    let rates: Vec<Option<Rate>> = if adaptive {
        vec![None]
    } else if spec.status_rates.is_empty() {
        vec![Some(sc.comms.status_rate)]
    } else {
        spec.status_rates.iter().copied().map(Some).collect()
    };
    let (mut settings, mut skipped) = (Vec::new(), Vec::new());
    for &tau in &taus {
        for &rate in &rates {
            let mut s = sc.clone();
            s.comms.tau = tau;
            if let Some(r) = rate {
                s.comms.status_rate = r;
            }
            if let Some(d) = spec.duration_s {
                s.duration_s = d;
            }
            match s.validate(Path::new("<advise candidate>")) {
                Ok(()) => settings.push((tau, rate, s)),
                Err(e) => skipped
                    .push(format!("τ {tau} s, status rate {}: {e}", rate.map_or("adaptive".into(), |r| r.to_string()))),
            }
        }
    }
    if settings.is_empty() {
        return Err(AdviseError::NoSetting(skipped));
    }
    let mut out = Vec::new();
    for (tau, rate, s) in settings {
        for p in &spec.policies {
            PolicySpec::new(p, &s)?;
            out.push(Candidate { policy: p.clone(), tau, status_rate: rate, scenario: s.clone() });
        }
    }
    Ok((out, skipped))
}

/// Mean true error over a grid of cells covering the survey (per cell: sum and samples).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorMap {
    /// South-west corner and cell size, m.
    pub x0: f64,
    pub y0: f64,
    pub cell_m: f64,
    pub nx: usize,
    pub ny: usize,
    pub sum: Vec<f64>,
    pub count: Vec<u64>,
}

impl ErrorMap {
    /// Square cells over the survey waypoints and the CNA's start, with a margin of one cell.
    pub fn over(sc: &Scenario, cells: usize) -> Self {
        let start = crate::scenario::start::cna_start(sc).pos;
        let pts: Vec<(f64, f64)> =
            (0..sc.fleet.n_auvs).flat_map(|k| sc.lawnmower(k).waypoints()).chain([(start.x, start.y)]).collect();
        let lo = pts.iter().fold((f64::INFINITY, f64::INFINITY), |a, p| (a.0.min(p.0), a.1.min(p.1)));
        let hi = pts.iter().fold((f64::NEG_INFINITY, f64::NEG_INFINITY), |a, p| (a.0.max(p.0), a.1.max(p.1)));
        let side = (hi.0 - lo.0).max(hi.1 - lo.1).max(1.0);
        // Centred on the survey, one cell of margin on its longer side.
        let cell_m = side / (cells - 2) as f64;
        let half = cells as f64 * cell_m / 2.0;
        ErrorMap {
            x0: (lo.0 + hi.0) / 2.0 - half,
            y0: (lo.1 + hi.1) / 2.0 - half,
            cell_m,
            nx: cells,
            ny: cells,
            sum: vec![0.0; cells * cells],
            count: vec![0; cells * cells],
        }
    }

    fn cell(&self, x: f64, y: f64) -> Option<usize> {
        let (i, j) = (((x - self.x0) / self.cell_m).floor(), ((y - self.y0) / self.cell_m).floor());
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.nx && (j as usize) < self.ny)
            .then(|| j as usize * self.nx + i as usize)
    }

    fn add(&mut self, other: &ErrorMap) {
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += b;
        }
        for (a, b) in self.count.iter_mut().zip(&other.count) {
            *a += b;
        }
    }

    /// Mean error in each cell (None where no AUV passed).
    pub fn means(&self) -> Vec<Option<f64>> {
        self.sum.iter().zip(&self.count).map(|(s, &n)| (n > 0).then(|| s / n as f64)).collect()
    }

    /// The cell with the highest mean error: its centre (x, y) and mean.
    pub fn peak(&self) -> Option<((f64, f64), f64)> {
        let (k, m) = self
            .means()
            .into_iter()
            .enumerate()
            .filter_map(|(k, m)| m.map(|m| (k, m)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let (i, j) = (k % self.nx, k / self.nx);
        Some(((self.x0 + (i as f64 + 0.5) * self.cell_m, self.y0 + (j as f64 + 0.5) * self.cell_m), m))
    }
}

/// What one run records beyond its metrics: the error map and the CNA's path once per τ.
struct Recorder {
    map: ErrorMap,
    tau: f64,
    next: f64,
    cna: Vec<(f64, f64)>,
}

impl Observer for Recorder {
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        for r in rows {
            if let Some(k) = self.map.cell(r.true_x, r.true_y) {
                self.map.sum[k] += r.error;
                self.map.count[k] += 1;
            }
        }
        if t >= self.next {
            self.cna.push((cna.x, cna.y));
            self.next += self.tau;
        }
    }
}

/// One candidate over its runs.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateResult {
    pub label: String,
    pub policy: String,
    pub tau: f64,
    pub status_rate: Option<Rate>,
    /// Fleet mean true error of each run, and their mean with its 95 % CI.
    pub runs: Vec<f64>,
    pub mean_error: Ci,
    /// Per survey AUV: mean and p95 true error, averaged over runs, m.
    pub auv_mean: Vec<f64>,
    pub auv_p95: Vec<f64>,
    pub healthy: bool,
    #[serde(skip)]
    pub map: ErrorMap,
}

/// The recommendation's margin over the runner-up on the confirming seed's runs.
#[derive(Debug, Clone, Serialize)]
pub struct Margin {
    pub runner_up: String,
    /// Recommended minus runner-up, paired by run (negative: the recommendation is better).
    pub difference: Ci,
    pub seed: u64,
    /// The CI excludes zero.
    pub decided: bool,
}

#[derive(Debug, Clone, Serialize)]
pub struct Advice {
    pub spec: AdviseSpec,
    /// The seed the candidates were compared on.
    pub seed: u64,
    pub candidates: Vec<CandidateResult>,
    /// Index into `candidates`.
    pub recommended: usize,
    pub margin: Option<Margin>,
    /// The recommended candidate's confirming runs (seed + 1): fleet mean error and per AUV.
    pub confirmed: CandidateResult,
    /// Settings left out, with why.
    pub skipped: Vec<String>,
    /// The recommended candidate's CNA path in its first confirming run, once per τ (x, y m).
    pub cna_path: Vec<(f64, f64)>,
}

struct RunOut {
    fleet: f64,
    auv_mean: Vec<f64>,
    auv_p95: Vec<f64>,
    healthy: bool,
    map: ErrorMap,
    cna: Vec<(f64, f64)>,
}

fn fly(c: &Candidate, seed: u64, cells: usize) -> Result<RunOut, PolicyError> {
    let sc = &c.scenario;
    let mut policy = PolicySpec::new(&c.policy, sc)?.build(sc)?;
    let mut rec = Recorder { map: ErrorMap::over(sc, cells), tau: sc.comms.tau, next: 0.0, cna: Vec::new() };
    let r = run(sc, &mut policy, seed, &Faults::default(), &mut rec);
    Ok(RunOut {
        fleet: r.fleet.error.mean,
        auv_mean: r.auvs.iter().map(|a| a.error.mean).collect(),
        auv_p95: r.auvs.iter().map(|a| a.error.p95).collect(),
        healthy: r.fleet.healthy,
        map: rec.map,
        cna: rec.cna,
    })
}

fn summarise(c: &Candidate, outs: Vec<RunOut>, cells: usize) -> CandidateResult {
    let n = outs.len().max(1) as f64;
    let n_auvs = c.scenario.fleet.n_auvs;
    let avg = |f: &dyn Fn(&RunOut) -> &Vec<f64>| -> Vec<f64> {
        (0..n_auvs).map(|k| outs.iter().map(|o| f(o)[k]).sum::<f64>() / n).collect()
    };
    let mut map = ErrorMap::over(&c.scenario, cells);
    outs.iter().for_each(|o| map.add(&o.map));
    let runs: Vec<f64> = outs.iter().map(|o| o.fleet).collect();
    CandidateResult {
        label: c.label(),
        policy: c.policy.clone(),
        tau: c.tau,
        status_rate: c.status_rate,
        mean_error: Ci::of(&runs),
        auv_mean: avg(&|o| &o.auv_mean),
        auv_p95: avg(&|o| &o.auv_p95),
        healthy: outs.iter().all(|o| o.healthy),
        runs,
        map,
    }
}

/// Flies `jobs` (candidate index, run seed) on rayon, results in job order.
fn fly_all(
    cands: &[Candidate],
    jobs: &[(usize, u64)],
    cells: usize,
    done: &std::sync::atomic::AtomicU64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<RunOut>, PolicyError> {
    jobs.par_iter()
        .map(|&(c, seed)| {
            let out = fly(&cands[c], seed, cells);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            out
        })
        .collect()
}

/// The runs [`advise`] makes for `n` candidates: `runs` each, then `runs` for the two finalists.
pub fn total_runs(n: usize, runs: usize) -> u64 {
    (n * runs + 2.min(n) * runs) as u64
}

/// Runs the candidates and recommends one (module doc). `progress(done)` counts finished runs
/// out of [`total_runs`].
pub fn advise(sc: &Scenario, spec: &AdviseSpec, progress: &(dyn Fn(u64) + Sync)) -> Result<Advice, AdviseError> {
    let (cands, skipped) = candidates(sc, spec)?;
    let runs = spec.runs;
    let cells = spec.map_cells;
    let done = std::sync::atomic::AtomicU64::new(0);
    let jobs: Vec<(usize, u64)> =
        (0..cands.len()).flat_map(|c| (0..runs).map(move |i| (c, run_seed(sc.seed, i as u64)))).collect();
    let mut outs = fly_all(&cands, &jobs, cells, &done, progress)?.into_iter();
    let results: Vec<CandidateResult> =
        cands.iter().map(|c| summarise(c, outs.by_ref().take(runs).collect(), cells)).collect();
    let mut order: Vec<usize> = (0..results.len()).collect();
    order.sort_by(|&a, &b| results[a].mean_error.mean.total_cmp(&results[b].mean_error.mean));
    let (best, second) = (order[0], order.get(1).copied());
    // The margin on runs the choice never saw: the next base seed.
    let confirm_seed = sc.seed.wrapping_add(1);
    let finalists: Vec<usize> = std::iter::once(best).chain(second).collect();
    let jobs: Vec<(usize, u64)> =
        finalists.iter().flat_map(|&c| (0..runs).map(move |i| (c, run_seed(confirm_seed, i as u64)))).collect();
    let outs = fly_all(&cands, &jobs, cells, &done, progress)?;
    let cna_path = outs[0].cna.clone();
    let mut outs = outs.into_iter();
    let confirmed = summarise(&cands[best], outs.by_ref().take(runs).collect(), cells);
    let margin = second.map(|s| {
        let other = summarise(&cands[s], outs.by_ref().take(runs).collect(), cells);
        let d: Vec<f64> = confirmed.runs.iter().zip(&other.runs).map(|(a, b)| a - b).collect();
        let difference = Ci::of(&d);
        Margin { runner_up: other.label, difference, seed: confirm_seed, decided: difference.high < 0.0 }
    });
    Ok(Advice {
        spec: spec.clone(),
        seed: sc.seed,
        candidates: results,
        recommended: best,
        margin,
        confirmed,
        skipped,
        cna_path,
    })
}
