//! Seeded Monte Carlo comparison of CNA policies on one scenario. Run i of every policy uses the
//! same seed `run_seed(base, i)` (common random numbers: the same sensor noise, compass maps and
//! channel draws), so the planner's advantage over a baseline is judged run by run (paired 95 %
//! CI). Runs go through rayon and are merged in index order: bit-identical on any thread count.

use crate::engine::{Faults, Observer};
use crate::models::metrics::LinkStats;
use crate::observe::metrics::{run, RunResult};
use crate::observe::stats::{t_975, Stats};
use crate::policy::registry::{PolicyError, PolicySpec};
use crate::scenario::world::Scenario;
use coopnav_core::run_seed;
use rayon::prelude::*;
use serde::Serialize;

/// Mean and 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ci {
    pub mean: f64,
    pub low: f64,
    pub high: f64,
}

impl Ci {
    pub fn of(v: &[f64]) -> Ci {
        let s = Stats::of(v);
        let half = if s.n > 1 { t_975((s.n - 1) as f64) * s.se } else { f64::INFINITY };
        Ci { mean: s.mean, low: s.mean - half, high: s.mean + half }
    }
}

/// One policy over all runs.
#[derive(Debug, Clone, Serialize)]
pub struct PolicySummary {
    pub policy: String,
    /// Per-run fleet mean true error, over runs.
    pub mean_error: Ci,
    pub rms_error: f64,
    pub p95_error: f64,
    pub max_error: f64,
    pub modelled_mean: Option<f64>,
    pub downlink_success: f64,
    pub uplink_success: f64,
    pub limit_violation: f64,
    pub deadline_misses: u64,
    pub healthy: bool,
    /// Mean NEES over every AUV and run (2 for consistent filters), and the AUV filters the NEES
    /// check flagged as diverged, over all runs.
    pub nees_mean: f64,
    pub diverged: usize,
    /// The filters' own recoveries (`filter.range_health`), over every AUV and run.
    pub recoveries: u64,
    /// Per-run fleet mean errors, in run order.
    pub runs: Vec<f64>,
    /// Per AUV, its own mean true error in each run (run order): where in the fleet a difference
    /// between two policies lies ([`paired_per_auv`]). Left out of the JSON (AUVs × runs numbers).
    #[serde(skip)]
    pub auv_runs: Vec<Vec<f64>>,
    /// Per AUV, the runs in which at least one of its status messages reached the CNA (0: no
    /// policy that plans on reports ever looked for it, by the thesis's start rule, Hudson 2012, Sec. 4.2).
    pub auv_heard_runs: Vec<usize>,
    /// Per AUV, over all runs: its status messages sent, and those the channel decoded but a
    /// collision or half-duplex lost (why an AUV is never heard, when it is that).
    pub auv_status_sent: Vec<u64>,
    pub auv_status_lost_in_air: Vec<u64>,
}

/// The reference policy (the first one compared, normally a planner) minus a baseline, paired
/// by run (negative = the reference is better).
#[derive(Debug, Clone, Serialize)]
pub struct Paired {
    pub baseline: String,
    pub difference: Ci,
    /// The reference's mean is lower and the CI excludes zero.
    pub planner_better: bool,
}

#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    pub n_auvs: usize,
    pub runs: usize,
    pub seed: u64,
    pub policies: Vec<PolicySummary>,
    pub paired: Vec<Paired>,
    /// Per policy (in the order of `policies`), per AUV over all runs: where the CNA was and what
    /// the AUV's filter made of it.
    pub auvs: Vec<Vec<AuvSummary>>,
}

/// One survey AUV under one policy, over all runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AuvSummary {
    /// Mean true horizontal CNA–AUV distance, m.
    pub distance_mean: f64,
    /// Fraction of the CNA's broadcasts (ranges) the AUV received.
    pub downlink_success: f64,
    /// Mean NEES of its filter (the mean over runs of each run's mean; 2 when consistent).
    pub nees_mean: f64,
}

fn auv_summaries(rs: &[RunResult]) -> Vec<AuvSummary> {
    let n_auvs = rs.first().map_or(0, |r| r.auvs.len());
    let runs = rs.len().max(1) as f64;
    (0..n_auvs)
        .map(|k| {
            let (sent, got) =
                rs.iter().fold((0u64, 0u64), |a, r| (a.0 + r.auvs[k].downlink.sent, a.1 + r.auvs[k].downlink.received));
            AuvSummary {
                distance_mean: rs.iter().map(|r| r.auvs[k].distance_mean).sum::<f64>() / runs,
                downlink_success: if sent == 0 { 0.0 } else { got as f64 / sent as f64 },
                nees_mean: rs.iter().map(|r| r.auvs[k].health.nees_mean).sum::<f64>() / runs,
            }
        })
        .collect()
}

/// Runs every policy `runs` times and pairs the first policy (the reference) with each other
/// one. `progress(done)` is called after each run.
pub fn monte_carlo(
    sc: &Scenario,
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Comparison, PolicyError> {
    monte_carlo_until(sc, policies, runs, progress, &|| false)
}

/// Ends every run at its next step once `stop()` is true (a caller's cancellation).
struct Until<'a>(&'a (dyn Fn() -> bool + Sync));

impl Observer for Until<'_> {
    fn stop(&self) -> bool {
        (self.0)()
    }
}

/// [`monte_carlo`] that a caller can cancel: once `stop()` is true every run ends at its next
/// step, and the (partial) comparison that comes back is to be discarded.
pub fn monte_carlo_until(
    sc: &Scenario,
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Comparison, PolicyError> {
    let mut comparisons = grid_until(std::slice::from_ref(sc), policies, runs, progress, stop)?;
    Ok(comparisons.remove(0))
}

/// [`monte_carlo`] on each of `scenarios` (the cells of an experiment), all runs of all cells in
/// one pool: no cell waits for the slowest run of the one before. `progress(done)` counts the
/// finished runs of the whole grid. Comparisons come back in the order of `scenarios`, each
/// bit-identical to its own [`monte_carlo`].
pub fn monte_carlo_grid(
    scenarios: &[Scenario],
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Comparison>, PolicyError> {
    grid_until(scenarios, policies, runs, progress, &|| false)
}

/// One run of a grid: the cell (scenario), the policy and the run index.
#[derive(Clone, Copy)]
struct Job {
    cell: usize,
    policy: usize,
    run: usize,
}

/// Every run of [`monte_carlo`] on `sc`, not yet compared: policy by policy (in the order of
/// `policies`), run by run within each; [`compare`] of them is [`monte_carlo`]'s comparison.
pub fn monte_carlo_runs(
    sc: &Scenario,
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<RunResult>, PolicyError> {
    grid_runs(std::slice::from_ref(sc), policies, runs, progress, &|| false)
}

fn grid_until(
    scenarios: &[Scenario],
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<Comparison>, PolicyError> {
    let results = grid_runs(scenarios, policies, runs, progress, stop)?;
    let per_cell = policies.len() * runs;
    Ok(scenarios
        .iter()
        .enumerate()
        .map(|(c, sc)| compare(sc, policies, runs, &results[c * per_cell..(c + 1) * per_cell]))
        .collect())
}

/// Every run of every cell, cell by cell, then policy by policy, then run by run.
fn grid_runs(
    scenarios: &[Scenario],
    policies: &[String],
    runs: usize,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<RunResult>, PolicyError> {
    let specs = scenarios
        .iter()
        .map(|sc| policies.iter().map(|p| PolicySpec::new(p, sc)).collect::<Result<Vec<_>, _>>())
        .collect::<Result<Vec<_>, _>>()?;
    let jobs: Vec<Job> = (0..scenarios.len())
        .flat_map(|cell| {
            (0..policies.len()).flat_map(move |policy| (0..runs).map(move |run| Job { cell, policy, run }))
        })
        .collect();
    let done = std::sync::atomic::AtomicU64::new(0);
    let results = longest_first(
        &jobs,
        |j| expected_cost(&scenarios[j.cell], &policies[j.policy]),
        |&j| {
            let sc = &scenarios[j.cell];
            let mut policy = specs[j.cell][j.policy].build(sc)?;
            let r = run(sc, &mut policy, run_seed(sc.seed, j.run as u64), &Faults::default(), &mut Until(stop));
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            Ok(r)
        },
    )
    .into_iter()
    .collect::<Result<Vec<RunResult>, PolicyError>>()?;
    Ok(results)
}

/// The relative cost of one run, for scheduling only (results never depend on it): the fleet
/// size, and the planners' search. Measured on single 1 h runs of the evaluation grid's cells:
/// planner-estimator 2.3–8× a baseline run, Hudson's planner 1.1–3.1×.
fn expected_cost(sc: &Scenario, policy: &str) -> f64 {
    let search = match policy {
        "planner-estimator" => 5.0,
        "planner" => 1.5,
        _ => 1.0,
    };
    (sc.fleet.n_auvs as f64 + 1.0) * search
}

/// `work` on every job on rayon's threads, the most expensive first (each thread takes the next
/// job as it becomes free, so the last ones to finish are short and no thread idles long at the
/// end); results in the order of `jobs`, whatever the thread count and timing.
fn longest_first<J: Sync, R: Send>(jobs: &[J], cost: impl Fn(&J) -> f64, work: impl Fn(&J) -> R + Sync) -> Vec<R> {
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    // Stable: equal costs keep the job order.
    order.sort_by(|&a, &b| cost(&jobs[b]).total_cmp(&cost(&jobs[a])));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let workers = rayon::current_num_threads().min(jobs.len()).max(1);
    let mut finished: Vec<(usize, R)> = (0..workers)
        .into_par_iter()
        .flat_map_iter(|_| {
            std::iter::from_fn(|| {
                let i = *order.get(next.fetch_add(1, std::sync::atomic::Ordering::Relaxed))?;
                Some((i, work(&jobs[i])))
            })
            .collect::<Vec<_>>()
        })
        .collect();
    finished.sort_by_key(|(i, _)| *i);
    finished.into_iter().map(|(_, r)| r).collect()
}

/// The comparison of one cell from its runs (`runs` per policy of `names`, policy by policy, runs
/// in index order): the first policy (the reference) paired with each other one. Public for runs
/// made outside [`monte_carlo`] (the headroom example's rollouts).
pub fn compare(sc: &Scenario, names: &[String], runs: usize, results: &[RunResult]) -> Comparison {
    let summaries: Vec<PolicySummary> =
        results.chunks(runs.max(1)).zip(names).map(|(rs, name)| summarise(name, rs)).collect();
    let paired = match summaries.split_first() {
        Some((reference, others)) => others
            .iter()
            .map(|b| {
                let d: Vec<f64> = reference.runs.iter().zip(&b.runs).map(|(p, q)| p - q).collect();
                let ci = Ci::of(&d);
                Paired { baseline: b.policy.clone(), difference: ci, planner_better: ci.high < 0.0 }
            })
            .collect(),
        None => Vec::new(),
    };
    let auvs = results.chunks(runs.max(1)).take(names.len()).map(auv_summaries).collect();
    Comparison { n_auvs: sc.fleet.n_auvs, runs, seed: sc.seed, policies: summaries, paired, auvs }
}

fn summarise(name: &str, rs: &[RunResult]) -> PolicySummary {
    let avg = |f: &dyn Fn(&RunResult) -> f64| rs.iter().map(f).sum::<f64>() / rs.len().max(1) as f64;
    let link = |down: bool| {
        let (sent, got) = rs.iter().flat_map(|r| &r.auvs).fold((0u64, 0u64), |acc, a| {
            let l = if down { a.downlink } else { a.uplink };
            (acc.0 + l.sent, acc.1 + l.received)
        });
        if sent == 0 {
            0.0
        } else {
            got as f64 / sent as f64
        }
    };
    let modelled: Vec<f64> = rs.iter().filter_map(|r| r.fleet.modelled_mean).collect();
    let runs: Vec<f64> = rs.iter().map(|r| r.fleet.error.mean).collect();
    let n_auvs = rs.first().map_or(0, |r| r.auvs.len());
    let auv_runs = (0..n_auvs).map(|k| rs.iter().map(|r| r.auvs[k].error.mean).collect()).collect();
    let auv_heard_runs = (0..n_auvs).map(|k| rs.iter().filter(|r| r.auvs[k].uplink.received > 0).count()).collect();
    let per_auv_total = |f: &dyn Fn(&LinkStats) -> u64| -> Vec<u64> {
        (0..n_auvs).map(|k| rs.iter().map(|r| f(&r.auvs[k].uplink)).sum()).collect()
    };
    PolicySummary {
        policy: name.to_string(),
        mean_error: Ci::of(&runs),
        rms_error: avg(&|r| r.fleet.error.rms),
        p95_error: avg(&|r| r.fleet.error.p95),
        max_error: avg(&|r| r.fleet.error.max),
        modelled_mean: (!modelled.is_empty()).then(|| modelled.iter().sum::<f64>() / modelled.len() as f64),
        downlink_success: link(true),
        uplink_success: link(false),
        limit_violation: avg(&|r| r.auvs.iter().map(|a| a.limit_violation).sum::<f64>() / r.auvs.len().max(1) as f64),
        deadline_misses: rs.iter().filter_map(|r| r.planner.as_ref()).map(|p| p.deadline_misses).sum(),
        healthy: rs.iter().all(|r| r.fleet.healthy),
        nees_mean: avg(&|r| r.auvs.iter().map(|a| a.health.nees_mean).sum::<f64>() / r.auvs.len().max(1) as f64),
        diverged: rs.iter().map(|r| r.fleet.diverged).sum(),
        recoveries: rs.iter().flat_map(|r| &r.auvs).map(|a| u64::from(a.health.recoveries)).sum(),
        runs,
        auv_runs,
        auv_heard_runs,
        auv_status_sent: per_auv_total(&|l| l.sent),
        auv_status_lost_in_air: per_auv_total(&|l| l.lost_in_air),
    }
}

/// `reference` minus `baseline` per AUV, paired by run (negative: the reference is better there).
pub fn paired_per_auv(reference: &PolicySummary, baseline: &PolicySummary) -> Vec<Ci> {
    reference
        .auv_runs
        .iter()
        .zip(&baseline.auv_runs)
        .map(|(r, b)| Ci::of(&r.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<f64>>()))
        .collect()
}

/// A plain-text comparison table (policies by mean true error, with 95 % CIs and the paired
/// planner-minus-baseline differences).
pub fn comparison_table(c: &Comparison) -> String {
    let mut out = format!("N = {} survey AUVs, {} runs per policy, base seed {}\n", c.n_auvs, c.runs, c.seed);
    out += &format!(
        "{:<10} {:>22} {:>8} {:>8} {:>8} {:>9} {:>7} {:>7} {:>7}\n",
        "policy", "mean true err [95% CI]", "RMS", "p95", "max", "modelled", "down%", "up%", "limit%"
    );
    for s in &c.policies {
        out += &format!(
            "{:<10} {:>7.2} [{:>6.2}, {:>6.2}] {:>8.2} {:>8.2} {:>8.2} {:>9} {:>7.1} {:>7.1} {:>7.1}\n",
            s.policy,
            s.mean_error.mean,
            s.mean_error.low,
            s.mean_error.high,
            s.rms_error,
            s.p95_error,
            s.max_error,
            s.modelled_mean.map_or("-".to_string(), |m| format!("{m:.2}")),
            100.0 * s.downlink_success,
            100.0 * s.uplink_success,
            100.0 * s.limit_violation,
        );
    }
    if !c.paired.is_empty() {
        let reference = c.policies.first().map_or("", |s| s.policy.as_str());
        out += &format!("{reference} minus baseline (paired by run, m; negative = {reference} better):\n");
        for p in &c.paired {
            out += &format!(
                "  vs {:<10} {:>7.2} [{:>6.2}, {:>6.2}] {}\n",
                p.baseline,
                p.difference.mean,
                p.difference.low,
                p.difference.high,
                if p.planner_better {
                    "reference better"
                } else if p.difference.low > 0.0 {
                    "reference WORSE"
                } else {
                    "no significant difference"
                }
            );
        }
    }
    out
}
