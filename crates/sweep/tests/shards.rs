//! A sweep planned, run in shards and merged: sharded and one-process runs give the same bytes,
//! a torn journal resumes, foreign and edited plans are refused, failed runs are reported, and a
//! one-cell sweep prints the table `simulate --runs` prints for the same scenario and policies.

use coopnav_sim::batch::mc::{comparison_table, monte_carlo};
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use coopnav_sweep::plan::{plan_file, Plan};
use coopnav_sweep::shard::{self, finished_bytes, journal_path, read_frames, Header, Outcome};
use coopnav_sweep::status::{status, State};
use coopnav_sweep::{merge, SweepError};
use std::path::{Path, PathBuf};

const SWEEP: &str = "scenarios = [\"default\"]\npolicies = [\"zigzag\", \"racetrack\"]\nruns = 3\n\
                     [[axis]]\npath = \"fleet.n_auvs\"\nvalues = [2, 3]\n";

fn plan(dir: &Path, name: &str, text: &str, shards: usize) -> Plan {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let (out, _) = plan_file(&file, text, shards, &dir.join(name), false, false, "test").unwrap();
    Plan::open(&out).unwrap()
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Every file under `dir` but the manifests (which name the command and the directory), with
/// its bytes, by relative path.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().unwrap() != "manifest.json" {
                out.push((p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn shards_run_apart_and_all_at_once_give_the_same_bytes_and_a_torn_journal_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let a = plan(tmp.path(), "a", SWEEP, 3);
    copy_dir(&a.dir, &tmp.path().join("b"));
    let b = Plan::open(&tmp.path().join("b")).unwrap();
    for s in [2, 0, 1] {
        let r = shard::run_shards(&a, &[s], &|_| {}).unwrap();
        assert_eq!((r[0].ran, r[0].skipped, r[0].failed), (4, 0, 0));
    }
    shard::run_shards(&b, &[0, 1, 2], &|_| {}).unwrap();
    // Running a finished shard again does nothing.
    assert_eq!(shard::run_shards(&a, &[1], &|_| {}).unwrap()[0].skipped, 4);
    let (ma, mb) = (merge::merge(&a, None, false, "t").unwrap(), merge::merge(&b, None, false, "t").unwrap());
    let fa = files(&a.dir);
    assert!(fa.len() > 12, "{fa:?}");
    assert_eq!(fa, files(&b.dir), "the sharded and the one-process runs differ");
    assert!(
        ma.table.starts_with("cell 0: default, fleet.n_auvs = 2\nN = 2 survey AUVs, 3 runs per policy"),
        "{}",
        ma.table
    );
    assert_eq!(ma.table, mb.table);

    // A process killed mid-write: the journal holds every run but the last, whose frame is torn.
    let finished = shard::finished_path(&a, 1);
    let whole = std::fs::read(&finished).unwrap();
    let frames = read_frames(&whole);
    assert_eq!(frames.records.len(), 4);
    let header = frames.header.clone().unwrap();
    let mut torn = finished_bytes(&header, &frames.records[..3]);
    let last = finished_bytes(&header, &frames.records[3..]);
    let header_len = finished_bytes(&header, &[]).len();
    torn.extend_from_slice(&last[header_len..header_len + 40]);
    std::fs::remove_file(&finished).unwrap();
    std::fs::write(journal_path(&a, 1), &torn).unwrap();
    assert_eq!(status(&a).unwrap()[1], State::Interrupted { journaled: 3, runs: 4 });
    let r = shard::run_shards(&a, &[1], &|_| {}).unwrap();
    assert_eq!((r[0].ran, r[0].skipped), (1, 3));
    assert_eq!(std::fs::read(&finished).unwrap(), whole, "the resumed shard differs");
    assert!(!journal_path(&a, 1).exists());
}

#[test]
fn a_locked_shard_is_refused_and_shown_running() {
    use std::os::fd::AsRawFd;
    let tmp = tempfile::tempdir().unwrap();
    let a = plan(tmp.path(), "a", SWEEP, 2);
    std::fs::create_dir_all(shard::results_dir(&a)).unwrap();
    let held = std::fs::File::create(journal_path(&a, 0)).unwrap();
    // SAFETY: flock on a descriptor this test owns.
    assert_eq!(unsafe { libc::flock(held.as_raw_fd(), libc::LOCK_EX) }, 0);
    assert!(matches!(shard::run_shards(&a, &[0], &|_| {}), Err(SweepError::Busy { shard: 0, .. })));
    let st = status(&a).unwrap();
    assert_eq!(st, [State::Running { journaled: 0, runs: 6 }, State::Missing { runs: 6 }]);
    drop(held);
    assert_eq!(status(&a).unwrap()[0], State::Interrupted { journaled: 0, runs: 6 });
    let e = merge::merge(&a, None, false, "t").unwrap_err().to_string();
    assert!(e.contains("shards 0, 1 are not finished"), "{e}");
}

#[test]
fn another_version_another_plan_and_an_edited_plan_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let a = plan(tmp.path(), "a", SWEEP, 2);
    let other = plan(tmp.path(), "other", &SWEEP.replace("runs = 3", "runs = 2"), 2);
    shard::run_shards(&other, &[0], &|_| {}).unwrap();
    std::fs::create_dir_all(shard::results_dir(&a)).unwrap();
    std::fs::copy(shard::finished_path(&other, 0), shard::finished_path(&a, 0)).unwrap();
    let e = shard::run_shards(&a, &[0], &|_| {}).unwrap_err();
    assert!(matches!(e, SweepError::OtherPlan { .. }), "{e}");
    std::fs::copy(other.dir.join("shards/shard-001.json"), a.dir.join("shards/shard-001.json")).unwrap();
    assert!(matches!(a.shard_runs(1), Err(SweepError::OtherPlan { .. })));

    let manifest = a.dir.join("manifest.json");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let version = format!("\"version\": \"{}\"", coopnav_sweep::plan::VERSION);
    assert!(text.contains(&version));
    std::fs::write(&manifest, text.replace(&version, "\"version\": \"0.0.1\"")).unwrap();
    let e = Plan::open(&a.dir).unwrap_err().to_string();
    assert!(e.contains("was planned by coopnav 0.0.1; this is coopnav"), "{e}");
    std::fs::write(&manifest, &text).unwrap();
    let cell = a.dir.join("cells/cell-0001.toml");
    let edited = std::fs::read_to_string(&cell).unwrap().replace("duration_s = 3600.0", "duration_s = 1800.0");
    std::fs::write(&cell, edited).unwrap();
    let e = Plan::open(&a.dir).unwrap_err().to_string();
    assert!(e.contains("the plan was changed after it was written"), "{e}");
}

#[test]
fn a_failed_run_is_reported_by_the_merge_and_its_cell_gets_no_comparison() {
    let tmp = tempfile::tempdir().unwrap();
    let a = plan(tmp.path(), "a", SWEEP, 1);
    shard::run_shards(&a, &[0], &|_| {}).unwrap();
    let path = shard::finished_path(&a, 0);
    let frames = read_frames(&std::fs::read(&path).unwrap());
    let mut records = frames.records;
    records[7].outcome = Outcome::Failed("the engine stopped".into());
    let header: Header = frames.header.unwrap();
    std::fs::write(&path, finished_bytes(&header, &records)).unwrap();
    assert_eq!(status(&a).unwrap(), [State::Failed { runs: 12, failed: 1 }]);
    let m = merge::merge(&a, None, false, "t").unwrap();
    assert_eq!(m.failures.len(), 1);
    let f = &m.failures[0];
    // Run 7: cell 1 (n_auvs = 3), policy 0 (zigzag), run 1.
    assert_eq!(
        (f.run_id, f.cell, f.policy.as_str(), f.run, f.error.as_str()),
        (7, 1, "zigzag", 1, "the engine stopped")
    );
    assert!(m.table.contains("cell 1: default, fleet.n_auvs = 3\nno comparison: 1 of its runs failed"), "{}", m.table);
    assert!(m.table.contains("cell 0: default, fleet.n_auvs = 2\nN = 2 survey AUVs"));
    let failures = std::fs::read_to_string(m.dir.join("failures.csv")).unwrap();
    assert_eq!(failures, "run_id,cell,policy,run,error\n7,1,zigzag,1,the engine stopped\n");
    let fleet = std::fs::read_to_string(m.dir.join("fleet.csv")).unwrap();
    let row = fleet.lines().nth(8).unwrap();
    assert!(row.starts_with("7,1,default,3,zigzag,1,") && row.contains(",the engine stopped,"), "{row}");
}

#[test]
fn a_one_cell_sweep_prints_the_monte_carlo_comparison_of_its_scenario() {
    let tmp = tempfile::tempdir().unwrap();
    let text = "scenarios = [\"default\"]\npolicies = [\"centroid\", \"zigzag\", \"racetrack\"]\nruns = 4\n";
    let a = plan(tmp.path(), "a", text, 3);
    shard::run_shards(&a, &[0, 1, 2], &|_| {}).unwrap();
    let m = merge::merge(&a, None, false, "t").unwrap();
    let sc = Scenario::parse(EXAMPLE, Path::new("default")).unwrap();
    let names: Vec<String> = ["centroid", "zigzag", "racetrack"].map(String::from).to_vec();
    let expected = comparison_table(&monte_carlo(&sc, &names, 4, &|_| {}).unwrap());
    assert_eq!(m.table, expected);
    assert_eq!(std::fs::read_to_string(m.dir.join("comparison.txt")).unwrap(), expected);
}
