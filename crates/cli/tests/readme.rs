//! Every command block of the README runs as written, so the documentation cannot drift from the
//! program: each `cargo run --release -- ARGS [> FILE]` line of a ```sh block runs as
//! `coopnav ARGS` (stdout into FILE), in order, in one temporary directory, and must exit 0.
//! The long ones (full experiments, benchmarks) run in the reduced forms listed in [`REDUCED`],
//! as the README says; every entry must still match a README line, so the list cannot go stale.

mod common;

use common::{coopnav, copy_dir, edited_example};
use std::path::Path;

/// The README's test command, the second of its two commands; `.ci/run` must run exactly this.
const TEST_COMMAND: &str = "cargo test --workspace --release";

/// The README lines that are not coopnav commands, and why the test does not run them.
const NOT_RUN: &[(&str, &str)] = &[
    (TEST_COMMAND, "this test suite itself"),
    (
        "COOPNAV_FUZZ_N=1000000 cargo test --release -p coopnav-cli --bin coopnav fuzz -- --ignored --nocapture",
        "the long fuzz run; `cargo test` runs its targets with fewer inputs",
    ),
    ("bash scripts/install-bellhop.sh", "installs an external program; .ci/run runs it"),
    ("bash scripts/install-pymoos.sh", "installs an external program; .ci/run runs it"),
    ("bash scripts/install-chromium.sh", "installs an external program; .ci/run runs it"),
];

/// A README command run in a smaller form: its arguments as the README writes them, the
/// arguments actually run, and an input file made first from an `--example`-style command's
/// output with text replaced (each replaced text must occur in that output).
struct Reduced {
    readme: &'static str,
    run: &'static str,
    input: Option<(&'static str, &'static str, &'static [(&'static str, &'static str)])>,
}

const REDUCED: &[Reduced] = &[
    Reduced {
        readme: "advise scenarios/geographic-survey.toml -o advice",
        run:
            "advise scenarios/geographic-survey.toml -o advice --runs 2 --duration 300 --policy planner-estimator,none",
        input: None,
    },
    Reduced {
        readme: "simulate s.toml --runs 100 --policy planner-estimator,planner,centroid,zigzag",
        run: "simulate s.toml --runs 2 --policy planner-estimator,planner,centroid,zigzag",
        input: None,
    },
    Reduced {
        readme: "reproduce closed-loop-vs-baselines -o closed-loop",
        run: "reproduce closed-loop-vs-baselines --reduced -o closed-loop",
        input: None,
    },
    Reduced {
        readme: "reproduce closed-loop-cna-navigation -o cna-nav",
        run: "reproduce closed-loop-cna-navigation --reduced -o cna-nav",
        input: None,
    },
    Reduced { readme: "reproduce <id>", run: "reproduce hudson-table-5.8 --reduced", input: None },
    Reduced { readme: "reproduce <id> --reduced", run: "reproduce hudson-table-5.8 --reduced", input: None },
    Reduced { readme: "bench closed-loop --tl analytic", run: "bench closed-loop --tl analytic --runs 1", input: None },
    Reduced { readme: "bench planner", run: "bench planner --runs 1 --brute-max-leaves 0", input: None },
    Reduced { readme: "bench hbl", run: "bench hbl --runs 4", input: None },
    Reduced { readme: "bench acomms", run: "bench acomms --runs 1 --no-bellhop", input: None },
    Reduced { readme: "hbl montecarlo -o hbl-mc", run: "hbl montecarlo -o hbl-mc --runs 4", input: None },
    Reduced {
        readme: "hbl grid -o hbl-grid",
        run: "hbl grid -o hbl-grid --grid grid-reduced.toml",
        input: Some((
            "hbl example grid",
            "grid-reduced.toml",
            &[("spacing = 10.0", "spacing = 50.0"), ("runs_per_cell = 250", "runs_per_cell = 2")],
        )),
    },
    Reduced {
        readme: "hbl tune --spec tune.toml -o tune",
        run: "hbl tune --spec tune-reduced.toml -o tune",
        input: Some((
            "hbl example tune",
            "tune-reduced.toml",
            &[("runs = 50", "runs = 4"), ("max_iters = 40", "max_iters = 2")],
        )),
    },
    Reduced {
        readme: "nams exp.toml -o nams",
        run: "nams exp-reduced.toml -o nams",
        input: Some(("nams --example", "exp-reduced.toml", &[("runs = 40", "runs = 1")])),
    },
];

/// Commands (as run) whose property checks fail on today's main, with why: they must still run
/// to completion and report their checks (exit 1 or 3, `[FAIL` lines), never crash.
const CHECKS_FAILING: &[(&str, &str)] = &[
    (
        "reproduce closed-loop-vs-baselines --reduced -o closed-loop",
        "the estimator-aware planner does not win every cell of the reduced evaluation (8 runs of 15 minutes per cell \
         do not resolve every cell; see docs/evaluation.md)",
    ),
    (
        "reproduce closed-loop-cna-navigation --reduced -o cna-nav",
        "its checks are those of closed-loop-vs-baselines on the AUV-CNA cells, as evaluated and with the CNA exact \
         (8 runs of 15 minutes do not resolve the sloping N = 2 cells either way; see docs/evaluation.md)",
    ),
];

const PREFIX: &str = "cargo run --release --";

/// The lines of the README's ```sh blocks, comments and blank lines removed.
fn readme_commands() -> Vec<String> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    let mut in_block = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        match line.trim() {
            "```sh" => in_block = true,
            "```" => in_block = false,
            l if in_block => {
                let command = l.split(" #").next().unwrap_or_default().trim();
                if !command.is_empty() && !command.starts_with('#') {
                    lines.push(command.to_string());
                }
            }
            _ => {}
        }
    }
    lines
}

/// Runs `coopnav ARGS` in `dir`, its stdout into `stdout_file` when given; panics with the
/// command and its stderr unless it exits 0.
fn run(dir: &Path, args: &str, stdout_file: Option<&str>) -> Vec<u8> {
    let out = coopnav(dir, &args.split_whitespace().collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&out.stderr);
    match CHECKS_FAILING.iter().find(|(a, _)| *a == args) {
        Some((_, why)) => {
            let code = out.status.code();
            let stdout = String::from_utf8_lossy(&out.stdout);
            eprintln!("note: `coopnav {args}` exit {code:?}, expected check failures: {why}");
            // The status is the one its printed checks and tables call for (1 for a plain
            // `[FAIL]`, else 3 for a failure with its measured cause, else 0): an exit 1 with no
            // failure printed is the run failing, not its checks.
            let lines = || stdout.lines();
            let want = if lines().any(|l| l.starts_with("[FAIL]")) {
                1
            } else if lines().any(|l| l.starts_with("[FAIL, measured cause]")) {
                3
            } else {
                0
            };
            assert_eq!(
                code,
                Some(want),
                "`coopnav {args}`: the exit status does not match its checks: {stdout}{stderr}"
            );
        }
        None => assert!(out.status.success(), "`coopnav {args}` failed: {stderr}"),
    }
    if let Some(file) = stdout_file {
        std::fs::write(dir.join(file), &out.stdout).unwrap();
    }
    out.stdout
}

fn make_input(dir: &Path, (command, file, edits): (&str, &str, &[(&str, &str)])) {
    edited_example(dir, &command.split_whitespace().collect::<Vec<_>>(), file, edits);
}

#[test]
fn every_readme_command_runs() {
    let tmp = tempfile::tempdir().unwrap();
    // The README's commands run from the repository's root: the scenario library is there.
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios"), &tmp.path().join("scenarios"));
    let mut used = vec![false; REDUCED.len()];
    let mut ran = 0;
    for line in readme_commands() {
        if NOT_RUN.iter().any(|(l, _)| *l == line) {
            continue;
        }
        let rest = line.strip_prefix(PREFIX).unwrap_or_else(|| panic!("README line {line:?} is not `{PREFIX} ...`"));
        let (args, stdout_file) = match rest.split_once(" > ") {
            Some((args, file)) => (args.trim(), Some(file.trim())),
            None => (rest.trim(), None),
        };
        let args = match REDUCED.iter().position(|r| r.readme == args) {
            Some(i) => {
                used[i] = true;
                if let Some(input) = REDUCED[i].input {
                    make_input(tmp.path(), input);
                }
                REDUCED[i].run
            }
            None => args,
        };
        run(tmp.path(), args, stdout_file);
        ran += 1;
    }
    let stale: Vec<_> = REDUCED.iter().zip(&used).filter(|(_, u)| !**u).map(|(r, _)| r.readme).collect();
    assert!(stale.is_empty(), "REDUCED entries matching no README line: {stale:?}");
    assert!(ran >= 20, "only {ran} README commands found");
}

/// CI runs the README's test command as written (so a newcomer's run and CI's are the same
/// build), and no other `cargo test`.
#[test]
fn ci_runs_the_readme_test_command() {
    let first_test_line = readme_commands().into_iter().find(|l| l.starts_with("cargo test"));
    assert_eq!(first_test_line.as_deref(), Some(TEST_COMMAND), "the README's first test command");
    let ci = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.ci/run")).unwrap();
    let ci_tests: Vec<&str> = ci.lines().map(str::trim).filter(|l| l.starts_with("cargo test")).collect();
    assert_eq!(ci_tests, [TEST_COMMAND], ".ci/run's cargo test lines");
}

/// Every crate the README's main job builds (`cargo run --release`, the `coopnav` binary's normal
/// dependencies) has the same features in the test command's build (the whole workspace with its
/// dev-dependencies), so the test step on a fresh clone reuses those units instead of rebuilding
/// them (the unifying entries are in `crates/cli/Cargo.toml`).
#[test]
fn the_test_build_reuses_every_crate_of_the_main_job() {
    let run = crate_features(&["-p", "coopnav-cli", "-e", "normal,build"]);
    let test = crate_features(&["--workspace", "-e", "normal,build,dev"]);
    let differing: Vec<String> = run
        .iter()
        .filter(|(krate, features)| test.get(*krate) != Some(*features))
        .map(|(krate, features)| format!("{krate}: main job [{features}], tests [{}]", test[krate]))
        .collect();
    assert!(run.len() > 50, "cargo tree listed only {} crates", run.len());
    assert!(differing.is_empty(), "crates whose features differ (add them to crates/cli/Cargo.toml): {differing:#?}");
}

/// `cargo tree` for the workspace: each package (name and version) with its enabled features.
fn crate_features(selection: &[&str]) -> std::collections::BTreeMap<String, String> {
    let out = std::process::Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--locked", "--prefix", "none", "-f", "{p}|{f}"])
        .args(selection)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|line| line.trim_end_matches(" (*)").split_once('|'))
        .map(|(package, features)| (package.to_string(), features.to_string()))
        .collect()
}
