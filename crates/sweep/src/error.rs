//! What can go wrong with a sweep, each error naming the file or directory it is about.

use coopnav_sim::batch::sweep::SweepFileError;
use coopnav_sim::output::OutputError;
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SweepError {
    #[error("cannot read sweep file {file}: {message}")]
    Read { file: PathBuf, message: String },
    #[error("sweep file {file}: {}", problems_text(problems))]
    Invalid { file: PathBuf, problems: Vec<String> },
    #[error("{dir} is not a sweep plan ({reason}); write one with `coopnav sweep plan FILE --shards N -o {}`", dir.display())]
    NotAPlan { dir: PathBuf, reason: String },
    #[error("{dir} was planned by coopnav {found}; this is coopnav {ours}: plan the sweep again with this version")]
    OtherVersion { dir: PathBuf, found: String, ours: String },
    #[error("{path}: written for another sweep plan (digest {found}, this plan {ours}); it does not belong in this directory")]
    OtherPlan { path: PathBuf, found: String, ours: String },
    #[error("{path}: {message}")]
    Corrupt { path: PathBuf, message: String },
    #[error("shard {shard} does not exist: the plan in {dir} has shards 0..{shards}")]
    NoShard { dir: PathBuf, shard: usize, shards: usize },
    #[error("shard {shard} of {dir} is being run by another process (its journal is locked)")]
    Busy { dir: PathBuf, shard: usize },
    #[error("{dir}: {} not finished (run them with `coopnav sweep run {} --shard I`, see `coopnav sweep status`)", shard_list(shards), dir.display())]
    Unfinished { dir: PathBuf, shards: Vec<usize> },
    #[error("{dir}: cannot report reproduction {id} from the merged runs: {message}")]
    Report { dir: PathBuf, id: String, message: String },
    #[error("cannot encode {file}: {message}")]
    Encode { file: String, message: String },
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Write(#[from] coopnav_sim::output::WriteError),
    #[error(transparent)]
    TooLarge(#[from] coopnav_core::limits::TooLarge),
}

impl From<SweepFileError> for SweepError {
    fn from(e: SweepFileError) -> Self {
        match e {
            SweepFileError::Read { file, message } => SweepError::Read { file, message },
            SweepFileError::Invalid { file, problems } => SweepError::Invalid { file, problems },
            SweepFileError::TooLarge(t) => SweepError::TooLarge(t),
        }
    }
}

fn problems_text(problems: &[String]) -> String {
    match problems {
        [one] => one.clone(),
        many => format!("{} problems:{}", many.len(), many.iter().map(|p| format!("\n  {p}")).collect::<String>()),
    }
}

fn shard_list(shards: &[usize]) -> String {
    let list = shards.iter().map(usize::to_string).collect::<Vec<_>>().join(", ");
    if shards.len() == 1 {
        format!("shard {list} is")
    } else {
        format!("shards {list} are")
    }
}

/// An I/O error on `path`.
pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Io { path: path.to_path_buf(), source }
}
