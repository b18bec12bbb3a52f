//! Where a command writes: the directory `-o/--output` names (created or, with `--force`,
//! replaced under [`RunDir::create_for`]'s rules), else a fresh `runs/<name>` beside the others.

use anyhow::Result;
use coopnav_sim::output::RunDir;
use std::path::Path;

/// The run directory of a command: `out` when given (never one of `inputs`), else a fresh
/// `runs/FRESH` (`runs/FRESH-2`, … when taken).
pub fn given_or_fresh(out: Option<&Path>, force: bool, inputs: &[&Path], fresh: &str) -> Result<RunDir> {
    Ok(match out {
        Some(p) => RunDir::create_for(p, force, inputs)?,
        None => RunDir::create_fresh("runs", fresh)?,
    })
}
