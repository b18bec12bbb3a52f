//! `coopnav nams FILE`: a small experiment file runs and writes its run directory; bad files
//! are rejected before anything runs, naming the field, and leave nothing behind.

use std::process::Command;

fn coopnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).env("RUST_BACKTRACE", "0").output().expect("run coopnav")
}

const SMALL: &str = r#"
[experiment]
runs = 2
max_time = 900.0
behaviours = [{ kind = "fixed", rate = 1 }, { kind = "adaptive", step = 10.0 }]
scenarios = [{ name = "tiny", square = 200.0, lane_spacing = 50.0, noise_db = 6.0 }]

[tl]
model = "analytic"
k = 1.5
"#;

#[test]
fn small_experiment_writes_its_run_directory() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("exp.toml");
    std::fs::write(&cfg, SMALL).unwrap();
    let out = dir.path().join("run");
    let o = coopnav(&["nams", cfg.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("tiny") && table.contains("adaptive") && table.contains("fixed rate 1"), "{table}");
    for f in ["cells.csv", "summary.json", "manifest.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}

#[test]
fn bad_files_are_rejected_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    for (text, needle) in [
        ("[experiment]\nrunz = 3\n", "runz"),
        ("[experiment]\nruns = 0\n", "experiment.runs = 0"),
        (
            "[experiment]\nrepetitions = 3\n",
            "renamed key(s), each with its new name:\n  experiment.repetitions -> experiment.runs",
        ),
        ("[experiment]\nscenarios = [{ square = 500.0, noise_db = -1.0 }]\n", "noise_db"),
        ("[experiment.success]\nnoise_db = -2.0\n", "noise_db"),
        ("[experiment.vehicle]\ntimestep = 0.0\n", "timestep"),
        ("[tl]\nmodel = \"analytic\"\nk = 9.0\n", "tl.k"),
        ("[tl]\nmodel = \"ray_magic\"\n", "ray_magic"),
    ] {
        let cfg = dir.path().join("bad.toml");
        std::fs::write(&cfg, text).unwrap();
        let o = coopnav(&["nams", cfg.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{text} was accepted");
        assert!(err.contains(needle), "{text}: error does not mention {needle}: {err}");
        assert!(!out.exists(), "nothing written for {text}");
    }
}
