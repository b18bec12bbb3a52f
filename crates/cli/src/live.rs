//! `coopnav live auv --auv K`: a survey AUV's OWTT navigator, and `coopnav live cna [FILE]`: the
//! CNA's planner, as live processes on LCM (the loops, the navigator and the planner are
//! coopnav-live's; this only parses arguments, reads the config or scenario, installs the
//! SIGINT/SIGTERM stop and prints the one-line JSON summary on stdout).

use anyhow::{bail, Context, Result};
use coopnav_live::{run_auv, run_cna, AuvNavigator, ClockSource, CnaPlanner, LiveConfig, RunOptions};
use coopnav_sim::scenario::file::read_scenario_text;
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use std::path::PathBuf;
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
    /// Config (TOML): `[filter]` post-processing's filter config, `[start]` e, n (m),
    /// `reorder_window_s` (default 2 s).
    #[arg(long)]
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
