//! `coopnav bench hbl`: the Table 5 Monte Carlo for MSBL, HBL One and HBL Two; runs and EKF
//! steps per second.

use anyhow::Result;
use coopnav_nav::cycle::Configuration;
use coopnav_sim::hbl::{monte_carlo, Scenario};
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
