//! Running shards. A shard's results go to `results/shard-NNN.journal` run by run as they finish
//! (so a killed run loses only the runs in flight), and once every run is in, to
//! `results/shard-NNN.cbor`, written whole with the project's staged-and-renamed
//! [`write_file`], in run-id order: the same bytes whatever the thread count, the order runs
//! finished in, or how many processes the shards were split over.
//!
//! Both files are the [`MAGIC`] line, then frames (a little-endian u32 length, then CBOR, which
//! keeps every f64 bit for bit): a [`Header`], then one [`Record`] per run. A journal whose last
//! frame is torn (a process killed mid-write) is cut back to its last whole frame and the rest of
//! the shard is run again; a finished shard is skipped. The journal is held under an exclusive
//! `flock` while its shard runs, so a second process refuses it and `sweep status` can tell a
//! running shard from an interrupted one.
//!
//! A run that fails (its policy cannot be built, or the engine panics) is recorded with its
//! error; the merge reports it.

use crate::error::{io, SweepError};
use crate::plan::{Plan, VERSION};
use coopnav_core::run_seed;
use coopnav_sim::engine::Faults;
use coopnav_sim::observe::metrics::{run, RunResult};
use coopnav_sim::output::write_file;
use coopnav_sim::policy::PolicySpec;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The first line of every shard results file.
pub const MAGIC: &[u8] = b"coopnav sweep shard results\n";

/// What a results file is for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub version: String,
    pub digest: String,
    pub shard: usize,
}

/// One run's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Outcome {
    Done(Box<RunResult>),
    Failed(String),
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Record {
    pub id: usize,
    pub outcome: Outcome,
}

/// A results file read back: its header, its records and how many leading bytes were whole.
pub struct Frames {
    pub header: Option<Header>,
    pub records: Vec<Record>,
    pub whole: u64,
}

/// The folder of the results, and the journal and finished file of shard `s`.
pub fn results_dir(plan: &Plan) -> PathBuf {
    plan.dir.join("results")
}

fn stem(plan: &Plan, s: usize) -> String {
    let w = plan.inputs.shards.saturating_sub(1).to_string().len().max(3);
    format!("shard-{s:0w$}")
}

pub fn journal_path(plan: &Plan, s: usize) -> PathBuf {
    results_dir(plan).join(format!("{}.journal", stem(plan, s)))
}

pub fn finished_path(plan: &Plan, s: usize) -> PathBuf {
    results_dir(plan).join(format!("{}.cbor", stem(plan, s)))
}

fn frame<T: Serialize>(value: &T) -> Vec<u8> {
    let mut body = Vec::new();
    ciborium::into_writer(value, &mut body).expect("CBOR encoding into memory does not fail");
    let mut out = (body.len() as u32).to_le_bytes().to_vec();
    out.extend(body);
    out
}

/// Reads the frames of `bytes`, stopping at the first torn or unreadable one.
pub fn read_frames(bytes: &[u8]) -> Frames {
    let mut out = Frames { header: None, records: Vec::new(), whole: 0 };
    let Some(mut rest) = bytes.strip_prefix(MAGIC) else { return out };
    let mut at = MAGIC.len();
    while rest.len() >= 4 {
        let len = u32::from_le_bytes(rest[..4].try_into().expect("4 bytes")) as usize;
        let Some(body) = rest.get(4..4 + len) else { break };
        if out.header.is_none() {
            match ciborium::from_reader::<Header, _>(body) {
                Ok(h) => out.header = Some(h),
                Err(_) => break,
            }
        } else {
            match ciborium::from_reader::<Record, _>(body) {
                Ok(r) => out.records.push(r),
                Err(_) => break,
            }
        }
        at += 4 + len;
        out.whole = at as u64;
        rest = &rest[4 + len..];
    }
    out
}

/// A shard's finished results file: the records of its every run, in id order.
pub fn finished_bytes(header: &Header, records: &[Record]) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend(frame(header));
    for r in records {
        out.extend(frame(r));
    }
    out
}

/// `write_file`'s test that an existing file is a shard results file coopnav wrote.
fn is_results(head: &[u8]) -> bool {
    head.starts_with(MAGIC)
}

/// Reads shard `s`'s finished results, if it has them, checked against the plan.
pub fn read_finished(plan: &Plan, s: usize) -> Result<Option<Vec<Record>>, SweepError> {
    let path = finished_path(plan, s);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io(&path)(e)),
    };
    let frames = read_frames(&bytes);
    check_header(plan, s, &path, frames.header.as_ref())?;
    if frames.whole != bytes.len() as u64 {
        return Err(SweepError::Corrupt { path, message: format!("unreadable after byte {}", frames.whole) });
    }
    let expected = plan.shard_runs(s)?;
    if frames.records.iter().map(|r| r.id).ne(expected.iter().copied()) {
        return Err(SweepError::Corrupt { path, message: format!("does not hold exactly the runs of shard {s}") });
    }
    Ok(Some(frames.records))
}

fn check_header(plan: &Plan, s: usize, path: &Path, header: Option<&Header>) -> Result<(), SweepError> {
    let Some(h) = header else {
        return Err(SweepError::Corrupt { path: path.to_path_buf(), message: "no shard results header".into() });
    };
    if h.digest != plan.inputs.digest || h.version != VERSION {
        let found = format!("{} of coopnav {}", h.digest, h.version);
        return Err(SweepError::OtherPlan { path: path.to_path_buf(), found, ours: plan.inputs.digest.clone() });
    }
    if h.shard != s {
        return Err(SweepError::Corrupt {
            path: path.to_path_buf(),
            message: format!("holds shard {}, not {s}", h.shard),
        });
    }
    Ok(())
}

/// Tries to take the journal's exclusive lock without waiting: false when another process holds it.
pub fn try_lock(file: &File) -> std::io::Result<bool> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock on a file descriptor this process owns for the call's duration.
    let r = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if r == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
        Ok(false)
    } else {
        Err(e)
    }
}

/// A shard being run: its journal (locked), what it held, and its runs still to do.
struct Open {
    shard: usize,
    journal: Mutex<File>,
    done: Vec<Record>,
    pending: Vec<usize>,
}

/// Opens shard `s`'s journal for running: None when the shard is finished already.
fn open_shard(plan: &Plan, s: usize) -> Result<Option<Open>, SweepError> {
    let runs = plan.shard_runs(s)?;
    if read_finished(plan, s)?.is_some() {
        return Ok(None);
    }
    let dir = results_dir(plan);
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    let path = journal_path(plan, s);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(io(&path))?;
    if !try_lock(&file).map_err(io(&path))? {
        return Err(SweepError::Busy { dir: plan.dir.clone(), shard: s });
    }
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes).map_err(io(&path))?;
    let frames = read_frames(&bytes);
    let header = Header { version: VERSION.into(), digest: plan.inputs.digest.clone(), shard: s };
    let mut done = Vec::new();
    if frames.header.is_some() {
        check_header(plan, s, &path, frames.header.as_ref())?;
        done = frames.records;
        file.set_len(frames.whole).map_err(io(&path))?;
    } else {
        // Empty, or torn before its header was whole: begun again.
        file.set_len(0).map_err(io(&path))?;
        let mut start = MAGIC.to_vec();
        start.extend(frame(&header));
        file.seek(std::io::SeekFrom::Start(0)).map_err(io(&path))?;
        file.write_all(&start).map_err(io(&path))?;
    }
    file.seek(std::io::SeekFrom::End(0)).map_err(io(&path))?;
    let mut seen = std::collections::BTreeSet::new();
    done.retain(|r| runs.binary_search(&r.id).is_ok() && seen.insert(r.id));
    let pending = runs.into_iter().filter(|id| !seen.contains(id)).collect();
    Ok(Some(Open { shard: s, journal: Mutex::new(file), done, pending }))
}

/// Runs one run of the plan, catching a panic as a failure.
fn run_one(plan: &Plan, specs: &BTreeMap<usize, Vec<PolicySpec>>, id: usize) -> Outcome {
    let at = plan.locate(id);
    let sc = &plan.cells[at.cell].scenario;
    let attempt = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut policy = specs[&at.cell][at.policy].build(sc).map_err(|e| e.to_string())?;
        Ok::<_, String>(run(sc, &mut policy, run_seed(sc.seed, at.run as u64), &Faults::default(), &mut ()))
    }));
    match attempt {
        Ok(Ok(r)) => Outcome::Done(Box::new(r)),
        Ok(Err(e)) => Outcome::Failed(e),
        Err(panic) => Outcome::Failed(format!(
            "the run panicked: {}",
            panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}

/// What `run_shards` did to one shard.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShardRun {
    pub shard: usize,
    /// Runs already finished before (journaled or the whole shard), and run now.
    pub skipped: usize,
    pub ran: usize,
    pub failed: usize,
}

/// Runs shards `shards` of `plan` in one rayon pool; `progress(done)` after every run (out of
/// [`pending_runs`]).
pub fn run_shards(plan: &Plan, shards: &[usize], progress: &(dyn Fn(u64) + Sync)) -> Result<Vec<ShardRun>, SweepError> {
    let mut open = Vec::new();
    let mut reports = Vec::new();
    for &s in shards {
        match open_shard(plan, s)? {
            Some(o) => open.push(o),
            None => reports.push(ShardRun { shard: s, skipped: plan.shard_runs(s)?.len(), ran: 0, failed: 0 }),
        }
    }
    let cells: std::collections::BTreeSet<usize> =
        open.iter().flat_map(|o| o.pending.iter().map(|&id| plan.locate(id).cell)).collect();
    let mut specs = BTreeMap::new();
    for c in cells {
        let sc = &plan.cells[c].scenario;
        let built = plan.inputs.policies.iter().map(|p| PolicySpec::new(p, sc)).collect::<Result<Vec<_>, _>>();
        // The plan checked every policy of every cell; one failing now is the run's failure.
        specs.insert(c, built.unwrap_or_default());
    }
    let jobs: Vec<(usize, usize)> =
        open.iter().enumerate().flat_map(|(k, o)| o.pending.iter().map(move |&id| (k, id))).collect();
    let counter = std::sync::atomic::AtomicU64::new(0);
    let fresh: Vec<(usize, Record)> = jobs
        .par_iter()
        .map(|&(k, id)| {
            let outcome = if specs[&plan.locate(id).cell].is_empty() {
                Outcome::Failed("its policies could not be built".into())
            } else {
                run_one(plan, &specs, id)
            };
            let record = Record { id, outcome };
            let bytes = frame(&record);
            let path = journal_path(plan, open[k].shard);
            open[k].journal.lock().unwrap_or_else(|p| p.into_inner()).write_all(&bytes).map_err(io(&path))?;
            progress(counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            Ok((k, record))
        })
        .collect::<Result<_, SweepError>>()?;
    let mut new_by_shard: Vec<Vec<Record>> = vec![Vec::new(); open.len()];
    for (k, r) in fresh {
        new_by_shard[k].push(r);
    }
    for (o, new) in open.into_iter().zip(new_by_shard) {
        let (skipped, ran) = (o.done.len(), new.len());
        let mut all: Vec<Record> = o.done.into_iter().chain(new).collect();
        all.sort_by_key(|r| r.id);
        let failed = all.iter().filter(|r| matches!(r.outcome, Outcome::Failed(_))).count();
        let header = Header { version: VERSION.into(), digest: plan.inputs.digest.clone(), shard: o.shard };
        let target = finished_path(plan, o.shard);
        write_file(&target, &finished_bytes(&header, &all), false, is_results, &[])?;
        let journal = journal_path(plan, o.shard);
        std::fs::remove_file(&journal).map_err(io(&journal))?;
        reports.push(ShardRun { shard: o.shard, skipped, ran, failed });
    }
    reports.sort_by_key(|r| r.shard);
    Ok(reports)
}

/// How many runs of `shards` are still to run (for a progress bar's length).
pub fn pending_runs(plan: &Plan, shards: &[usize]) -> Result<u64, SweepError> {
    let mut n = 0;
    for &s in shards {
        if read_finished(plan, s)?.is_some() {
            continue;
        }
        let journaled = std::fs::read(journal_path(plan, s)).map(|b| read_frames(&b).records.len()).unwrap_or(0);
        n += plan.shard_runs(s)?.len().saturating_sub(journaled) as u64;
    }
    Ok(n)
}
