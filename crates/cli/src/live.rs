//! `coopnav live auv --auv K`: a survey AUV's OWTT navigator as a live process on LCM (the loop
//! and the navigator are coopnav-live's; this only parses arguments, reads the config, installs
//! the SIGINT/SIGTERM stop and prints the one-line JSON summary on stdout).

use anyhow::{bail, Context, Result};
use coopnav_live::{run_auv, AuvNavigator, LiveConfig, RunOptions};
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
    let Command::Auv(args) = cmd;
    let cfg = match &args.config {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            LiveConfig::from_toml(&text).with_context(|| format!("config {}", path.display()))?
        }
        None => LiveConfig::default(),
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))?;
    let opts = RunOptions {
        announce: true,
        url: args.url,
        log: args.log,
        duration: seconds("duration", args.duration)?,
        until_idle: seconds("until-idle", args.until_idle)?,
        stop,
    };
    let nav = AuvNavigator::new(args.auv, cfg)?;
    let summary = run_auv(nav, &opts)?;
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}
