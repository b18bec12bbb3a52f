//! `coopnav bench <target>`: speed measurements printed as JSON (one target per crate).

use anyhow::{ensure, Result};
use clap::Subcommand;
use coopnav_plan::workload::Workload;
use coopnav_nav::cycle::Configuration;
use coopnav_plan::{Algorithm, LookAheadPlanner};
use coopnav_sim::hbl::{monte_carlo, Scenario};
use coopnav_sim::predeploy::{self, EXAMPLE};
use serde_json::json;
use std::time::Instant;

#[derive(Subcommand)]
pub enum Target {
    /// One planner decision on the issue-2 workloads: branch-and-bound (1 thread and rayon) vs
    /// brute force, with node counts and AUV-updates per second.
    Planner {
        /// Repetitions per measurement (the median is reported).
        #[arg(long, default_value_t = 5)]
        reps: usize,
        /// Skip the brute force above this many leaves.
        #[arg(long, default_value_t = 6_000_000)]
        brute_max_leaves: u64,
    },
    /// The Table 5 Monte Carlo (Δt = 0.1 s) for MSBL, HBL One and HBL Two.
    Hbl {
        #[arg(long, default_value_t = 250)]
        runs: usize,
        /// Worker threads (0 = rayon default).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// The acoustic link: the full Nams experiment (4 scenarios × 4 behaviours × 40 runs) on the
    /// analytic TL and on a cached TL grid, tracker encode/decode throughput, and one BELLHOP run
    /// against a cached-grid lookup.
    Acomms(crate::bench_acomms::Args),
    /// The closed loop: 3 h mission, 5 survey AUVs, τ = 30 s, planner A = 5, L = 5, 10 Hz EKFs;
    /// wall time against the ≤ 1.1 s target, with the planner/filters/channel split.
    ClosedLoop(crate::bench_closed_loop::Args),
}

pub fn run(target: Target) -> Result<()> {
    match target {
        Target::Planner { reps, brute_max_leaves } => planner(reps.max(1), brute_max_leaves),
        Target::Hbl { runs, threads, seed } => hbl(runs, threads, seed),
        Target::Acomms(args) => crate::bench_acomms::run(args),
        Target::ClosedLoop(args) => crate::bench_closed_loop::run(args),
    }
}

/// Median wall time (s) of `reps` runs of `f`, and its last result.
fn time<T>(reps: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times = Vec::with_capacity(reps);
    let mut last = None;
    for _ in 0..reps {
        let t0 = Instant::now();
        last = Some(f()?);
        times.push(t0.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok((times[reps / 2], last.expect("reps >= 1")))
}

fn planner(reps: usize, brute_max_leaves: u64) -> Result<()> {
    let workloads = [
        Workload { n: 2, a: 5, b: 1, l: 5, gap: 500.0 },
        Workload { n: 2, a: 5, b: 1, l: 5, gap: 100.0 },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 500.0 },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 100.0 },
        Workload { n: 2, a: 7, b: 1, l: 4, gap: 500.0 },
        Workload { n: 2, a: 4, b: 5, l: 3, gap: 500.0 },
        Workload { n: 5, a: 3, b: 6, l: 3, gap: 100.0 },
    ];
    let mut rows = Vec::new();
    for w in workloads {
        let (t_seq, seq) = time(reps, || Ok(w.decide(Algorithm::BranchAndBound, false)?))?;
        let (t_par, par) = time(reps, || Ok(w.decide(Algorithm::BranchAndBound, true)?))?;
        ensure!((seq.option, seq.value) == (par.option, par.value), "parallel and sequential searches disagree on {w:?}");
        let brute = if w.leaves() <= brute_max_leaves {
            let (t, b) = time(1.max(reps / 2), || Ok(w.decide(Algorithm::BruteForce, false)?))?;
            ensure!((b.option, b.value) == (seq.option, seq.value), "branch-and-bound and brute force disagree on {w:?}");
            let updates = b.nodes as f64 * w.n as f64;
            json!({ "seconds": t, "nodes": b.nodes, "auv_updates_per_s": updates / t, "same_decision": true })
        } else {
            serde_json::Value::Null
        };
        rows.push(json!({
            "workload": w,
            "leaves": w.leaves(),
            "decision": seq.option,
            "min_cost": seq.value,
            "bnb_1_thread": { "seconds": t_seq, "nodes": seq.nodes },
            "bnb_parallel": { "seconds": t_par, "nodes": par.nodes, "threads": rayon_threads() },
            "brute_force": brute,
            "tree_nodes_full": (1..=w.l as u32 + 1).map(|d| ((w.a * w.b) as u64).pow(d)).sum::<u64>(),
        }));
    }
    let missions = [4, 6].into_iter().map(mission_nodes).collect::<Result<Vec<_>>>()?;
    println!("{}", serde_json::to_string_pretty(&json!({ "target": "planner", "reps": reps, "results": rows, "missions": missions }))?);
    Ok(())
}

/// Nodes expanded over the whole embedded example mission (N = 2, A = 5) at look-ahead `l`:
/// branch-and-bound (one thread) against the full tree a plain depth-first search visits and the
/// brute force's path recomputations.
fn mission_nodes(l: usize) -> Result<serde_json::Value> {
    let file = std::path::Path::new("<embedded example>");
    let mut mission = predeploy::Scenario::parse(EXAMPLE, file)?.build(file, std::path::Path::new("."))?;
    mission.planner.look_ahead = l;
    mission.planner.search.parallel = false;
    let m = mission.planner.motion.options().len() as u64;
    let mut planner = LookAheadPlanner::new(mission.planner)?;
    let t0 = Instant::now();
    let result = predeploy::run(&mission, &mut planner, &|_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let bnb: u64 = result.decisions.iter().map(|d| d.nodes).sum();
    let full: u64 = result.decisions.iter().map(|d| (1..=d.levels_searched as u32).map(|k| m.pow(k)).sum::<u64>()).sum();
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

fn hbl(runs: usize, threads: usize, seed: u64) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let mut results = Vec::new();
    for c in [Configuration::Msbl, Configuration::HblOne, Configuration::HblTwo] {
        let sc = Scenario::table5(c);
        let start = Instant::now();
        let r = pool.install(|| monte_carlo(&sc, runs, seed, &|_| {}))?;
        let secs = start.elapsed().as_secs_f64();
        let s = &r.summary;
        results.push(json!({
            "configuration": s.configuration,
            "runs": runs,
            "dt": sc.dt,
            "seconds": secs,
            "runs_per_second": runs as f64 / secs,
            "filter_updates": s.filter_updates,
            "filter_predicts": s.filter_predicts,
            "ekf_updates_per_second": s.filter_updates as f64 / secs,
            "ekf_steps_per_second": (s.filter_updates + s.filter_predicts) as f64 / secs,
            "zone_error_mean": s.zone_error.mean,
        }));
    }
    let out = json!({ "target": "hbl", "threads": pool.current_num_threads(), "results": results });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
