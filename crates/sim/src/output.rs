//! Run directories: every command that produces results writes one directory holding
//! `manifest.json` (inputs, seed, version), CSV time series, `summary.json` and SVG plots.
//!
//! Writing goes to a hidden staging directory beside the target that is renamed into place by
//! [`RunDir::finish`], so a run that fails half-way leaves nothing behind, and an existing
//! directory is replaced only when the caller says `force`.

use crate::plot::PlotError;
use serde::Serialize;
use std::fs;
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("output directory {0} already exists; choose another with -o or pass --force to replace it")]
    Exists(PathBuf),
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("cannot write CSV {path}: {source}")]
    Csv { path: PathBuf, source: csv::Error },
    #[error("cannot serialise {path} as JSON: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
}

/// Why a run directory could not be written, whatever the run type.
#[derive(Debug, Error)]
pub enum WriteError {
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Plot(#[from] PlotError),
    #[error("the run was not recorded (no time series to write)")]
    NotRecorded,
    #[error("cannot export the run as a MOOS alog: {0}")]
    Alog(#[from] coopnav_moos::ExportError),
    #[error("cannot build the replay page: {0}")]
    Replay(#[from] coopnav_moos::replay::ReplayError),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io { path: path.to_path_buf(), source }
}

/// What produced a run: written as `manifest.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Manifest {
    pub tool: &'static str,
    pub version: &'static str,
    /// The command, e.g. "plan" or "hbl montecarlo".
    pub command: String,
    pub seed: Option<u64>,
    /// The fully resolved inputs (scenario after defaults), so the run can be repeated.
    pub inputs: serde_json::Value,
}

impl Manifest {
    pub fn new(command: impl Into<String>, seed: Option<u64>, inputs: serde_json::Value) -> Self {
        Manifest { tool: "coopnav", version: env!("CARGO_PKG_VERSION"), command: command.into(), seed, inputs }
    }
}

/// A run directory being written.
#[derive(Debug)]
pub struct RunDir {
    target: PathBuf,
    staging: PathBuf,
    force: bool,
    finished: bool,
}

impl RunDir {
    /// Starts writing a run that will land at `target`. Fails at once if `target` exists and
    /// `force` is false.
    pub fn create(target: impl Into<PathBuf>, force: bool) -> Result<Self, OutputError> {
        let target = target.into();
        if target.exists() && !force {
            return Err(OutputError::Exists(target));
        }
        let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "run".into());
        let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        fs::create_dir_all(parent).map_err(io_err(parent))?;
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(io_err(&staging))?;
        }
        fs::create_dir(&staging).map_err(io_err(&staging))?;
        Ok(RunDir { target, staging, force, finished: false })
    }

    /// Starts a run under `base` with the first free name among `stem`, `stem-2`, `stem-3`, ...
    /// (used for default output locations, so repeating a command never fails or overwrites).
    pub fn create_fresh(base: impl AsRef<Path>, stem: &str) -> Result<Self, OutputError> {
        let base = base.as_ref();
        let target = (1..)
            .map(|k| if k == 1 { base.join(stem) } else { base.join(format!("{stem}-{k}")) })
            .find(|p| !p.exists())
            .expect("an unbounded range always yields a free name");
        Self::create(target, false)
    }

    /// Where the run lands once finished.
    pub fn target(&self) -> &Path {
        &self.target
    }

    fn staged(&self, name: &str) -> PathBuf {
        self.staging.join(name)
    }

    pub fn write_text(&self, name: &str, text: &str) -> Result<(), OutputError> {
        self.write_bytes(name, text)
    }

    pub fn write_bytes(&self, name: &str, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        let path = self.staged(name);
        fs::write(&path, bytes).map_err(io_err(&path))
    }

    pub fn write_json<T: Serialize + ?Sized>(&self, name: &str, value: &T) -> Result<(), OutputError> {
        let path = self.staged(name);
        let text =
            serde_json::to_string_pretty(value).map_err(|source| OutputError::Json { path: path.clone(), source })?;
        fs::write(&path, text + "\n").map_err(io_err(&path))
    }

    /// Writes `rows` as CSV with a header taken from the row type's field names.
    pub fn write_csv<T: Serialize>(&self, name: &str, rows: impl IntoIterator<Item = T>) -> Result<(), OutputError> {
        let path = self.staged(name);
        let csv_err = |source| OutputError::Csv { path: path.clone(), source };
        let mut w = csv::Writer::from_path(&path).map_err(csv_err)?;
        for row in rows {
            w.serialize(row).map_err(csv_err)?;
        }
        w.flush().map_err(io_err(&path))
    }

    /// Moves the finished run into place (replacing an existing target only under `force`).
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        if self.target.exists() {
            if !self.force {
                return Err(OutputError::Exists(self.target.clone()));
            }
            fs::remove_dir_all(&self.target).map_err(io_err(&self.target))?;
        }
        fs::rename(&self.staging, &self.target).map_err(io_err(&self.target))?;
        self.finished = true;
        Ok(self.target.clone())
    }
}

impl Drop for RunDir {
    fn drop(&mut self) {
        if !self.finished {
            // A run that did not finish leaves nothing behind; failure to clean up is not worth
            // masking the original error for.
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Row {
        t: f64,
        err: f64,
    }

    #[test]
    fn run_lands_only_when_finished() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("run");
        {
            let run = RunDir::create(&target, false).unwrap();
            run.write_text("a.txt", "x").unwrap();
        }
        assert!(!target.exists(), "an unfinished run must leave nothing");
        assert_eq!(fs::read_dir(tmp.path()).unwrap().count(), 0);
        let run = RunDir::create(&target, false).unwrap();
        run.write_csv("ts.csv", [Row { t: 0.0, err: 1.5 }]).unwrap();
        run.write_json("summary.json", &serde_json::json!({"k": 1})).unwrap();
        run.finish().unwrap();
        assert_eq!(fs::read_to_string(target.join("ts.csv")).unwrap(), "t,err\n0.0,1.5\n");
    }

    #[test]
    fn existing_target_needs_force() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("run");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("old.txt"), "old").unwrap();
        assert!(matches!(RunDir::create(&target, false), Err(OutputError::Exists(_))));
        let run = RunDir::create(&target, true).unwrap();
        run.write_text("new.txt", "new").unwrap();
        run.finish().unwrap();
        assert!(target.join("new.txt").exists() && !target.join("old.txt").exists());
    }

    #[test]
    fn fresh_names_count_up() {
        let tmp = tempfile::tempdir().unwrap();
        let a = RunDir::create_fresh(tmp.path(), "plan").unwrap().finish().unwrap();
        let b = RunDir::create_fresh(tmp.path(), "plan").unwrap().finish().unwrap();
        assert_eq!(a.file_name().unwrap(), "plan");
        assert_eq!(b.file_name().unwrap(), "plan-2");
    }
}
