//! `coopnav view RUN_DIR`: (re)writes the interactive `replay.html` of a run directory from its
//! `run.alog` (every `simulate`, `hbl simulate` and `plan` run has one). Nothing is written unless
//! the whole page was built.

use anyhow::{bail, Context, Result};
use coopnav_moos::{read_alog_file, replay};
use coopnav_sim::output::moos_export::ALOG_FILE;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A run directory written by `coopnav simulate`, `coopnav hbl simulate` or `coopnav plan`.
    run_dir: PathBuf,
}

pub fn run(args: Args) -> Result<()> {
    let dir = &args.run_dir;
    if !dir.is_dir() {
        bail!("{} is not a directory: give the run directory that simulate, hbl simulate or plan wrote", dir.display());
    }
    let alog = dir.join(ALOG_FILE);
    if !alog.is_file() {
        bail!(
            "{} has no {ALOG_FILE}: only simulate, hbl simulate and plan runs (written by this coopnav version) can be replayed",
            dir.display()
        );
    }
    let log = read_alog_file(&alog)?;
    let html = replay::from_alog(&log).with_context(|| format!("building the replay of {}", alog.display()))?;
    let out = dir.join(replay::FILE);
    std::fs::write(&out, html).with_context(|| format!("cannot write {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}
