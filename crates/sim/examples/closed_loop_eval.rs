//! The full `closed-loop-vs-baselines` evaluation with a chosen number of runs per cell, writing
//! the table and the plot of the paired differences:
//! `cargo run --release -p coopnav-sim --example closed_loop_eval -- RUNS SEED OUT_DIR [SCENARIO [N,N,... [POLICY,...]]]`
//! (SCENARIO: `current` or `sloping-auv-cna`, one of them only, or `all`; default both; N: only
//! these fleet sizes, default all; POLICY: planner-estimator first, then only these baselines,
//! default every one).

use coopnav_sim::experiments::closed_loop::{difference_svg, evaluate, policies, setup, Cell};
use coopnav_sim::experiments::{ReproOptions, Size};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (runs, seed, out, only, sizes, chosen) = match args.as_slice() {
        [runs, seed, out] => (runs, seed, out, "all", None, None),
        [runs, seed, out, only] => (runs, seed, out, only.as_str(), None, None),
        [runs, seed, out, only, sizes] => (runs, seed, out, only.as_str(), Some(sizes), None),
        [runs, seed, out, only, sizes, chosen] => (runs, seed, out, only.as_str(), Some(sizes), Some(chosen)),
        _ => return Err("usage: closed_loop_eval RUNS SEED OUT_DIR [SCENARIO [N,N,... [POLICY,...]]]".into()),
    };
    let policies: Vec<String> = chosen.map_or_else(policies, |c| c.split(',').map(str::to_string).collect());
    let (runs, seed): (usize, u64) = (runs.parse()?, seed.parse()?);
    let sizes: Option<Vec<usize>> =
        sizes.map(|s| s.split(',').map(str::parse).collect::<Result<_, _>>()).transpose()?;
    let (mut settings, _) = setup(&ReproOptions::new(Size::Full, seed))?;
    settings.retain(|s| only == "all" || s.name == only);
    if settings.is_empty() {
        return Err(format!("no scenario {only} (allowed: current, sloping-auv-cna, all)").into());
    }
    if let Some(sizes) = &sizes {
        for s in settings.iter_mut() {
            s.n.retain(|n| sizes.contains(n));
        }
    }
    // Before the runs, so a bad OUT_DIR fails at once rather than after them.
    std::fs::create_dir_all(out).map_err(|e| format!("output directory {out}: {e}"))?;
    let start = Instant::now();
    let report = evaluate(&settings, runs, None, seed, &policies, &|_| {})?;
    let wall = start.elapsed().as_secs_f64();
    let cells: Vec<Cell> = serde_json::from_value(report.data["cells"].clone())?;
    let checks: Vec<String> = report.checks.iter().map(|c| c.line()).collect();
    let text = format!("{}\n{}\nwall time {wall:.1} s\n", report.table, checks.join("\n"));
    std::fs::write(format!("{out}/table.txt"), &text)?;
    std::fs::write(format!("{out}/differences.svg"), difference_svg(&cells)?)?;
    std::fs::write(format!("{out}/report.json"), serde_json::to_string_pretty(&report)?)?;
    print!("{text}");
    Ok(())
}
