//! `coopnav view RUN_DIR`: (re)writes the interactive `replay.html` of a run directory from its
//! `run.alog` (every `simulate`, `hbl simulate` and `plan` run has one). Nothing is written unless
//! the whole page was built.

use anyhow::{bail, Context, Result};
use coopnav_moos::{read_alog_file, replay};
use coopnav_sim::output::moos_export::ALOG_FILE;
use coopnav_sim::output::write_file;
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
    // Rewriting the page is what `view` is for: a replay coopnav wrote is replaced (through a
    // staged file renamed into place), any other file of that name is refused.
    write_file(&out, html.as_bytes(), true, is_coopnav_replay, &[alog.as_path()])
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}

/// A replay page coopnav wrote: its title starts "coopnav replay".
fn is_coopnav_replay(head: &[u8]) -> bool {
    String::from_utf8_lossy(head).contains("<title>coopnav replay")
}
