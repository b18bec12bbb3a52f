//! The merge's time over many finished runs without running them all: plans a one-cell sweep of
//! `N` runs (default 10,000: two baseline policies, N/2 runs each) in 2 shards, runs one real
//! mission, writes every shard's results file with that mission's record under every id (the
//! merge reads, pairs and tabulates N whole records, as after a real run), then times `merge`.
//! Prints one JSON object. `cargo run --release -p coopnav-sweep --example merge_bench [N]`.

use coopnav_sweep::plan::{plan_file, Plan};
use coopnav_sweep::shard::{self, finished_bytes, read_frames, Header, Record};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map_or(Ok(10_000), |a| a.parse())?;
    let tmp = tempfile::tempdir()?;
    let file = tmp.path().join("s.toml");
    let text = format!("scenarios = [\"default\"]\npolicies = [\"zigzag\", \"racetrack\"]\nruns = {}\n", n / 2);
    std::fs::write(&file, &text)?;
    let (dir, _) = plan_file(&file, &text, 2, &tmp.path().join("plan"), false, true, "bench")?;
    let one = tmp.path().join("one.toml");
    let one_text = "scenarios = [\"default\"]\npolicies = [\"zigzag\"]\nruns = 1\n";
    std::fs::write(&one, one_text)?;
    let (one_dir, _) = plan_file(&one, one_text, 1, &tmp.path().join("one"), false, false, "bench")?;
    let one_plan = Plan::open(&one_dir)?;
    shard::run_shards(&one_plan, &[0], &|_| {})?;
    let record = read_frames(&std::fs::read(shard::finished_path(&one_plan, 0))?).records.remove(0);
    let plan = Plan::open(&dir)?;
    std::fs::create_dir_all(shard::results_dir(&plan))?;
    for s in 0..2 {
        let header =
            Header { version: coopnav_sweep::plan::VERSION.into(), digest: plan.inputs.digest.clone(), shard: s };
        let records: Vec<Record> =
            plan.shard_runs(s)?.into_iter().map(|id| Record { id, outcome: record.outcome.clone() }).collect();
        std::fs::write(shard::finished_path(&plan, s), finished_bytes(&header, &records))?;
    }
    let start = Instant::now();
    let merged = coopnav_sweep::merge::merge(&plan, None, false, "bench")?;
    let wall = start.elapsed().as_secs_f64();
    let size = |f: &str| std::fs::metadata(merged.dir.join(f)).map_or(0, |m| m.len());
    println!(
        "{{\"runs\": {n}, \"merge_wall_s\": {wall:.3}, \"runs_parquet_bytes\": {}, \"fleet_parquet_bytes\": {}}}",
        size("runs.parquet"),
        size("fleet.parquet")
    );
    Ok(())
}
