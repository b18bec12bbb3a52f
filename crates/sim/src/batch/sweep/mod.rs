//! The sweep file and its expansion into cells: the one description of a study of many
//! closed-loop missions, read by `coopnav sweep` (the `coopnav-sweep` crate plans, shards, runs
//! and merges it) and by the reproductions whose cells are written as a sweep file
//! (`closed-loop-vs-baselines`). [`file`] reads the file; [`expand`] checks it whole and
//! expands it into cells in a documented order (`docs/sweeps.md`).

pub mod expand;
pub mod file;

use std::path::PathBuf;
use thiserror::Error;

/// What can go wrong reading or expanding a sweep file, naming the file.
#[derive(Debug, Error)]
pub enum SweepFileError {
    #[error("cannot read sweep file {file}: {message}")]
    Read { file: PathBuf, message: String },
    #[error("sweep file {file}: {}", problems_text(problems))]
    Invalid { file: PathBuf, problems: Vec<String> },
    #[error(transparent)]
    TooLarge(#[from] coopnav_core::limits::TooLarge),
}

fn problems_text(problems: &[String]) -> String {
    match problems {
        [one] => one.clone(),
        many => format!("{} problems:{}", many.len(), many.iter().map(|p| format!("\n  {p}")).collect::<String>()),
    }
}
