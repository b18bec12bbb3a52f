//! `coopnav plan` end to end: the default run writes fresh directories, an explicit existing -o
//! is refused without --force, and bad input exits non-zero leaving no output directory.

use std::path::Path;
use std::process::Command;

fn coopnav(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).current_dir(dir).output().unwrap()
}

fn short_example(dir: &Path) -> String {
    let out = coopnav(dir, &["plan", "--example"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap().replace("[cna]", "[mission]\nend_time = 300.0\n\n[cna]");
    std::fs::write(dir.join("s.toml"), text).unwrap();
    "s.toml".into()
}

#[test]
fn default_runs_get_fresh_names_and_explicit_outputs_need_force() {
    let dir = tempfile::tempdir().unwrap();
    let s = short_example(dir.path());
    for _ in 0..2 {
        assert!(coopnav(dir.path(), &["plan", &s]).status.success());
    }
    assert!(dir.path().join("runs/plan-s/summary.json").is_file());
    assert!(dir.path().join("runs/plan-s-2/cna_waypoints.moos").is_file());
    assert!(coopnav(dir.path(), &["plan", &s, "-o", "out"]).status.success());
    let again = coopnav(dir.path(), &["plan", &s, "-o", "out"]);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    assert!(coopnav(dir.path(), &["plan", &s, "-o", "out", "--force"]).status.success());
}

#[test]
fn bad_input_exits_non_zero_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let s = short_example(dir.path());
    let text = std::fs::read_to_string(dir.path().join(&s)).unwrap();
    let cases = [
        ("unknown.toml", text.replace("[policy.planner]\n", "[policy.planner]\ncolour = 1\n"), "colour"),
        ("a1.toml", text.replace("heading_options = 5", "heading_options = 1"), "heading_options"),
        ("speed.toml", text.replace("speed = 3.0 ", "speed = -1.0 "), "speed"),
        ("turn.toml", text.replace("max_turn_rate_deg_s = 4.0", "max_turn_rate_deg_s = 20.0"), "max_turn_rate_deg_s"),
    ];
    for (name, body, needle) in cases {
        std::fs::write(dir.path().join(name), body).unwrap();
        let out = coopnav(dir.path(), &["plan", name, "-o", "o"]);
        assert!(!out.status.success(), "{name} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{name}: {err}");
        assert!(!dir.path().join("o").exists(), "{name} left an output directory");
    }
    let out = coopnav(dir.path(), &["plan", "missing.toml", "-o", "o"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("missing.toml"));
    assert!(!dir.path().join("o").exists());
}
