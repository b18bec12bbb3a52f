//! `coopnav bench planner`: one planner decision on the standard workloads (`Workload::standard`,
//! the list the criterion bench runs too: branch-and-bound on one thread and with rayon against
//! brute force), and the nodes expanded over the embedded example mission.

use anyhow::{ensure, Result};
use coopnav_plan::predeploy;
use coopnav_plan::workload::Workload;
use coopnav_plan::{Algorithm, LookAheadPlanner};
use coopnav_sim::scenario::plan::{self as plan_scenario, EXAMPLE};
use serde_json::json;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Timed runs per measurement (the median is reported).
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// Skip the brute force above this many leaves.
    #[arg(long, default_value_t = 6_000_000)]
    brute_max_leaves: u64,
    /// Nodes the parallel mode searches on one thread before it shares the tree (default: the
    /// planner's, `SearchConfig::parallel_after_nodes`; 0 = share at once).
    #[arg(long)]
    parallel_after_nodes: Option<u64>,
    /// ... nor before this many microseconds (default: the planner's,
    /// `SearchConfig::parallel_after_us`; 0 = the node count alone).
    #[arg(long)]
    parallel_after_us: Option<u64>,
}

/// Median wall time (s) of `runs` runs of `f`, and its last result.
fn time<T>(runs: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let t0 = Instant::now();
        last = Some(f()?);
        times.push(t0.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok((times[runs / 2], last.expect("runs >= 1")))
}

/// The machine's 1-, 5- and 15-minute load averages (`/proc/loadavg`; `None` where there is none):
/// timings on a shared machine mean little without them.
pub(super) fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut fields = text.split_whitespace().map(|f| f.parse::<f64>().ok());
    Some([fields.next()??, fields.next()??, fields.next()??])
}

pub fn run(args: Args) -> Result<()> {
    let (runs, brute_max_leaves) = (args.runs.max(1), args.brute_max_leaves);
    let one_thread = Workload::search(Algorithm::BranchAndBound, false);
    let mut parallel = Workload::search(Algorithm::BranchAndBound, true);
    parallel.parallel_after_nodes = args.parallel_after_nodes.unwrap_or(parallel.parallel_after_nodes);
    parallel.parallel_after_us = args.parallel_after_us.unwrap_or(parallel.parallel_after_us);
    let load_before = load_average();
    let mut rows = Vec::new();
    for w in Workload::standard() {
        let (t_seq, seq) = time(runs, || Ok(w.decide(one_thread)?))?;
        let (t_par, par) = time(runs, || Ok(w.decide(parallel)?))?;
        ensure!(
            (seq.option, seq.value) == (par.option, par.value),
            "parallel and sequential searches disagree on {w:?}"
        );
        let brute = if w.leaves() <= brute_max_leaves {
            let (t, b) = time(1.max(runs / 2), || Ok(w.decide(Workload::search(Algorithm::BruteForce, false))?))?;
            ensure!(
                (b.option, b.value) == (seq.option, seq.value),
                "branch-and-bound and brute force disagree on {w:?}"
            );
            let updates = b.nodes as f64 * w.n as f64;
            json!({ "seconds": t, "nodes": b.nodes, "auv_updates_per_s": updates / t, "same_decision": true })
        } else {
            serde_json::Value::Null
        };
        rows.push(json!({
            "workload": w,
            "name": w.name(),
            "leaves": w.leaves(),
            "decision": seq.option,
            "min_cost": seq.value,
            "bnb_1_thread": { "seconds": t_seq, "nodes": seq.nodes },
            "bnb_parallel": {
                "seconds": t_par,
                "nodes": par.nodes,
                "threads": rayon_threads(),
                "after_nodes": parallel.parallel_after_nodes,
                "after_us": parallel.parallel_after_us,
            },
            "parallel_speedup": t_seq / t_par,
            "brute_force": brute,
            "tree_nodes_full": (1..=w.l as u32 + 1).map(|d| ((w.a * w.b) as u64).pow(d)).sum::<u64>(),
        }));
    }
    let missions = [4, 6].into_iter().map(mission_nodes).collect::<Result<Vec<_>>>()?;
    println!(
        "{}",
        serde_json::to_string_pretty(&json!({
            "target": "planner",
            "runs": runs,
            "load_average": { "before": load_before, "after": load_average() },
            "results": rows,
            "missions": missions
        }))?
    );
    Ok(())
}

/// Nodes expanded over the whole embedded example mission (N = 2, A = 5) at look-ahead `l`:
/// branch-and-bound (one thread) against the full tree a plain depth-first search visits and the
/// brute force's path recomputations.
fn mission_nodes(l: usize) -> Result<serde_json::Value> {
    let file = std::path::Path::new("<embedded example>");
    let mut mission = plan_scenario::Scenario::parse(EXAMPLE, file)?.build(file, std::path::Path::new("."))?;
    mission.planner.look_ahead = l;
    mission.planner.search.parallel = false;
    let m = mission.planner.motion.options().len() as u64;
    let mut planner = LookAheadPlanner::new(mission.planner)?;
    let t0 = Instant::now();
    let result = predeploy::run(&mission, &mut planner, &|_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let bnb: u64 = result.decisions.iter().map(|d| d.nodes).sum();
    let full: u64 =
        result.decisions.iter().map(|d| (1..=d.levels_searched as u32).map(|k| m.pow(k)).sum::<u64>()).sum();
    let brute: u64 = result.decisions.iter().map(|d| m.pow(d.levels_searched as u32) * d.levels_searched as u64).sum();
    Ok(json!({
        "scenario": "embedded example (N = 2, A = 5, tau = 10 s)",
        "look_ahead": l,
        "decisions": result.decisions.len(),
        "seconds_1_thread": seconds,
        "bnb_nodes": bnb,
        "full_tree_nodes": full,
        "brute_force_nodes": brute,
        "bnb_fraction_of_full_tree": bnb as f64 / full as f64,
    }))
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}
