//! `coopnav simulate` end to end: the default mission writes a run directory with the report,
//! `--example` prints a scenario that runs, and a bad scenario fails naming the field and writes
//! nothing.

mod common;

use common::coopnav;

#[test]
fn default_mission_writes_a_fresh_run_directory() {
    let tmp = tempfile::tempdir().unwrap();
    for expected in ["sim-default", "sim-default-2"] {
        let out = coopnav(tmp.path(), &["simulate"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let run = tmp.path().join("runs").join(expected);
        for f in [
            "report.html",
            "summary.json",
            "manifest.json",
            "timeseries.csv",
            "comms.csv",
            "tracks.svg",
            "error.svg",
            "comms.svg",
        ] {
            assert!(run.join(f).is_file(), "{expected}/{f}");
        }
    }
}

#[test]
fn example_round_trips_and_bad_files_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let example = coopnav(tmp.path(), &["simulate", "--example"]);
    assert!(example.status.success());
    let text = String::from_utf8(example.stdout).unwrap();
    let short = text.replace("duration_s = 3600.0", "duration_s = 120.0");
    std::fs::write(tmp.path().join("s.toml"), &short).unwrap();
    let ok = coopnav(tmp.path(), &["simulate", "s.toml", "--runs", "2", "--policy", "planner,centroid"]);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let table = String::from_utf8(ok.stdout).unwrap();
    assert!(table.contains("centroid") && table.contains("95% CI"), "{table}");

    std::fs::write(tmp.path().join("bad.toml"), short.replace("tau = 30.0", "tau = 0.5")).unwrap();
    let bad = coopnav(tmp.path(), &["simulate", "bad.toml"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("comms.tau") && err.contains("bad.toml"), "{err}");
    assert!(!tmp.path().join("runs").exists(), "nothing written for a bad scenario");
}
