//! `coopnav sitl [FILE] --lockstep -o DIR`: the closed-loop mission with the CNA's planner
//! outside the engine, as a `coopnav live cna` child process on LCM (coopnav-live's `sitl`; the
//! world waits for each decision), written to the same run directory as `coopnav simulate`, plus
//! the child's LCM log (`cna.lcm`) and the world's account of it (`sitl.json`).

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{bail, Context, Result};
use coopnav_core::limits::Estimate;
use coopnav_live::sitl::{run_lockstep, SitlOptions};
use coopnav_sim::batch::work;
use coopnav_sim::output::run::write_run;
use coopnav_sim::scenario::file::Validate;
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use std::time::Duration;

#[derive(clap::Args)]
pub struct Args {
    /// CNA policy the child runs (the names `coopnav simulate --policy` takes).
    #[arg(long, default_value = "planner-estimator")]
    policy: String,
    /// Seed (default: the scenario's).
    #[arg(long)]
    seed: Option<u64>,
    /// The world's clock on the bus; the world waits for each decision (results equal
    /// `coopnav simulate`'s with the same seed).
    #[arg(long)]
    lockstep: bool,
    /// Free-running at W × wall-clock time (not implemented yet: use --lockstep).
    #[arg(long)]
    warp: Option<f64>,
    /// One `live auv` per survey AUV in place of the engine's filters (not implemented yet).
    #[arg(long)]
    live_auvs: bool,
    /// LCM URL (UDP multicast) of the world and its child.
    #[arg(long, default_value = "udpm://239.255.76.67:7667?ttl=0")]
    url: String,
    /// Seconds the world waits for one decision before the CNA holds its last command.
    #[arg(long, default_value_t = 10.0)]
    decision_timeout: f64,
    /// Scenario file, -o, --force, --example.
    #[command(flatten)]
    scenario: ScenarioArgs<Sitl>,
}

/// What `coopnav sitl` reads: a closed-loop scenario.
pub enum Sitl {}

impl ScenarioCommand for Sitl {
    type Scenario = Scenario;
    const SCENARIO_HELP: &'static str = "Scenario file (TOML). Omit it to run the embedded default mission";
    const OUTPUT_HELP: &'static str = "Output directory (default: a fresh runs/sitl-<name>)";
    const EXAMPLE_HELP: &'static str = "Print the embedded default scenario as TOML and exit";
    const EXAMPLE: &'static str = EXAMPLE;
    const EMBEDDED: &'static str = "default";
    const RUN_PREFIX: &'static str = "sitl";
    const READ: fn(&str, &std::path::Path) -> Result<Scenario, coopnav_sim::scenario::file::ScenarioError> =
        Scenario::read;
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    const WORK: fn(&Scenario) -> Vec<Estimate> = |scenario| work::closed_loop(scenario, 1, 1);
}

pub fn run(args: Args) -> Result<()> {
    if args.scenario.print_example() {
        return Ok(());
    }
    if args.warp.is_some() || !args.lockstep {
        bail!("free-running sitl (--warp) is not implemented yet: give --lockstep");
    }
    if args.live_auvs {
        bail!("--live-auvs is not implemented yet: the engine's own filters navigate the survey AUVs");
    }
    if !(args.decision_timeout.is_finite() && args.decision_timeout > 0.0 && args.decision_timeout < 1e6) {
        bail!("--decision-timeout {}: give a positive number of seconds", args.decision_timeout);
    }
    let Loaded { mut scenario, stem, file, .. } = args.scenario.load()?;
    if let Some(seed) = args.seed {
        scenario.seed = seed;
    }
    let dir = args.scenario.run_dir(&stem, &[&file])?;
    let log = std::env::temp_dir().join(format!("coopnav-sitl-{}-cna.lcm", std::process::id()));
    let exe = std::env::current_exe().context("the coopnav binary's path")?;
    let mut child = vec![exe.display().to_string(), "live".into(), "cna".into()];
    if file.is_file() {
        child.push(file.display().to_string());
    }
    for (flag, value) in [
        ("--policy", args.policy.as_str()),
        ("--clock", "bus"),
        ("--url", args.url.as_str()),
        ("--log", &log.display().to_string()),
    ] {
        child.extend([flag.to_string(), value.to_string()]);
    }
    let opts =
        SitlOptions { url: args.url.clone(), child, decision_timeout: Duration::from_secs_f64(args.decision_timeout) };
    let run = run_lockstep(&scenario, &args.policy, &opts)?;
    let bytes = std::fs::read(&log).with_context(|| format!("the child's log {}", log.display()));
    let _ = std::fs::remove_file(&log);
    dir.write_bytes("cna.lcm", bytes?)?;
    let world = serde_json::json!({ "world": run.counts, "live_cna": run.child_summary });
    dir.write_json("sitl.json", &world)?;
    let out = write_run(dir, &scenario, &run.result, &std::env::args().collect::<Vec<_>>().join(" "))
        .context("writing the run directory")?;
    let c = &run.counts;
    println!(
        "sitl lockstep · policy {} · {} decisions ({} missed, {} on other inputs) · {} statuses to the CNA -> {}",
        run.result.policy,
        c.decisions,
        c.missed_decisions,
        c.input_mismatches,
        c.statuses_published,
        out.display()
    );
    Ok(())
}
