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
    // A long mission (within the memory limit), so the run is still being computed when the
    // signal arrives.
    let long = String::from_utf8(example.stdout).unwrap().replace("duration_s = 3600.0", "duration_s = 150000.0");
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

/// A short mission file in `dir`: the example at 2 AUVs and 5 minutes.
fn short_scenario(dir: &Path, home: &Path) -> std::path::PathBuf {
    let out = coopnav(dir, home, &["simulate", "--example"]);
    let text = String::from_utf8(out.stdout).unwrap().replace("duration_s = 3600.0", "duration_s = 300.0");
    assert!(text.contains("duration_s = 300.0"), "the example's duration line moved");
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `--json` prints the result on stdout and writes no file: the old `--json FILE` form is refused
/// without touching the file it names; with `--runs` stdout is the comparison's JSON, byte for
/// byte the `comparison.json` of `-o`, and one run's is its `summary.json`; `-o` with `--runs`
/// writes the comparison's table, JSON and plot.
#[test]
fn the_comparison_json_and_directory_follow_the_run_directory_rules() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, home) = (tmp.path(), tmp.path().join("home"));
    let scenario = short_scenario(dir, &home);
    let original = std::fs::read_to_string(&scenario).unwrap();
    let runs = |extra: &[&str]| {
        let mut args = vec!["simulate", "s.toml", "--runs", "2", "--policy", "centroid,zigzag"];
        args.extend_from_slice(extra);
        coopnav(dir, &home, &args)
    };
    for force in [&[][..], &["--force"][..]] {
        let out = runs(&[&["--json", "s.toml"][..], force].concat());
        assert!(!out.status.success(), "--json takes no file: a second positional is refused");
        assert_eq!(std::fs::read_to_string(&scenario).unwrap(), original, "the scenario was overwritten");
    }
    let out = runs(&["--json", "-o", "cmp-json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON alone");
    assert_eq!(value["runs"].as_u64(), Some(2));
    assert_eq!(value["paired"][0]["baseline"].as_str(), Some("zigzag"));
    assert_eq!(out.stdout, std::fs::read(dir.join("cmp-json/comparison.json")).unwrap());
    assert!(String::from_utf8_lossy(&out.stderr).contains("wrote "), "the directory is named on stderr");
    let again = runs(&["--json"]);
    assert_eq!(again.stdout, out.stdout, "same seed, same bytes");

    let single = coopnav(dir, &home, &["simulate", "s.toml", "--json", "-o", "one"]);
    assert!(single.status.success(), "{}", String::from_utf8_lossy(&single.stderr));
    assert_eq!(single.stdout, std::fs::read(dir.join("one/summary.json")).unwrap());
    serde_json::from_slice::<serde_json::Value>(&single.stdout).expect("stdout is JSON alone");

    let out = runs(&["-o", "cmp"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let table = std::fs::read_to_string(dir.join("cmp/comparison.txt")).unwrap();
    assert_eq!(
        table,
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .take_while(|l| !l.starts_with("wrote"))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("cmp/comparison.json")).unwrap()).unwrap();
    assert_eq!(json["paired"][0]["baseline"].as_str(), Some("zigzag"));
    let svg = std::fs::read_to_string(dir.join("cmp/differences.svg")).unwrap();
    assert!(svg.contains("vs zigzag") && svg.contains("centroid minus"), "the plot labels its interval");
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("cmp/manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["tool"].as_str(), Some("coopnav"));
    assert!(hidden(dir).is_empty(), "staging left behind: {:?}", hidden(dir));
}

/// `--force` never deletes the command's own input: a scenario or a log inside the directory it
/// would replace is named and nothing is touched.
#[test]
fn force_refuses_a_target_that_holds_the_commands_input() {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, home) = (tmp.path(), tmp.path().join("home"));
    short_scenario(dir, &home);
    assert!(coopnav(dir, &home, &["simulate", "s.toml", "-o", "r"]).status.success());
    std::fs::copy(dir.join("s.toml"), dir.join("r/s.toml")).unwrap();
    let out = coopnav(dir, &home, &["simulate", "r/s.toml", "-o", "r", "--force"]);
    assert_refused(&out, "r/s.toml");
    assert!(dir.join("r/s.toml").is_file(), "the scenario was deleted");
    let out = coopnav(dir, &home, &["simulate", "./r/../r/s.toml", "-o", "r/", "--force"]);
    assert_refused(&out, "an input of this command");
    assert!(dir.join("r/s.toml").is_file());

    assert!(coopnav(dir, &home, &["hbl", "simulate", "-o", "h"]).status.success());
    let log = dir.join("h/log.csv");
    assert!(log.is_file(), "hbl simulate writes log.csv");
    let out = coopnav(dir, &home, &["hbl", "postprocess", "h/log.csv", "-o", "h", "--force"]);
    assert_refused(&out, "h/log.csv");
    assert!(log.is_file(), "the log was deleted");
    assert!(hidden(dir).is_empty(), "staging left behind: {:?}", hidden(dir));
}

/// Every file of run directory `dir`, by name.
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap())
        })
        .collect()
}

fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// A `--force` replacement killed with SIGKILL anywhere, 50 times at seeded random points of its
/// run (the later ones inside the window where the new run lands): afterwards the target is the
/// old run or the new one, whole, and the next run removes whatever the killed ones left.
#[test]
fn a_replacement_killed_anywhere_leaves_the_old_run_or_the_new_one() {
    use rand::{Rng, SeedableRng};
    let tmp = tempfile::tempdir().unwrap();
    let (dir, home) = (tmp.path(), tmp.path().join("home"));
    short_scenario(dir, &home);
    let args = |seed: &'static str| ["simulate", "s.toml", "-o", "r", "--force", "--seed", seed];
    let run = |seed| {
        let start = Instant::now();
        let out = coopnav(dir, &home, &args(seed));
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (snapshot(&dir.join("r")), start.elapsed())
    };
    let (new, _) = run("2");
    let (old, full) = run("1");
    assert_ne!(old, new, "the two seeds give different runs");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut current = "1";
    let mut outcomes = [0usize; 2];
    for round in 0..50 {
        let seed = if current == "1" { "2" } else { "1" };
        // Most kills fall in the last fifth of the run, where the run directory is written and
        // swapped into place.
        let fraction = if round % 2 == 0 { rng.gen_range(0.0..1.0) } else { rng.gen_range(0.8..1.1) };
        let mut child = Command::new(env!("CARGO_BIN_EXE_coopnav"))
            .args(args(seed))
            .current_dir(dir)
            .env("HOME", &home)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(full.mul_f64(fraction));
        let _ = child.kill();
        let status = child.wait().unwrap();
        let state = snapshot(&dir.join("r"));
        current = if state == old {
            "1"
        } else if state == new {
            "2"
        } else {
            panic!("round {round} (killed at {fraction:.2} of a run, {status}): the target is neither run whole");
        };
        outcomes[usize::from(current == seed)] += 1;
    }
    let (_, _) = run(current);
    assert!(hidden(dir).is_empty(), "left behind after the next run: {:?}", hidden(dir));
    assert!(outcomes[0] > 0 && outcomes[1] > 0, "kills before and after landing both occurred: {outcomes:?}");
}
