//! `coopnav live auv --auv K`: a survey AUV's OWTT navigator, and `coopnav live cna [FILE]`: the
//! CNA's planner, as live processes on LCM (the loops, the navigator and the planner are
//! coopnav-live's; this only parses arguments, reads the config or scenario, installs the
//! SIGINT/SIGTERM stop and prints the one-line JSON summary on stdout); and `coopnav live import
//! LOG... -o DIR`: their LCM logs as a run directory (`run.alog`, `replay.html`, each AUV's
//! post-processing log and config), read by coopnav-live's `import`.

use anyhow::{bail, Context, Result};
use coopnav_live::import::{field_log, run_alog, truth_from_timeseries, LiveRecord};
use coopnav_live::{run_auv, run_cna, AuvNavigator, ClockSource, CnaPlanner, LiveConfig, RunOptions};
use coopnav_moos::{replay, write_run_alog_with};
use coopnav_sim::output::moos_export::ALOG_FILE;
use coopnav_sim::output::{Manifest, RunDir};
use coopnav_sim::scenario::file::read_scenario_text;
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use serde_json::json;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

#[derive(clap::Subcommand)]
pub enum Command {
    /// A survey AUV's navigator: subscribes to COOPNAV_AUV{K}_SENSORS (auv_sensors_t) and
    /// COOPNAV_AUV{K}_RANGE (owtt_range_t), publishes COOPNAV_AUV{K}_ESTIMATE (auv_estimate_t)
    /// after each update. Stops on SIGINT/SIGTERM, --duration or --until-idle.
    Auv(AuvArgs),
    /// The CNA's planner: the policy the scenario (no file: the embedded default) configures,
    /// run by the simulator's own code. Subscribes to COOPNAV_CNA_FIX (cna_fix_t) and
    /// COOPNAV_CNA_STATUS (status_frame_t), with --clock bus also COOPNAV_CLOCK (clock_t); every
    /// tau publishes COOPNAV_CNA_COMMAND (cna_command_t) and COOPNAV_CNA_DECISION (decision_t).
    /// Stops on SIGINT/SIGTERM, --duration, --until-idle or, on the bus clock, a stopped clock.
    Cna(CnaArgs),
    /// The live processes' LCM logs as a run directory that `coopnav view` and `coopnav hbl
    /// postprocess` read: run.alog (the CNA's fixes, commands and decisions, the statuses it
    /// received, each AUV's estimates and ranges), replay.html, auvK.log and auvK.post.toml per
    /// survey AUV, and import.json (what was read and left out).
    Import(ImportArgs),
}

#[derive(clap::Args)]
pub struct CnaArgs {
    /// Scenario file (TOML): the schedule, the fleet and the policy's configuration. Omit it for
    /// the embedded default mission.
    scenario: Option<PathBuf>,
    /// CNA policy (the names `coopnav simulate --policy` takes).
    #[arg(long, default_value = "planner-estimator")]
    policy: String,
    /// LCM URL (UDP multicast).
    #[arg(long, default_value = "udpm://239.255.76.67:7667?ttl=0")]
    url: String,
    /// Where time comes from: `system` (the machine's clock) or `bus` (the world's clock_t).
    #[arg(long, default_value = "system", value_parser = ["system", "bus"])]
    clock: String,
    /// The mission's time zero, microseconds on the synchronous clock (decision m is at
    /// epoch + m * tau).
    #[arg(long, default_value_t = 0)]
    epoch_utime: i64,
    /// Write what was received and published to this LCM log (lcm-logger's format).
    #[arg(long)]
    log: Option<PathBuf>,
    /// Stop after this many seconds.
    #[arg(long)]
    duration: Option<f64>,
    /// Stop after this many seconds without a message on the CNA's channels.
    #[arg(long)]
    until_idle: Option<f64>,
}

#[derive(clap::Args)]
pub struct AuvArgs {
    /// This AUV's id K (the channel names' and the messages' `auv`).
    #[arg(long)]
    auv: i16,
    /// LCM URL (UDP multicast).
    #[arg(long, default_value = "udpm://239.255.76.67:7667?ttl=0")]
    url: String,
    /// Navigator config (TOML): `[filter]` post-processing's filter config, `[start]` e, n (m),
    /// `reorder_window_s` (default 2 s). Omit it for the defaults.
    config: Option<PathBuf>,
    /// Write what was received and published to this LCM log (lcm-logger's format).
    #[arg(long)]
    log: Option<PathBuf>,
    /// Stop after this many seconds.
    #[arg(long)]
    duration: Option<f64>,
    /// Stop after this many seconds without a message on the AUV's channels.
    #[arg(long)]
    until_idle: Option<f64>,
}

fn seconds(name: &str, v: Option<f64>) -> Result<Option<Duration>> {
    match v {
        None => Ok(None),
        Some(s) if s.is_finite() && s > 0.0 && s < 1e9 => Ok(Some(Duration::from_secs_f64(s))),
        Some(s) => bail!("--{name} {s}: give a positive number of seconds"),
    }
}

pub fn run(cmd: Command) -> Result<()> {
    match cmd {
        Command::Auv(args) => auv(args),
        Command::Cna(args) => cna(args),
        Command::Import(args) => import(args),
    }
}

/// SIGINT and SIGTERM set the returned flag.
fn stop_flag() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))?;
    Ok(stop)
}

fn cna(args: CnaArgs) -> Result<()> {
    let scenario: Scenario = match &args.scenario {
        Some(path) => Scenario::parse(&read_scenario_text(path, false)?, path)?,
        None => Scenario::parse(EXAMPLE, &PathBuf::from("<embedded default>"))?,
    };
    let clock = if args.clock == "bus" { ClockSource::Bus } else { ClockSource::System };
    let opts = RunOptions {
        announce: true,
        url: args.url,
        log: args.log,
        duration: seconds("duration", args.duration)?,
        until_idle: seconds("until-idle", args.until_idle)?,
        stop: stop_flag()?,
    };
    let planner = CnaPlanner::new(&scenario, &args.policy, args.epoch_utime)?;
    let summary = run_cna(planner, &opts, clock)?;
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

fn auv(args: AuvArgs) -> Result<()> {
    let cfg = match &args.config {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            LiveConfig::from_toml(&text).with_context(|| format!("config {}", path.display()))?
        }
        None => LiveConfig::default(),
    };
    let opts = RunOptions {
        announce: true,
        url: args.url,
        log: args.log,
        duration: seconds("duration", args.duration)?,
        until_idle: seconds("until-idle", args.until_idle)?,
        stop: stop_flag()?,
    };
    let nav = AuvNavigator::new(args.auv, cfg)?;
    let summary = run_auv(nav, &opts)?;
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

#[derive(clap::Args)]
pub struct ImportArgs {
    /// The live processes' LCM logs (lcm-logger's format), in any order: `live cna --log`
    /// (cna.lcm) and each `live auv --log` (auvK.lcm). AUV K's navigator config is the file
    /// beside its log with the log's name and `.toml` (auvK.toml, as `sitl` writes it); without
    /// one, the default `live auv` runs with.
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// The simulated world's truth: the `timeseries.csv` of the `sitl` run that wrote the logs.
    /// A real vehicle has none: without it the run has no truth, and says so.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Output directory: run.alog, replay.html, auvK.log, auvK.post.toml, import.json.
    #[arg(short, long)]
    output: PathBuf,
    /// Replace the output directory if it exists.
    #[arg(long)]
    force: bool,
}

fn import(args: ImportArgs) -> Result<()> {
    let inputs: Vec<&Path> = args.logs.iter().map(PathBuf::as_path).chain(args.truth.as_deref()).collect();
    let dir = RunDir::create_for(&args.output, args.force, &inputs)?;
    let mut record = LiveRecord::default();
    let mut logs = Vec::new();
    // The first log holding each AUV's sensors: its navigator's config is beside it.
    let mut first_log: BTreeMap<i16, &Path> = BTreeMap::new();
    for path in &args.logs {
        let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
        let before = record.counts.events;
        record.read(BufReader::new(file), &path.display().to_string())?;
        for (&k, a) in &record.auvs {
            if !a.sensors.is_empty() || !a.ranges.is_empty() {
                first_log.entry(k).or_insert(path);
            }
        }
        logs.push(json!({ "file": path, "events": record.counts.events - before }));
    }
    let truth = match &args.truth {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            Some(truth_from_timeseries(&text, &path.display().to_string())?)
        }
        None => None,
    };
    let names: Vec<String> = args
        .logs
        .iter()
        .map(|p| p.file_name().map_or(p.display().to_string(), |n| n.to_string_lossy().into_owned()))
        .collect();
    let imported = run_alog(&record, truth.as_ref(), &names.join(", "));
    let alog = write_run_alog_with(&imported.run, &imported.postings, ALOG_FILE, imported.log_start, Vec::new())?;
    let html = replay::from_alog_bytes(&alog).context("building the replay page")?;
    dir.write_bytes(ALOG_FILE, &alog)?;
    dir.write_text(replay::FILE, &html)?;
    let mut auvs = serde_json::Map::new();
    for (&k, log) in &first_log {
        let beside = log.with_extension("toml");
        let (cfg, config) = if beside.is_file() {
            let text = std::fs::read_to_string(&beside).with_context(|| format!("cannot read {}", beside.display()))?;
            let cfg = LiveConfig::from_toml(&text).with_context(|| format!("config {}", beside.display()))?;
            (cfg, beside.display().to_string())
        } else {
            (LiveConfig::default(), "the default (no config beside the log)".to_string())
        };
        let track: Vec<(f64, f64, f64)> = truth
            .as_ref()
            .and_then(|t| t.get(&k))
            .map(|rows| rows.iter().map(|&(t, x, y, _)| (t, x, y)).collect())
            .unwrap_or_default();
        // Every log, in the order given: the rows of AUV K are read from whichever holds them.
        let mut all: Box<dyn Read> = Box::new(std::io::empty());
        for path in &args.logs {
            let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
            all = Box::new(all.chain(BufReader::new(file)));
        }
        let rows = field_log(all, k, cfg.start, &track)?;
        dir.write_text(&format!("auv{k}.log"), &rows.log)?;
        dir.write_text(&format!("auv{k}.post.toml"), &toml::to_string(&cfg.post_equivalent())?)?;
        auvs.insert(
            format!("auv{k}"),
            json!({ "config": config, "sensors": rows.sensors, "ranges": rows.ranges, "estimates": rows.estimates.len(), "left_out": rows.left_out }),
        );
    }
    let truth_said = match &args.truth {
        Some(path) => json!(path),
        None => json!("none: the logs are a vehicle's, which has no truth"),
    };
    let summary = json!({
        "logs": logs,
        "truth": truth_said,
        "counts": record.counts,
        "cna": { "fixes": record.fixes.len(), "statuses": record.statuses.len(), "commands": record.commands.len(), "decisions": record.decisions.len() },
        "auvs": auvs,
        "pulses_without_track": imported.pulses_without_track,
        "legs_without_track": imported.legs_without_track,
        "log_start": imported.log_start,
    });
    dir.write_json("import.json", &summary)?;
    dir.write_json(
        "manifest.json",
        &Manifest::new("live import", None, json!({ "logs": args.logs, "truth": args.truth })),
    )?;
    let out = dir.finish()?;
    println!(
        "live import · {} events from {} logs · CNA {} decisions · {} survey AUVs{} -> {}",
        record.counts.events,
        args.logs.len(),
        record.decisions.len(),
        first_log.len(),
        if truth.is_some() { " · with truth" } else { " · no truth" },
        out.display()
    );
    Ok(())
}
