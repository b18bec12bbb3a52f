//! `coopnav sitl --lockstep` end to end, only inside a private network namespace the test makes
//! (`netns`: `unshare -n`, loopback only, TTL 0): the world and its `live cna` child on real UDP
//! multicast give the run directory `coopnav simulate` writes for the same scenario and seed,
//! byte for byte but for the command line the manifest and report quote; and a child that stops
//! answering is reported by the world, which holds the CNA's last command and finishes the run.
//! Free running and live AUVs: `sitl_live.rs`.
//! Ignored, with the reason, where `unshare` cannot make a namespace.

mod netns;

use coopnav_live::sitl::{run_lockstep, SitlOptions};
use coopnav_sim::scenario::file::load;
use coopnav_sim::scenario::Scenario;
use netns::{coopnav_ok, in_private_netns, refused, stop_clock_at_decision};
use std::path::{Path, PathBuf};
use std::time::Duration;

const URL: &str = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

fn scenario_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name)
}

/// Every file `simulate` wrote is in the sitl run, equal; the manifest and report once each
/// quotes its own command line.
fn same_run(sim: &Path, sitl: &Path, commands: (&str, &str)) {
    let mut files = 0;
    for entry in std::fs::read_dir(sim).unwrap() {
        let name = entry.unwrap().file_name();
        let a = std::fs::read_to_string(sim.join(&name)).unwrap();
        let b = std::fs::read_to_string(sitl.join(&name)).unwrap_or_else(|e| panic!("{name:?}: {e}"));
        // The report quotes it HTML-escaped.
        let quoted = |c: &str| c.replace('&', "&amp;");
        let a = a.replace(commands.0, "COMMAND").replace(&quoted(commands.0), "COMMAND");
        let b = b.replace(commands.1, "COMMAND").replace(&quoted(commands.1), "COMMAND");
        assert!(a == b, "{name:?} differs");
        files += 1;
    }
    assert!(files >= 9, "{files} files");
}

fn lockstep_equals_simulate(file: &str) {
    let dir = tempfile::tempdir().unwrap();
    let (sim, sitl) = (dir.path().join("sim"), dir.path().join("sitl"));
    let scenario = scenario_path(file);
    let sc = scenario.to_str().unwrap();
    let bin = env!("CARGO_BIN_EXE_coopnav");
    let sim_args = ["simulate", sc, "-o", sim.to_str().unwrap()];
    let sitl_args = ["sitl", sc, "--lockstep", "-o", sitl.to_str().unwrap(), "--url", URL];
    coopnav_ok(&sim_args, Duration::from_secs(240));
    let said = coopnav_ok(&sitl_args, Duration::from_secs(240));
    println!("{said}");
    assert!(said.contains("(0 missed, 0 on other inputs)"), "{said}");
    let join = |args: &[&str]| [&[bin][..], args].concat().join(" ");
    same_run(&sim, &sitl, (&join(&sim_args), &join(&sitl_args)));
    let world: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sitl.join("sitl.json")).unwrap()).unwrap();
    assert_eq!(world["live_cna"]["stopped_by"], "clock_stopped", "{world}");
    assert_eq!(world["live_cna"]["decisions"], world["world"]["decisions"], "{world}");
    assert!(std::fs::metadata(sitl.join("cna.lcm")).unwrap().len() > 1000);
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn sitl_in_lockstep_writes_the_run_simulate_writes() {
    in_private_netns("sitl_in_lockstep_writes_the_run_simulate_writes", || {
        lockstep_equals_simulate("default.toml");
        lockstep_equals_simulate("auv-cna-tdma.toml");
    });
}

/// The child stops commanding at decision 40 (the test stops its clock): the world waits for
/// each later decision in vain, counts it as missed, holds the last command, and finishes.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn sitl_reports_a_cna_that_stopped_commanding_and_holds_its_last_command() {
    in_private_netns("sitl_reports_a_cna_that_stopped_commanding_and_holds_its_last_command", || {
        let path = scenario_path("default.toml");
        let sc: Scenario = load(&path, Scenario::validate).unwrap();
        // Stops the child's clock at decision 40.
        let stopper = stop_clock_at_decision(URL, 40);
        let bin = env!("CARGO_BIN_EXE_coopnav").to_string();
        let child =
            [&bin, "live", "cna", path.to_str().unwrap(), "--policy", "planner", "--clock", "bus", "--url", URL];
        let child = child.iter().map(|s| s.to_string()).collect();
        let opts = SitlOptions::lockstep(URL, child, Duration::from_millis(150));
        let run = run_lockstep(&sc, "planner", &opts).unwrap();
        assert!(stopper.join().unwrap(), "decision 40 was seen");
        let answered = run.child_summary.as_ref().unwrap()["decisions"].as_u64().unwrap();
        let c = &run.counts;
        println!("{c:?}, the child answered {answered}");
        assert_eq!(c.decisions, 120);
        assert!((41..=43).contains(&answered), "{answered}");
        assert_eq!(c.missed_decisions, c.decisions - answered);
        assert_eq!(c.input_mismatches, 0);
        // The run finished, the CNA holding its last command; the planner's tally is the child's
        // at its last answer.
        assert_eq!(run.result.planner.as_ref().unwrap().decisions, answered);
        assert!(run.result.fleet.error.mean.is_finite());
    });
}

/// Without a pace, with a warp that is no factor, or with both paces, sitl says what it takes.
#[test]
fn sitl_refuses_a_missing_or_impossible_pace() {
    for (args, expected) in [
        (&["sitl"][..], "give --lockstep (the world waits for each decision) or --warp W (free running)"),
        (&["sitl", "--warp", "0"][..], "--warp 0: give a factor in (0, 1000]"),
        (&["sitl", "--warp", "nan"][..], "--warp NaN: give a factor in (0, 1000]"),
        (&["sitl", "--lockstep", "--warp", "30"][..], "cannot be used with"),
    ] {
        refused(args, expected);
    }
}
