//! `coopnav sitl [FILE] --lockstep|--warp W [--live-auvs] -o DIR`: the closed-loop mission with
//! the CNA's planner outside the engine, as a `coopnav live cna` child process on LCM, and with
//! `--live-auvs` one `coopnav live auv` child per survey AUV (coopnav-live's `sitl`), written to
//! the same run directory as `coopnav simulate`, plus each child's LCM log (`cna.lcm`,
//! `auvK.lcm`), the navigators' configs (`auvK.toml`) and the world's account of its children
//! (`sitl.json`).

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{bail, Context, Result};
use coopnav_core::limits::Estimate;
use coopnav_live::import::field_log;
use coopnav_live::sitl::{self as world, LiveAuvs, Pace, SitlOptions, SitlRun};
use coopnav_live::LiveConfig;
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
    #[arg(long, conflicts_with = "warp")]
    lockstep: bool,
    /// Free running at W × wall-clock time: the CNA's commands are applied when they arrive.
    #[arg(long)]
    warp: Option<f64>,
    /// One `live auv` per survey AUV on the world's sensor and range messages; the run is scored
    /// on their estimates.
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
    const FORMAT: crate::input::Format = crate::input::Format::Mission;
    const READ: fn(&str, &std::path::Path) -> Result<Scenario, coopnav_sim::scenario::file::ScenarioError> =
        Scenario::read;
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    const WORK: fn(&Scenario) -> Vec<Estimate> = |scenario| work::closed_loop(scenario, 1, 1);
}

pub fn run(args: Args) -> Result<()> {
    if args.scenario.print_example() {
        return Ok(());
    }
    let pace = match (args.lockstep, args.warp) {
        (true, None) => Pace::Lockstep,
        (false, Some(w)) if w.is_finite() && w > 0.0 && w <= 1000.0 => Pace::Warp(w),
        (false, Some(w)) => bail!("--warp {w}: give a factor in (0, 1000]"),
        _ => bail!("give --lockstep (the world waits for each decision) or --warp W (free running)"),
    };
    if !(args.decision_timeout.is_finite() && args.decision_timeout > 0.0 && args.decision_timeout < 1e6) {
        bail!("--decision-timeout {}: give a positive number of seconds", args.decision_timeout);
    }
    let Loaded { mut scenario, stem, file, .. } = args.scenario.load()?;
    if let Some(seed) = args.seed {
        scenario.seed = seed;
    }
    let dir = args.scenario.run_dir(&stem, &[&file])?;
    let work = std::env::temp_dir().join(format!("coopnav-sitl-{}", std::process::id()));
    std::fs::create_dir_all(&work).with_context(|| format!("creating {}", work.display()))?;
    let log = work.join("cna.lcm");
    let exe = std::env::current_exe().context("the coopnav binary's path")?.display().to_string();
    let mut child = vec![exe.clone(), "live".into(), "cna".into()];
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
    let live_auvs = args.live_auvs.then(|| LiveAuvs {
        program: vec![exe.clone(), "live".into(), "auv".into()],
        dir: work.clone(),
        faults: Default::default(),
        restart: None,
        estimate_timeout: Duration::from_secs(5),
    });
    let opts = SitlOptions {
        url: args.url.clone(),
        child,
        decision_timeout: Duration::from_secs_f64(args.decision_timeout),
        pace,
        live_auvs,
    };
    let outcome = world::run(&scenario, &args.policy, &opts);
    let imported = match &outcome {
        Ok(run) => import_logs(run),
        Err(_) => Ok(()),
    };
    let kept = imported.and_then(|()| keep_logs(&dir, &work));
    let _ = std::fs::remove_dir_all(&work);
    let run = outcome?;
    kept?;
    let world = serde_json::json!({
        "pace": match pace { Pace::Lockstep => "lockstep".to_string(), Pace::Warp(w) => format!("warp {w}") },
        "wall_s": run.wall_s,
        "world": run.counts,
        "latencies": run.latencies,
        "live_auvs": run.auvs,
        "live_cna": run.child_summary,
        "live_auv_summaries": run.auv_summaries,
    });
    dir.write_json("sitl.json", &world)?;
    let out = write_run(dir, &scenario, &run.result, &std::env::args().collect::<Vec<_>>().join(" "))
        .context("writing the run directory")?;
    let c = &run.counts;
    let mode = match pace {
        Pace::Lockstep => "lockstep".to_string(),
        Pace::Warp(w) => format!("warp {w}"),
    };
    let live = if run.auvs.is_some() { " · live AUVs" } else { "" };
    println!(
        "sitl {mode}{live} · policy {} · {} decisions ({} missed, {} on other inputs) · {} statuses to the CNA · fleet error {:.2} m -> {}",
        run.result.policy,
        c.decisions,
        c.missed_decisions,
        c.input_mismatches,
        c.statuses_published,
        run.result.fleet.error.mean,
        out.display()
    );
    Ok(())
}

/// Each live navigator's LCM log as a post-processing log beside it (`auvK.log`, with the
/// world's truth of AUV K once a second), and its filter's config as `hbl postprocess --config`
/// reads it (`auvK.post.toml`): `coopnav hbl postprocess auvK.log --config auvK.post.toml`.
fn import_logs(run: &SitlRun) -> Result<()> {
    let rows = run.result.trace.as_ref().map(|t| t.rows.as_slice()).unwrap_or_default();
    for (k, logs) in run.auv_logs.iter().enumerate() {
        let truth: Vec<(f64, f64, f64)> =
            rows.iter().filter(|r| r.auv == k).map(|r| (r.t, r.true_x, r.true_y)).collect();
        for log in logs {
            let config = log.with_extension("toml");
            let text = std::fs::read_to_string(&config).with_context(|| format!("{}", config.display()))?;
            let cfg = LiveConfig::from_toml(&text).with_context(|| format!("{}", config.display()))?;
            let file = std::fs::File::open(log).with_context(|| format!("{}", log.display()))?;
            let imported = field_log(std::io::BufReader::new(file), k as i16, cfg.start, &truth)?;
            std::fs::write(log.with_extension("log"), imported.log)?;
            std::fs::write(log.with_extension("post.toml"), toml::to_string(&cfg.post_equivalent())?)?;
        }
    }
    Ok(())
}

/// Copies the children's logs and configs from the work directory into the run directory.
fn keep_logs(dir: &coopnav_sim::output::RunDir, work: &std::path::Path) -> Result<()> {
    let mut names: Vec<_> = std::fs::read_dir(work)
        .with_context(|| format!("reading {}", work.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    for name in names {
        let bytes = std::fs::read(work.join(&name)).with_context(|| format!("the child's file {name}"))?;
        dir.write_bytes(&name, bytes)?;
    }
    Ok(())
}
