//! Run directories: every command that produces results writes one directory holding
//! `manifest.json` (inputs, seed, version), CSV time series, `summary.json` and SVG plots.
//!
//! Writing goes to a hidden staging directory beside the target that is moved into place by
//! [`RunDir::finish`], so a run that fails half-way, or is interrupted (the binary calls
//! [`remove_unfinished_runs`] from its Ctrl-C / SIGTERM handler), leaves nothing behind.
//!
//! Replacing an existing directory (`force`) is the one place coopnav deletes files, so it is
//! guarded by [`check_replaceable`]: only a directory coopnav itself wrote (it holds a coopnav
//! `manifest.json`) or an empty one may be replaced, and never the filesystem root, the home
//! directory, the working directory or any directory that contains it. The new run and the old
//! directory are exchanged in one atomic rename, so the target is at every instant the old run or
//! the new one, whole; the old one is then deleted.
//!
//! A process killed outright (SIGKILL, a failed allocation) cannot clean up after itself, so every
//! staging directory holds a marker naming its process (pid and start time): the next run writing
//! beside it removes the staging of processes that no longer run, and restores a replaced run
//! that such a process had moved aside.
//!
//! What goes in them: one closed-loop run's ([`run`]), a pre-deployment plan's ([`plan`]), the
//! `coopnav hbl` tools' recorded pass and field log ([`record`], [`log_format`]) and plots
//! ([`hbl_plot`]), the shared SVG plots ([`plot`]), HTML reports ([`report`]) and the MOOS-IvP
//! alog export ([`moos_export`]).

pub mod advise;
pub mod hbl_plot;
pub mod jumps;
pub mod log_format;
pub mod moos_export;
pub mod plan;
pub mod plot;
pub mod record;
pub mod report;
pub mod run;

use plot::PlotError;
use serde::Serialize;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use thiserror::Error;

/// The file that marks a directory as a coopnav run (and so replaceable under `force`).
pub const MANIFEST: &str = "manifest.json";

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("output directory {0} already exists; choose another with -o or pass --force to replace it")]
    Exists(PathBuf),
    #[error("refusing to replace {path} (--force replaces only a run directory coopnav wrote): {reason}")]
    Unsafe { path: PathBuf, reason: UnsafeTarget },
    #[error("output path {0} has no final directory name; name the directory to write")]
    Unnamed(PathBuf),
    #[error("refusing to replace {target}: it holds {input}, an input of this command; write the output elsewhere")]
    InputInside { target: PathBuf, input: PathBuf },
    #[error("output file {0} already exists; choose another name or pass --force to replace it")]
    FileExists(PathBuf),
    #[error("refusing to replace {path} (--force replaces only a file coopnav wrote): {reason}")]
    UnsafeFile { path: PathBuf, reason: &'static str },
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("cannot write CSV {path}: {source}")]
    Csv { path: PathBuf, source: csv::Error },
    #[error("cannot serialise {path} as JSON: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
}

/// Why an existing path may not be replaced.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum UnsafeTarget {
    #[error("it is the filesystem root")]
    Root,
    #[error("it is the home directory")]
    Home,
    #[error("it is the current working directory")]
    WorkingDirectory,
    #[error("it contains the current working directory")]
    AncestorOfWorkingDirectory,
    #[error("it contains the home directory")]
    AncestorOfHome,
    #[error("it is a symbolic link")]
    Symlink,
    #[error("it is not a directory")]
    NotADirectory,
    #[error("it is not empty and holds no coopnav {MANIFEST}, so coopnav did not write it")]
    NotACoopnavRun,
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

/// Checks that the existing `target` may be replaced by a new run, without touching it.
pub fn check_replaceable(target: &Path) -> Result<(), OutputError> {
    let unsafe_target = |reason| OutputError::Unsafe { path: target.to_path_buf(), reason };
    let meta = fs::symlink_metadata(target).map_err(io_err(target))?;
    if meta.file_type().is_symlink() {
        return Err(unsafe_target(UnsafeTarget::Symlink));
    }
    let resolved = fs::canonicalize(target).map_err(io_err(target))?;
    if let Some(reason) = protected_reason(&resolved) {
        return Err(unsafe_target(reason));
    }
    if !meta.is_dir() {
        return Err(unsafe_target(UnsafeTarget::NotADirectory));
    }
    if is_empty_dir(&resolved)? || holds_coopnav_manifest(&resolved) {
        Ok(())
    } else {
        Err(unsafe_target(UnsafeTarget::NotACoopnavRun))
    }
}

/// Why the canonical path `dir` is never replaced, whatever it holds.
fn protected_reason(dir: &Path) -> Option<UnsafeTarget> {
    if dir.parent().is_none() {
        return Some(UnsafeTarget::Root);
    }
    let canonical = |p: PathBuf| fs::canonicalize(p).ok();
    if let Some(cwd) = std::env::current_dir().ok().and_then(canonical) {
        if cwd == dir {
            return Some(UnsafeTarget::WorkingDirectory);
        }
        if cwd.starts_with(dir) {
            return Some(UnsafeTarget::AncestorOfWorkingDirectory);
        }
    }
    if let Some(home) = std::env::var_os("HOME").map(PathBuf::from).and_then(canonical) {
        if home == dir {
            return Some(UnsafeTarget::Home);
        }
        if home.starts_with(dir) {
            return Some(UnsafeTarget::AncestorOfHome);
        }
    }
    None
}

fn is_empty_dir(dir: &Path) -> Result<bool, OutputError> {
    Ok(fs::read_dir(dir).map_err(io_err(dir))?.next().is_none())
}

/// True when `dir/manifest.json` is a JSON object whose `tool` is "coopnav".
fn holds_coopnav_manifest(dir: &Path) -> bool {
    let Ok(text) = fs::read_to_string(dir.join(MANIFEST)) else { return false };
    serde_json::from_str::<serde_json::Value>(&text)
        .map(|v| v.get("tool").and_then(|t| t.as_str()) == Some(TOOL))
        .unwrap_or(false)
}

const TOOL: &str = "coopnav";

/// Staging directories of runs in progress, so an interrupted process can remove them.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A poisoned list is still a list of paths; losing it would leave staging directories behind.
    UNFINISHED.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes the staging directory of every run still in progress. Called from the binary's
/// interrupt handler: afterwards no run of this process can land, as the list stays locked
/// until `finish` (which moves staging into place under the same lock) fails to find its
/// directory.
pub fn remove_unfinished_runs() {
    for staging in unfinished().drain(..) {
        // A run directory's staging, or a single file's (`write_file`).
        let _ = fs::remove_dir_all(&staging).or_else(|_| fs::remove_file(&staging));
    }
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
        Manifest { tool: TOOL, version: env!("CARGO_PKG_VERSION"), command: command.into(), seed, inputs }
    }
}

/// A run directory being written.
#[derive(Debug)]
pub struct RunDir {
    /// Where the run lands, as the user named it (for messages).
    target: PathBuf,
    /// The same place with its parent resolved, for the file operations.
    resolved: PathBuf,
    staging: PathBuf,
    force: bool,
    finished: bool,
}

impl RunDir {
    /// Starts writing a run that will land at `target`. Fails at once, before any work, if
    /// `target` exists and is not an empty directory, unless `force` is set and
    /// [`check_replaceable`] allows replacing it.
    pub fn create(target: impl Into<PathBuf>, force: bool) -> Result<Self, OutputError> {
        Self::create_for(target, force, &[])
    }

    /// [`RunDir::create`] for a command that reads `inputs`: an existing `target` that holds any
    /// of them is never replaced (replacing it would delete the command's own input).
    pub fn create_for(target: impl Into<PathBuf>, force: bool, inputs: &[&Path]) -> Result<Self, OutputError> {
        let target = target.into();
        check_target(&target, force)?;
        check_inputs_outside(&target, inputs)?;
        let name = target
            .file_name()
            .filter(|n| !matches!(Path::new(n).components().next(), Some(std::path::Component::ParentDir)))
            .ok_or_else(|| OutputError::Unnamed(target.clone()))?
            .to_owned();
        let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        fs::create_dir_all(parent).map_err(io_err(parent))?;
        let parent = fs::canonicalize(parent).map_err(io_err(parent))?;
        let resolved = parent.join(&name);
        let staging = parent.join(format!(".{}.partial-{}", name.to_string_lossy(), std::process::id()));
        let mut live = unfinished();
        recover_abandoned(&parent, &name.to_string_lossy());
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(io_err(&staging))?;
        }
        fs::create_dir(&staging).map_err(io_err(&staging))?;
        live.push(staging.clone());
        fs::write(staging.join(STAGING_MARKER), Owner::this_process().to_string()).map_err(io_err(&staging))?;
        Ok(RunDir { target, resolved, staging, force, finished: false })
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

    /// Where file `name` (a path inside the run, `cells/cell-0.toml`) is staged; its folders are
    /// made on the way.
    fn staged(&self, name: &str) -> Result<PathBuf, OutputError> {
        let path = self.staging.join(name);
        if let Some(parent) = path.parent().filter(|p| *p != self.staging) {
            fs::create_dir_all(parent).map_err(io_err(parent))?;
        }
        Ok(path)
    }

    pub fn write_text(&self, name: &str, text: &str) -> Result<(), OutputError> {
        self.write_bytes(name, text)
    }

    pub fn write_bytes(&self, name: &str, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        let path = self.staged(name)?;
        fs::write(&path, bytes).map_err(io_err(&path))
    }

    pub fn write_json<T: Serialize + ?Sized>(&self, name: &str, value: &T) -> Result<(), OutputError> {
        let path = self.staged(name)?;
        let text =
            serde_json::to_string_pretty(value).map_err(|source| OutputError::Json { path: path.clone(), source })?;
        fs::write(&path, text + "\n").map_err(io_err(&path))
    }

    /// Writes `rows` as CSV with a header taken from the row type's field names.
    pub fn write_csv<T: Serialize>(&self, name: &str, rows: impl IntoIterator<Item = T>) -> Result<(), OutputError> {
        let path = self.staged(name)?;
        let csv_err = |source| OutputError::Csv { path: path.clone(), source };
        let mut w = csv::Writer::from_path(&path).map_err(csv_err)?;
        for row in rows {
            w.serialize(row).map_err(csv_err)?;
        }
        w.flush().map_err(io_err(&path))
    }

    /// Moves the finished run into place. An existing target (checked again: it may have changed
    /// while the run was computed) is moved aside first and deleted only once the new run is in
    /// place, so a failure leaves the old run intact.
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        check_target(&self.target, self.force)?;
        let mut live = unfinished();
        let Some(index) = live.iter().position(|p| *p == self.staging) else {
            return Err(OutputError::Io {
                path: self.staging.clone(),
                source: std::io::Error::new(std::io::ErrorKind::Interrupted, "the run was interrupted"),
            });
        };
        // From here the staging directory is the run: the marker goes, so that a kill after the
        // exchange leaves no marker inside the landed run.
        fs::remove_file(self.staging.join(STAGING_MARKER)).map_err(io_err(&self.staging))?;
        let replaced = match exchange(&self.staging, &self.resolved) {
            Ok(()) => true,
            Err(e) if e.raw_os_error() == Some(libc::ENOENT) => {
                // Nothing to replace (or it vanished meanwhile): a plain rename, which refuses
                // to clobber a directory another process landed in the meantime.
                fs::rename(&self.staging, &self.resolved).map_err(io_err(&self.target))?;
                false
            }
            Err(e) if matches!(e.raw_os_error(), Some(libc::EINVAL | libc::ENOSYS | libc::EOPNOTSUPP)) => {
                // A filesystem without the exchange: the old run is moved aside first (a kill
                // between the two renames is repaired by the next run, `recover_abandoned`).
                let aside = self.resolved.with_file_name(format!(
                    ".{}.replaced-{}",
                    self.resolved.file_name().unwrap_or_default().to_string_lossy(),
                    std::process::id()
                ));
                fs::rename(&self.resolved, &aside).map_err(io_err(&self.target))?;
                if let Err(e) = fs::rename(&self.staging, &self.resolved) {
                    let _ = fs::rename(&aside, &self.resolved);
                    return Err(io_err(&self.target)(e));
                }
                fs::rename(&aside, &self.staging).map_err(io_err(&aside))?;
                true
            }
            Err(e) => return Err(io_err(&self.target)(e)),
        };
        live.swap_remove(index);
        self.finished = true;
        drop(live);
        if replaced {
            // The old run, now at the staging path: named for this live process until deleted.
            remove_run(&self.staging).map_err(io_err(&self.staging))?;
        }
        Ok(self.target.clone())
    }
}

/// Deletes a run directory with its manifest last, so that a kill half-way leaves a directory
/// that [`recover_abandoned`] still recognises as coopnav's.
fn remove_run(dir: &Path) -> std::io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let entry = entry?;
        if entry.file_name() == MANIFEST {
            continue;
        }
        if entry.file_type()?.is_dir() {
            fs::remove_dir_all(entry.path())?;
        } else {
            fs::remove_file(entry.path())?;
        }
    }
    let _ = fs::remove_file(dir.join(MANIFEST));
    fs::remove_dir(dir)
}

/// The marker file inside a staging directory: the process that writes it.
const STAGING_MARKER: &str = ".coopnav-staging";

/// A process, told apart from a later one that reuses its pid by its start time (clock ticks
/// after boot, `/proc/PID/stat` field 22).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Owner {
    pid: u32,
    start: u64,
}

impl Owner {
    fn this_process() -> Self {
        let pid = std::process::id();
        Owner { pid, start: start_time(pid).unwrap_or(0) }
    }

    fn parse(text: &str) -> Option<Self> {
        let (pid, start) = text.trim().split_once(' ')?;
        Some(Owner { pid: pid.parse().ok()?, start: start.parse().ok()? })
    }

    /// Whether this process still runs (the same pid with the same start time).
    fn alive(&self) -> bool {
        start_time(self.pid) == Some(self.start)
    }
}

impl std::fmt::Display for Owner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.pid, self.start)
    }
}

/// A process's start time, or None when no such process runs.
fn start_time(pid: u32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces) start at field 3.
    let after = stat.rsplit_once(')')?.1;
    after.split_whitespace().nth(19)?.parse().ok()
}

/// Exchanges two paths in one step (renameat2 RENAME_EXCHANGE): both must exist.
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| std::ffi::CString::new(p.as_os_str().as_bytes()).map_err(std::io::Error::other);
    let (a, b) = (c(a)?, c(b)?);
    // SAFETY: two valid NUL-terminated paths, relative to the working directory.
    let r = unsafe { libc::renameat2(libc::AT_FDCWD, a.as_ptr(), libc::AT_FDCWD, b.as_ptr(), libc::RENAME_EXCHANGE) };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// Removes, beside `name` in `parent`, what coopnav processes that no longer run left behind:
/// their staging directories (recognised by the marker inside, or, once exchanged, by the old
/// run's coopnav manifest) and staged single files that coopnav wrote. Failures are ignored: this
/// is housekeeping, and the run itself reports what matters.
fn recover_abandoned(parent: &Path, name: &str) {
    let Ok(entries) = fs::read_dir(parent) else { return };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file_name.strip_prefix(&prefix) else { continue };
        let Some(pid) = ["partial-", "replaced-"].iter().find_map(|k| rest.strip_prefix(k)) else { continue };
        let Ok(pid) = pid.parse::<u32>() else { continue };
        let path = entry.path();
        let Ok(meta) = fs::symlink_metadata(&path) else { continue };
        if meta.is_dir() {
            let owner = fs::read_to_string(path.join(STAGING_MARKER)).ok().and_then(|t| Owner::parse(&t));
            if owner.is_none() && start_time(pid).is_none() && fs::remove_dir(&path).is_ok() {
                // An empty staging directory (killed before its marker was written).
                continue;
            }
            let abandoned = match owner {
                Some(o) => o.pid == pid && !o.alive(),
                // An exchanged-out old run keeps no marker: its manifest says coopnav wrote it,
                // and its named process is gone.
                None => holds_coopnav_manifest(&path) && start_time(pid).is_none(),
            };
            if !abandoned {
                continue;
            }
            // A run moved aside by a process killed before its new run landed is the target's
            // last whole state: it goes back.
            let target = parent.join(name);
            if rest.starts_with("replaced-") && fs::symlink_metadata(&target).is_err() {
                let _ = fs::rename(&path, &target);
            } else {
                let _ = remove_run(&path).or_else(|_| fs::remove_dir_all(&path));
            }
        } else if meta.is_file() && start_time(pid).is_none() {
            let head = file_head(&path);
            if head.is_ok_and(|h| String::from_utf8_lossy(&h).contains("<title>coopnav replay")) {
                let _ = fs::remove_file(&path);
            }
        }
    }
}

/// An existing target is reused only when it may be replaced (see [`check_replaceable`]) and
/// is either empty or `force` is set.
fn check_target(target: &Path, force: bool) -> Result<(), OutputError> {
    if fs::symlink_metadata(target).is_err() {
        return Ok(());
    }
    check_replaceable(target)?;
    if force || is_empty_dir(target)? {
        Ok(())
    } else {
        Err(OutputError::Exists(target.to_path_buf()))
    }
}

/// Refuses an existing `target` that contains one of `inputs` (compared as canonical paths, so
/// `run/./s.toml`, `../x/run/s.toml` and links into the directory are caught).
fn check_inputs_outside(target: &Path, inputs: &[&Path]) -> Result<(), OutputError> {
    let Ok(dir) = fs::canonicalize(target) else { return Ok(()) };
    for input in inputs {
        if fs::canonicalize(input).is_ok_and(|p| p.starts_with(&dir)) {
            return Err(OutputError::InputInside { target: target.to_path_buf(), input: input.to_path_buf() });
        }
    }
    Ok(())
}

/// Writes one output file the way a run directory lands: the bytes go to a hidden
/// `.NAME.partial-PID` beside `target` and are renamed over it only once whole (a full disk or an
/// interrupt leaves the old file, or nothing). An existing `target` is replaced only with `force`
/// and only when `ours(existing bytes)` says coopnav wrote it; a symbolic link, a directory or an
/// input of the command (`inputs`) never is.
pub fn write_file(
    target: &Path,
    bytes: &[u8],
    force: bool,
    ours: fn(&[u8]) -> bool,
    inputs: &[&Path],
) -> Result<(), OutputError> {
    check_file_target(target, force, ours, inputs)?;
    let name = target.file_name().ok_or_else(|| OutputError::Unnamed(target.to_path_buf()))?.to_string_lossy();
    let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
    recover_abandoned(parent, &name);
    unfinished().push(staging.clone());
    let written = (|| {
        use std::io::Write;
        let mut f = fs::File::create(&staging)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&staging, target)
    })();
    let mut live = unfinished();
    live.retain(|p| *p != staging);
    if let Err(e) = written {
        let _ = fs::remove_file(&staging);
        return Err(io_err(target)(e));
    }
    Ok(())
}

/// Checks, without touching it, that [`write_file`] may write `target`: absent, or a regular file
/// that is not one of `inputs`, replaced only with `force` and only when `ours(its first bytes)`.
/// A command calls it before its work, so that a refusal costs nothing.
pub fn check_file_target(
    target: &Path,
    force: bool,
    ours: fn(&[u8]) -> bool,
    inputs: &[&Path],
) -> Result<(), OutputError> {
    let Ok(meta) = fs::symlink_metadata(target) else { return Ok(()) };
    let unsafe_file = |reason| OutputError::UnsafeFile { path: target.to_path_buf(), reason };
    if meta.file_type().is_symlink() {
        return Err(unsafe_file("it is a symbolic link"));
    }
    if !meta.is_file() {
        return Err(unsafe_file("it is not a regular file"));
    }
    let canonical = fs::canonicalize(target).map_err(io_err(target))?;
    if inputs.iter().any(|i| fs::canonicalize(i).is_ok_and(|p| p == canonical)) {
        return Err(unsafe_file("it is an input of this command"));
    }
    if !force {
        return Err(OutputError::FileExists(target.to_path_buf()));
    }
    if !ours(&file_head(target).map_err(io_err(target))?) {
        return Err(unsafe_file("coopnav did not write it"));
    }
    Ok(())
}

/// The first [`OWNERSHIP_PREFIX`] bytes of `path`: what tells a file coopnav wrote.
fn file_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut head = Vec::with_capacity(OWNERSHIP_PREFIX);
    fs::File::open(path)?.take(OWNERSHIP_PREFIX as u64).read_to_end(&mut head)?;
    Ok(head)
}

/// How many leading bytes of an existing output file [`write_file`]'s `ours` sees.
pub const OWNERSHIP_PREFIX: usize = 4096;

impl Drop for RunDir {
    fn drop(&mut self) {
        if !self.finished {
            // A run that did not finish leaves nothing behind; failure to clean up is not worth
            // masking the original error for.
            let mut live = unfinished();
            live.retain(|p| *p != self.staging);
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

    fn write_files(dir: &Path, names: &[&str]) {
        fs::create_dir_all(dir).unwrap();
        for name in names {
            fs::write(dir.join(name), "user data").unwrap();
        }
    }

    fn unsafe_reason(result: Result<RunDir, OutputError>) -> UnsafeTarget {
        match result {
            Err(OutputError::Unsafe { reason, .. }) => reason,
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn a_coopnav_run_is_replaced_only_with_force() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("run");
        let first = RunDir::create(&target, false).unwrap();
        first.write_json(MANIFEST, &Manifest::new("test", None, serde_json::json!({}))).unwrap();
        first.write_text("old.txt", "old").unwrap();
        first.finish().unwrap();
        assert!(matches!(RunDir::create(&target, false), Err(OutputError::Exists(_))));
        let run = RunDir::create(&target, true).unwrap();
        run.write_text("new.txt", "new").unwrap();
        run.finish().unwrap();
        assert!(target.join("new.txt").exists() && !target.join("old.txt").exists());
        let leftovers: Vec<_> = fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(leftovers, ["run"], "no staging or set-aside directory may remain");
    }

    #[test]
    fn force_never_replaces_a_directory_coopnav_did_not_write() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("mine");
        write_files(&target, &["thesis.tex", "data.csv"]);
        // A manifest.json that some other tool wrote does not make a directory ours.
        fs::write(target.join(MANIFEST), r#"{"tool": "other"}"#).unwrap();
        for force in [false, true] {
            assert_eq!(unsafe_reason(RunDir::create(&target, force)), UnsafeTarget::NotACoopnavRun);
        }
        let file = tmp.path().join("notes.txt");
        fs::write(&file, "x").unwrap();
        assert_eq!(unsafe_reason(RunDir::create(&file, true)), UnsafeTarget::NotADirectory);
        assert_eq!(fs::read_dir(&target).unwrap().count(), 3);
        assert_eq!(fs::read_to_string(&file).unwrap(), "x");
    }

    #[test]
    fn the_root_and_symlinks_are_refused_before_anything_is_written() {
        assert_eq!(
            match check_replaceable(Path::new("/")) {
                Err(OutputError::Unsafe { reason, .. }) => reason,
                other => panic!("expected a refusal, got {other:?}"),
            },
            UnsafeTarget::Root
        );
        let tmp = tempfile::tempdir().unwrap();
        let real = tmp.path().join("real");
        write_files(&real, &[]);
        let link = tmp.path().join("link");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        assert_eq!(unsafe_reason(RunDir::create(&link, true)), UnsafeTarget::Symlink);
        assert_eq!(fs::read_dir(tmp.path()).unwrap().count(), 2, "no staging directory was made");
    }

    #[test]
    fn an_empty_directory_is_used_without_force() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("empty");
        fs::create_dir(&target).unwrap();
        let run = RunDir::create(&target, false).unwrap();
        run.write_text("a.txt", "a").unwrap();
        run.finish().unwrap();
        assert!(target.join("a.txt").is_file());
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
