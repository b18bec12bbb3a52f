//! `coopnav bench hbl`: the Table 5 Monte Carlo for MSBL, HBL One and HBL Two on the one engine
//! (`scenarios/gill-table5-*.toml`, Gill's zone metric as the observer); runs and engine steps
//! per second.

use anyhow::Result;
use coopnav_nav::cycle::Configuration;
use coopnav_sim::observe::zone::{zone_monte_carlo, ZoneSpec};
use coopnav_sim::scenario::hbl::table5_scenario;
use serde_json::json;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    #[arg(long, default_value_t = 250)]
    runs: usize,
    /// Worker threads (0 = rayon default).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(Args { runs, threads, seed }: Args) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let mut results = Vec::new();
    for c in [Configuration::Msbl, Configuration::HblOne, Configuration::HblTwo] {
        let sc = table5_scenario(c)?;
        let start = Instant::now();
        let r = pool.install(|| zone_monte_carlo(&sc, ZoneSpec::table5(), runs, seed))?;
        let secs = start.elapsed().as_secs_f64();
        let s = r.summary(seed)?;
        // Every run lasts the file's duration (the zone observer never stops a Table 5 run).
        let steps = runs as f64 * (sc.duration_s / sc.dt).round();
        results.push(json!({
            "configuration": c.label(),
            "runs": runs,
            "dt": sc.dt,
            "seconds": secs,
            "runs_per_second": runs as f64 / secs,
            "engine_steps_per_second": steps / secs,
            "zone_error_mean": s.zone_error.mean,
        }));
    }
    let out = json!({ "target": "hbl", "threads": pool.current_num_threads(), "results": results });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
