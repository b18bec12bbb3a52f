//! `coopnav bench generated-mission`: what `coopnav reproduce closed-loop-generalization` pays
//! per mission. Named missions of its generator file (`scenarios/generators/generalization.toml`,
//! embedded) are flown once per CNA policy of the study, each run exactly as the study flies its
//! run 0 (`run_seed(mission seed, 0)`), one after another on the calling thread; the CPU time of
//! each run (every thread of the process, from the kernel's per-thread accounting) and its wall
//! time are reported per policy and per mission-hour, with the engine alone (policy `none`) as
//! the floor every policy pays.

use super::planner::load_average;
use anyhow::{bail, Context, Result};
use coopnav_core::run_seed;
use coopnav_sim::engine::Faults;
use coopnav_sim::experiments::closed_loop::policies;
use coopnav_sim::experiments::generalization::{FILE, RANGES};
use coopnav_sim::observe::metrics;
use coopnav_sim::policy::PolicySpec;
use coopnav_sim::scenario::generate::Ranges;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Mission indices of the generator file, comma-separated (default: three that span the
    /// study: 2, N = 8 in 3 separated groups with an AUV CNA and 5-state filters; 23, N = 6
    /// adjacent with the ASC and 7-state filters; 7, N = 2 adjacent, ASC, 7-state).
    #[arg(long, value_delimiter = ',', default_values_t = [DEFAULT_MISSIONS[0], DEFAULT_MISSIONS[1], DEFAULT_MISSIONS[2]])]
    missions: Vec<usize>,
    /// CNA policies, comma-separated (default: the study's eleven).
    #[arg(long, value_delimiter = ',')]
    policy: Vec<String>,
    /// Timed runs of each policy on each mission (the median CPU time is reported).
    #[arg(long, default_value_t = 1)]
    runs: usize,
}

/// The missions timed unless `--missions` names others.
const DEFAULT_MISSIONS: [usize; 3] = [2, 23, 7];

/// CPU seconds every thread of this process has run so far (`/proc/self/task/*/schedstat`, whose
/// first field is the nanoseconds on a CPU); `None` where the kernel does not say.
fn process_cpu_s() -> Option<f64> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let text = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

pub fn run(args: Args) -> Result<()> {
    let file = Path::new(FILE);
    let ranges = Ranges::parse(RANGES, file)?;
    let names = if args.policy.is_empty() { policies() } else { args.policy.clone() };
    if args.missions.is_empty() {
        bail!("--missions: give at least one mission index of {FILE}");
    }
    process_cpu_s().context("this benchmark reads CPU time from /proc/self/task/*/schedstat")?;
    let runs = args.runs.max(1);
    let load_before = load_average();
    let mut missions = Vec::new();
    let mut totals = vec![(0.0f64, 0.0f64); names.len()];
    let mut hours_total = 0.0;
    for &index in &args.missions {
        let mission = ranges.mission(index, file)?;
        let sc = &mission.scenario;
        let hours = sc.duration_s / 3600.0;
        hours_total += hours;
        let seed = run_seed(sc.seed, 0);
        let mut rows = Vec::new();
        let (mut cpu_mission, mut wall_mission) = (0.0, 0.0);
        for (p, name) in names.iter().enumerate() {
            let spec = PolicySpec::new(name, sc)?;
            let mut samples = Vec::with_capacity(runs);
            let mut error = f64::NAN;
            for _ in 0..runs {
                let mut policy = spec.build(sc)?;
                let (cpu0, wall0) = (process_cpu_s().unwrap_or(f64::NAN), Instant::now());
                let r = metrics::run(sc, &mut policy, seed, &Faults::default(), &mut ());
                let wall = wall0.elapsed().as_secs_f64();
                let cpu = process_cpu_s().unwrap_or(f64::NAN) - cpu0;
                samples.push((cpu, wall));
                error = r.fleet.error.mean;
            }
            samples.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (cpu, wall) = samples[runs / 2];
            cpu_mission += cpu;
            wall_mission += wall;
            totals[p].0 += cpu;
            totals[p].1 += wall;
            rows.push(json!({
                "policy": name,
                "cpu_s": cpu,
                "wall_s": wall,
                "cpu_s_per_mission_hour": cpu / hours,
                "wall_s_per_mission_hour": wall / hours,
                "fleet_mean_true_error_m": error,
            }));
        }
        missions.push(json!({
            "mission": index,
            "seed": sc.seed,
            "facts": mission.facts.line(),
            "n_auvs": sc.fleet.n_auvs,
            "mission_h": hours,
            "cpu_s (one run of every policy)": cpu_mission,
            "wall_s (one run of every policy)": wall_mission,
            "policies": rows,
        }));
    }
    let per_policy: Vec<_> = names
        .iter()
        .zip(&totals)
        .map(|(name, (cpu, wall))| {
            json!({
                "policy": name,
                "cpu_s_per_mission_hour": cpu / hours_total,
                "wall_s_per_mission_hour": wall / hours_total,
            })
        })
        .collect();
    let out = json!({
        "target": "generated-mission",
        "generator": FILE,
        "runs": "one per policy and mission: the study's run 0, on the calling thread",
        "runs (median CPU time reported)": runs,
        "threads (rayon; the planners' searches are one-thread in these missions)": rayon::current_num_threads(),
        "load_average_before": load_before,
        "load_average_after": load_average(),
        "mission_hours": hours_total,
        "cpu_s (every run of every mission)": totals.iter().map(|t| t.0).sum::<f64>(),
        "per_policy (over every mission timed)": per_policy,
        "missions": missions,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
