//! `coopnav bench post`: post-processing (EKF + RTS) of a generated field log, by default the
//! target day: 24 h at 10 Hz (yaw rate, speed and heading rows), 5 moving beacons, a
//! range every 15 s; with `--tune`, the tuning on it too. Peak memory: run under
//! `/usr/bin/time -v` (generating the log is part of it; its rows are reported).

use anyhow::{Context, Result};
use coopnav_nav::fieldlog::{write_field_log, FieldLog, TimeBase};
use coopnav_nav::post::{postprocess_rows, PostConfig};
use coopnav_nav::post_tune::{tune, TuneOptions};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Log length (hours).
    #[arg(long, default_value_t = 24.0)]
    hours: f64,
    #[arg(long, default_value_t = 5)]
    beacons: u32,
    /// Also time `postprocess --tune` (default options) on the same log.
    #[arg(long)]
    tune: bool,
    /// With --tune: the search's dead-reckoning block (s; 0: full rate).
    #[arg(long, default_value_t = TuneOptions::default().dead_reckoning_block_s)]
    tune_block_s: f64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the generated log to this file (version 2, relative time) and stop: the input of an
    /// end-to-end `hbl postprocess` run, e.g. under `/usr/bin/time -v`.
    #[arg(long)]
    write_log: Option<PathBuf>,
}

pub fn run(Args { hours, beacons, tune: with_tune, tune_block_s, seed, write_log }: Args) -> Result<()> {
    let spec = SyntheticSpec { duration_s: hours * 3600.0, beacons, seed, ..SyntheticSpec::default() };
    let start = Instant::now();
    let rows = synthetic_log(&spec);
    let generate_s = start.elapsed().as_secs_f64();
    if let Some(path) = write_log {
        let file = std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        let log = FieldLog { time: TimeBase::Relative, rows };
        write_field_log(std::io::BufWriter::new(file), &log, None)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("{}", json!({ "target": "post", "hours": hours, "rows": log.rows.len(), "wrote": path }));
        return Ok(());
    }
    let cfg = PostConfig::default();
    let start = Instant::now();
    let r = postprocess_rows(&rows, &cfg)?;
    let post_s = start.elapsed().as_secs_f64();
    let mut out = json!({
        "target": "post",
        "hours": hours,
        "rate_hz": spec.rate_hz,
        "beacons": beacons,
        "range_every_s": spec.range_every_s,
        "rows": rows.len(),
        "filter_steps": r.samples.len(),
        "ranges": r.summary.ranges,
        "generate_seconds": generate_s,
        "postprocess_seconds": post_s,
        "rms_smoothed_error_m": r.summary.rms_smoothed_error,
    });
    drop(r);
    if with_tune {
        let start = Instant::now();
        let opts = TuneOptions { dead_reckoning_block_s: tune_block_s, ..TuneOptions::default() };
        let t = tune(&rows, &cfg, &opts)?;
        out["tune_seconds"] = json!(start.elapsed().as_secs_f64());
        // The machine is shared: the 1-minute load average (Linux) beside the time.
        let load = std::fs::read_to_string("/proc/loadavg").ok();
        out["load_average_1m"] = json!(load.and_then(|l| l.split_whitespace().next()?.parse::<f64>().ok()));
        out["tune_block_s"] = json!(tune_block_s);
        out["tune_evaluations"] = json!(t.evaluations);
        out["tune_iterations"] = json!(t.iterations);
        out["tuned"] = json!(t.after.values);
        out["tune_log_likelihood_before_after"] = json!([t.before.log_likelihood, t.after.log_likelihood]);
    }
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
