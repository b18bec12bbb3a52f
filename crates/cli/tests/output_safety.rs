//! Output directories never cost the user a file: `--force` replaces only a
//! run directory coopnav wrote, refuses the working directory, its ancestors and home, and an
//! interrupted run leaves no directory behind. Every case runs inside a temporary directory.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn coopnav(cwd: &Path, home: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).current_dir(cwd).env("HOME", home).output().unwrap()
}

/// A directory of user files, and a check that they are all still there, unchanged.
struct UserFiles {
    dir: std::path::PathBuf,
}

impl UserFiles {
    const NAMES: [&'static str; 3] = ["thesis.tex", "survey.csv", "notes.md"];

    fn new(dir: &Path) -> Self {
        std::fs::create_dir_all(dir).unwrap();
        for name in Self::NAMES {
            std::fs::write(dir.join(name), format!("precious {name}")).unwrap();
        }
        UserFiles { dir: dir.to_path_buf() }
    }

    fn assert_intact(&self) {
        for name in Self::NAMES {
            let text = std::fs::read_to_string(self.dir.join(name)).unwrap_or_default();
            assert_eq!(text, format!("precious {name}"), "{} was lost", self.dir.join(name).display());
        }
        let hidden: Vec<_> = std::fs::read_dir(&self.dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "staging left behind in {}: {hidden:?}", self.dir.display());
    }
}

fn assert_refused(out: &Output, reason: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a destructive --force must fail");
    assert!(stderr.contains(reason), "the message should say '{reason}': {stderr}");
    assert_eq!(stderr.matches("Error").count(), 1, "the error prints once: {stderr}");
}

#[test]
fn force_refuses_the_working_directory_and_its_parent() {
    let tmp = tempfile::tempdir().unwrap();
    let parent = UserFiles::new(tmp.path());
    let cwd = UserFiles::new(&tmp.path().join("work"));
    let home = tmp.path().join("home");
    for command in ["plan", "simulate"] {
        assert_refused(&coopnav(&cwd.dir, &home, &[command, "-o", ".", "--force"]), "current working directory");
        assert_refused(&coopnav(&cwd.dir, &home, &[command, "-o", "..", "--force"]), "contains the current working");
        assert_refused(&coopnav(&cwd.dir, &home, &[command, "-o", "./../work/", "--force"]), "current working");
    }
    cwd.assert_intact();
    parent.assert_intact();
}

#[test]
fn force_refuses_home_and_any_directory_coopnav_did_not_write() {
    let tmp = tempfile::tempdir().unwrap();
    let home = UserFiles::new(&tmp.path().join("home"));
    let mine = UserFiles::new(&tmp.path().join("mine"));
    let home_arg = home.dir.to_string_lossy().into_owned();
    assert_refused(&coopnav(tmp.path(), &home.dir, &["plan", "-o", &home_arg, "--force"]), "home directory");
    assert_refused(&coopnav(tmp.path(), &home.dir, &["simulate", "-o", "mine", "--force"]), "no coopnav manifest");
    assert_refused(&coopnav(tmp.path(), &home.dir, &["simulate", "-o", "mine"]), "no coopnav manifest");
    home.assert_intact();
    mine.assert_intact();
}

#[test]
fn force_replaces_a_run_coopnav_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let home = tmp.path().join("home");
    assert!(coopnav(tmp.path(), &home, &["simulate", "-o", "run"]).status.success());
    std::fs::write(tmp.path().join("run/stale.txt"), "from an older run").unwrap();
    assert!(coopnav(tmp.path(), &home, &["simulate", "-o", "run", "--force"]).status.success());
    assert!(tmp.path().join("run/manifest.json").is_file());
    assert!(!tmp.path().join("run/stale.txt").exists(), "the old run was replaced, not merged");
    let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, ["run"], "no staging or set-aside directory may remain");
}

#[test]
fn an_interrupted_run_leaves_no_directory_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let example = coopnav(tmp.path(), tmp.path(), &["simulate", "--example"]);
    // A long mission, so the run is still being computed when the signal arrives.
    let long = String::from_utf8(example.stdout).unwrap().replace("duration_s = 3600.0", "duration_s = 500000.0");
    std::fs::write(tmp.path().join("long.toml"), long).unwrap();
    for signal in ["-TERM", "-INT"] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_coopnav"))
            .args(["simulate", "long.toml", "-o", "run"])
            .current_dir(tmp.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while !has_staging(tmp.path()) {
            assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be interrupted");
            assert!(start.elapsed() < Duration::from_secs(60), "no staging directory appeared");
            std::thread::sleep(Duration::from_millis(20));
        }
        let killed = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
        assert!(killed.success());
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{}", String::from_utf8_lossy(&out.stderr));
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, ["long.toml"], "after {signal}: nothing but the scenario may remain");
    }
}

fn has_staging(dir: &Path) -> bool {
    std::fs::read_dir(dir).unwrap().any(|e| e.unwrap().file_name().to_string_lossy().contains(".partial-"))
}
