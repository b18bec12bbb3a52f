//! Monte Carlo over HBL runs (digest §5.6): run i uses `run_seed(base, i)` so configurations
//! compared with one base seed share their noise (common random numbers); runs go in parallel
//! with rayon and are merged in index order, so results do not depend on the thread count.
//! Also the across-run statistics and the Welch confidence interval of a difference (§4.3).

use super::config::{ConfigError, Scenario};
use super::profile::{bin_rows, merge_bins, BinSums, ProfileBin};
use super::world::{run, RunMetrics};
use coopnav_core::run_seed;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum McError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("runs < 2: a Monte Carlo needs at least 2 runs")]
    TooFewRuns,
    #[error("profile bin width {0} m: must be a finite number > 0")]
    BadBin(f64),
    #[error("run {index} (seed {seed}): the AUV never entered the measurement zone within max_duration_s")]
    NoZone { index: usize, seed: u64 },
}

/// Mean, SD (n − 1) and standard error of the mean.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    pub n: usize,
    pub mean: f64,
    pub sd: f64,
    pub se: f64,
}

impl Stats {
    pub fn of(v: &[f64]) -> Stats {
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n.max(1) as f64;
        let var = if n > 1 { v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
        Stats { n, mean, sd: var.sqrt(), se: (var / n.max(1) as f64).sqrt() }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct McSummary {
    pub configuration: String,
    pub cycle: String,
    pub runs: usize,
    pub base_seed: u64,
    pub zone_error: Stats,
    pub zone_parallel: Stats,
    pub zone_perpendicular: Stats,
    /// Across-path error just before the zone (digest §11: HBL corrects it there, MSBL not).
    pub approach_perpendicular: Option<Stats>,
    pub buoy_error: Option<Stats>,
    pub saturation_error: Option<Stats>,
    /// Every run kept finite states and positive-definite covariances.
    pub all_healthy: bool,
    pub filter_predicts: u64,
    pub filter_updates: u64,
}

#[derive(Debug, Clone)]
pub struct McResult {
    pub runs: Vec<RunMetrics>,
    pub summary: McSummary,
    /// The error profile against x_rel, when asked for ([`monte_carlo_profiled`]).
    pub profile: Option<Vec<ProfileBin>>,
}

/// Runs `runs` simulations of `sc` with seeds `run_seed(base_seed, i)`; `progress` is called with
/// the number of finished runs.
pub fn monte_carlo(
    sc: &Scenario,
    runs: usize,
    base_seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<McResult, McError> {
    simulate_all(sc, runs, base_seed, None, progress)
}

/// [`monte_carlo`] that also bins every step of the same runs into an error profile against x_rel
/// (`bin_m` metres per bin), so the runs are simulated once for both.
pub fn monte_carlo_profiled(
    sc: &Scenario,
    runs: usize,
    base_seed: u64,
    bin_m: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<McResult, McError> {
    if !(bin_m.is_finite() && bin_m > 0.0) {
        return Err(McError::BadBin(bin_m));
    }
    simulate_all(sc, runs, base_seed, Some(bin_m), progress)
}

fn simulate_all(
    sc: &Scenario,
    runs: usize,
    base_seed: u64,
    bin_m: Option<f64>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<McResult, McError> {
    sc.validate()?;
    if runs < 2 {
        return Err(McError::TooFewRuns);
    }
    let cycle = sc.resolved_cycle()?;
    let done = AtomicU64::new(0);
    let per_run: Vec<(RunMetrics, Option<BinSums>)> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let (m, trace) = run(sc, &cycle, run_seed(base_seed, i as u64), bin_m.is_some());
            let bins = bin_m.zip(trace).map(|(b, t)| bin_rows(&t.rows, b));
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            (m, bins)
        })
        .collect();
    let (metrics, bins): (Vec<RunMetrics>, Vec<Option<BinSums>>) = per_run.into_iter().unzip();
    let summary = summarise(sc, &cycle.name, base_seed, &metrics)?;
    let profile = bin_m.map(|b| merge_bins(bins.into_iter().flatten(), b));
    Ok(McResult { runs: metrics, summary, profile })
}

fn summarise(sc: &Scenario, cycle: &str, base_seed: u64, per_run: &[RunMetrics]) -> Result<McSummary, McError> {
    let mut zone = Vec::with_capacity(per_run.len());
    let (mut par, mut perp) = (Vec::new(), Vec::new());
    for (index, m) in per_run.iter().enumerate() {
        let (Some(z), Some(pa), Some(pe)) = (m.zone_error, m.zone_parallel, m.zone_perpendicular) else {
            return Err(McError::NoZone { index, seed: run_seed(base_seed, index as u64) });
        };
        zone.push(z);
        par.push(pa);
        perp.push(pe);
    }
    let opt = |f: fn(&RunMetrics) -> Option<f64>| {
        let v: Vec<f64> = per_run.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| Stats::of(&v))
    };
    Ok(McSummary {
        configuration: sc.configuration.label().to_string(),
        cycle: cycle.to_string(),
        runs: per_run.len(),
        base_seed,
        zone_error: Stats::of(&zone),
        zone_parallel: Stats::of(&par),
        zone_perpendicular: Stats::of(&perp),
        approach_perpendicular: opt(|m| m.approach_perpendicular),
        buoy_error: opt(|m| m.buoy_error),
        saturation_error: opt(|m| m.saturation_error),
        all_healthy: per_run.iter().all(|m| m.healthy),
        filter_predicts: per_run.iter().map(|m| m.filter_predicts).sum(),
        filter_updates: per_run.iter().map(|m| m.filter_updates).sum(),
    })
}

/// 95 % Welch confidence interval of mean(a) − mean(b).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WelchCi {
    pub difference: f64,
    pub se: f64,
    pub df: f64,
    pub low: f64,
    pub high: f64,
}

pub fn welch_95(a: &Stats, b: &Stats) -> WelchCi {
    let (va, vb) = (a.sd.powi(2) / a.n as f64, b.sd.powi(2) / b.n as f64);
    let se = (va + vb).sqrt();
    let df = if se > 0.0 {
        (va + vb).powi(2) / (va.powi(2) / (a.n as f64 - 1.0) + vb.powi(2) / (b.n as f64 - 1.0))
    } else {
        f64::INFINITY
    };
    let t = t_975(df);
    let difference = a.mean - b.mean;
    WelchCi { difference, se, df, low: difference - t * se, high: difference + t * se }
}

/// 97.5 % quantile of Student's t with `df` degrees of freedom: Cornish–Fisher expansion about
/// the normal quantile (error < 1e-3 for df ≥ 4; the Monte Carlo df are in the hundreds).
pub fn t_975(df: f64) -> f64 {
    let z: f64 = 1.959_963_984_540_054;
    if !df.is_finite() {
        return z;
    }
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * df)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * df * df)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * df.powi(3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_reproduces_the_thesis_cycle_interval() {
        // §4.3: 1.59 ± 0.95 vs 1.37 ± 0.76, n = 250 each → [0.07, 0.37].
        let long = Stats { n: 250, mean: 1.59, sd: 0.95, se: 0.95 / 250f64.sqrt() };
        let short = Stats { n: 250, mean: 1.37, sd: 0.76, se: 0.76 / 250f64.sqrt() };
        let ci = welch_95(&long, &short);
        assert!((ci.low - 0.069).abs() < 0.003 && (ci.high - 0.371).abs() < 0.003, "{ci:?}");
    }

    #[test]
    fn t_quantiles() {
        assert!((t_975(10.0) - 2.228).abs() < 0.005);
        assert!((t_975(30.0) - 2.042).abs() < 0.002);
        assert!((t_975(f64::INFINITY) - 1.96).abs() < 1e-3);
    }

    #[test]
    fn stats_basics() {
        let s = Stats::of(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - 1.2909944).abs() < 1e-6);
        assert!((s.se - s.sd / 2.0).abs() < 1e-12);
    }
}
