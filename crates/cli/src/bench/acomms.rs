//! `coopnav bench acomms`: the Nams experiment on the analytic TL and on a cached TL grid, tracker
//! encode/decode throughput, and one BELLHOP run against a cached-grid lookup.

use anyhow::Result;
use coopnav_acomms::status::Frame0;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::tl::cached::{CachedGrid, GridSpec};
use coopnav_acomms::tracker::MaskWidth;
use coopnav_acomms::workload::{sample_frame0, TrackerExchange};
use coopnav_acomms::TransmissionLoss;
use coopnav_core::{Bathymetry, Shelf, Vec3};
use coopnav_sim::batch::nams::{run_experiment, ExperimentResult, ExperimentTl};
use coopnav_sim::experiments::nams::default_tl;
use coopnav_sim::scenario::nams::ExperimentConfig;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{json, Value};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Runs per (scenario, behaviour).
    #[arg(long, default_value_t = 40)]
    runs: usize,
    /// Skip everything that needs BELLHOP.
    #[arg(long)]
    no_bellhop: bool,
}

fn bar(len: u64, msg: &'static str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb.set_message(msg);
    pb
}

fn summary(r: &ExperimentResult) -> Value {
    let rows: Vec<Value> = r
        .cells
        .iter()
        .map(|c| json!({"scenario": c.scenario, "behaviour": c.behaviour, "bandwidth": c.mean.bandwidth, "status_period": c.mean.status_period, "duty_cycle": c.mean.duty_cycle, "score": c.mean.score}))
        .collect();
    Value::Array(rows)
}

fn experiment(tl: Arc<dyn TransmissionLoss>, label: &str, runs: usize) -> Result<Value> {
    let cfg = ExperimentConfig { runs, ..ExperimentConfig::default() };
    let n = (cfg.scenarios.len() * cfg.behaviours.len() * runs) as u64;
    let pb = bar(n, "experiment");
    let t = Instant::now();
    let r = run_experiment(&cfg, &ExperimentTl::Shared(tl), &|k| pb.inc(k))?;
    let secs = t.elapsed().as_secs_f64();
    pb.finish_and_clear();
    Ok(json!({"tl": label, "runs": n, "seconds": secs, "threads": rayon::current_num_threads(), "cells": summary(&r)}))
}

/// Operations per second of `f`, over about `budget` seconds.
fn rate(budget: f64, mut f: impl FnMut()) -> f64 {
    let (t, mut n) = (Instant::now(), 0u64);
    while t.elapsed().as_secs_f64() < budget {
        for _ in 0..1000 {
            f();
        }
        n += 1000;
    }
    n as f64 / t.elapsed().as_secs_f64()
}

fn tracker() -> Result<Value> {
    let frame = sample_frame0();
    let bytes = frame.encode(MaskWidth::Narrow, 64)?;
    let enc = rate(0.5, || {
        black_box(black_box(&frame).encode(MaskWidth::Narrow, 64).ok());
    });
    let dec = rate(0.5, || {
        black_box(Frame0::decode(black_box(&bytes), MaskWidth::Narrow).ok());
    });
    // Tracker bookkeeping: one transmit and one receive per vehicle per iteration.
    let mut exchange = TrackerExchange::default();
    let cycle = rate(0.5, || exchange.step());
    Ok(
        json!({"frame0_bytes": bytes.len(), "header_entries": frame.header.entries.len(), "encode_per_s": enc, "decode_per_s": dec, "tracker_exchanges_per_s": cycle}),
    )
}

fn bellhop(runs: usize) -> Result<Value> {
    let bathy = Arc::new(Bathymetry::shelf(&Shelf::default())?);
    let bh = match Bellhop::new(AcousticEnv::nams(bathy)) {
        Ok(b) => b,
        Err(e) => return Ok(json!({"skipped": e.to_string()})),
    };
    let (src, rx) = (Vec3::new(250.0, 250.0, 25.0), Vec3::new(600.0, 400.0, 28.0));
    let t = Instant::now();
    let tl_direct = bh.tl(&src, &rx)?;
    let one_run = t.elapsed().as_secs_f64();
    let spec = GridSpec { bearings: 8, range_step: 25.0, max_range: 3000.0, depth_step: 2.5, max_depth: 60.0 };
    let pb = bar(spec.bearings as u64, "bellhop grid");
    let t = Instant::now();
    let grid = CachedGrid::build(&bh, Vec3::new(1000.0, 1000.0, 30.0), spec, &|k| pb.inc(k))?;
    let build = t.elapsed().as_secs_f64();
    pb.finish_and_clear();
    let lookups = rate(0.5, || {
        black_box(grid.tl(black_box(&src), black_box(&rx)).ok());
    });
    let (tl_cached, grid_bytes) = (grid.tl(&src, &rx)?, grid.bytes());
    let exp = experiment(Arc::new(grid), "cached BELLHOP grid (8 bearings from (1000, 1000, 30))", runs)?;
    Ok(json!({
        "one_run_seconds": one_run,
        "tl_direct_db": tl_direct,
        "tl_cached_db": tl_cached,
        "grid_build_seconds": build,
        "grid_bytes": grid_bytes,
        "cached_lookup_seconds": 1.0 / lookups,
        "speedup_cached_vs_run": one_run * lookups,
        "experiment": exp,
    }))
}

pub fn run(args: Args) -> Result<()> {
    anyhow::ensure!((1..=10_000).contains(&args.runs), "--runs {} must be in [1, 10000]", args.runs);
    let tl = default_tl();
    let analytic = experiment(Arc::new(tl), &format!("analytic, k = {}", tl.k), args.runs)?;
    let pb = bar(8, "analytic grid");
    let grid = CachedGrid::build(
        &tl,
        Vec3::new(1000.0, 1000.0, 30.0),
        GridSpec { bearings: 8, range_step: 25.0, max_range: 3000.0, depth_step: 2.5, max_depth: 60.0 },
        &|k| pb.inc(k),
    )?;
    pb.finish_and_clear();
    let cached = experiment(Arc::new(grid), "cached grid of the analytic model", args.runs)?;
    let bellhop = if args.no_bellhop { json!({"skipped": "--no-bellhop"}) } else { bellhop(args.runs)? };
    let out = json!({"target": "acomms", "experiment_analytic": analytic, "experiment_cached_analytic": cached, "tracker": tracker()?, "bellhop": bellhop});
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
