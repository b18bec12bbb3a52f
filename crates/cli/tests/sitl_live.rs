//! Free-running `sitl --warp` and live AUVs end to end, only inside a private network namespace
//! the test makes (`netns`: `unshare -n`, loopback only, TTL 0): the world with its `live cna`
//! and `live auv` children on real UDP multicast. A short warped mission misses no decision and
//! is scored on the live navigators' estimates; each fault the world injects into its messages
//! to the navigators (dropped, duplicated, delayed, reordered, malformed) is counted by them and
//! changes the run only as it should; a navigator killed and started again mid-mission resumes;
//! a CNA that stops commanding in a free-running run is reported as a silence. The one-hour
//! five-AUV check against `simulate --runs 20` is ignored (about six minutes on an idle machine):
//! run it with `--ignored`. Ignored, with the reason, where `unshare` cannot make a namespace.

mod netns;

use coopnav_live::sitl::{run, BusFaults, LiveAuvs, Pace, Restart, SitlOptions, SitlRun};
use coopnav_sim::scenario::file::load;
use coopnav_sim::scenario::Scenario;
use netns::{coopnav_ok, in_private_netns, stop_clock_at_decision};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const URL: &str = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

fn scenario_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name)
}

/// `name` from the library with its duration set to `duration_s`, written to `dir` (the CNA
/// child reads the same file).
fn shortened(name: &str, duration_s: f64, dir: &Path) -> (PathBuf, Scenario) {
    let text = std::fs::read_to_string(scenario_path(name)).unwrap();
    let text = text.replacen("duration_s = 3600.0", &format!("duration_s = {duration_s:.1}"), 1);
    assert!(text.contains(&format!("duration_s = {duration_s:.1}")));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let sc: Scenario = load(&path, Scenario::validate).unwrap();
    (path, sc)
}

fn options(file: &Path, policy: &str, pace: Pace, live: Option<LiveAuvs>) -> SitlOptions {
    let bin = env!("CARGO_BIN_EXE_coopnav").to_string();
    let child = [&bin, "live", "cna", file.to_str().unwrap(), "--policy", policy, "--clock", "bus", "--url", URL];
    SitlOptions {
        url: URL.into(),
        child: child.iter().map(|s| s.to_string()).collect(),
        decision_timeout: Duration::from_secs(10),
        pace,
        live_auvs: live,
    }
}

fn live(dir: &Path, faults: BusFaults, restart: Option<Restart>) -> LiveAuvs {
    let bin = env!("CARGO_BIN_EXE_coopnav").to_string();
    LiveAuvs {
        program: vec![bin, "live".into(), "auv".into()],
        dir: dir.to_path_buf(),
        faults,
        restart,
        estimate_timeout: Duration::from_secs(5),
    }
}

/// The sum over the navigators (every process) of summary field `field`.
fn nav_sum(run: &SitlRun, field: &str) -> u64 {
    run.auv_summaries.iter().flatten().map(|s| s[field].as_u64().unwrap_or(0)).sum()
}

/// Messages the navigators received on their sensors and range channels.
fn nav_received(run: &SitlRun) -> u64 {
    run.auv_summaries
        .iter()
        .flatten()
        .filter_map(|s| s["messages"].as_object())
        .flat_map(|m| m.values())
        .map(|v| v.as_u64().unwrap())
        .sum()
}

/// A 300 s lockstep run of the default mission with live AUVs and `faults`.
fn lockstep_live(tmp: &Path, faults: BusFaults, restart: Option<Restart>) -> SitlRun {
    let (file, sc) = shortened("default.toml", 300.0, tmp);
    let logs = tmp.join(format!("logs-{}", std::time::UNIX_EPOCH.elapsed().unwrap().as_nanos()));
    std::fs::create_dir_all(&logs).unwrap();
    let opts = options(&file, "planner", Pace::Lockstep, Some(live(&logs, faults, restart)));
    let run = run(&sc, "planner", &opts).unwrap();
    let c = &run.counts;
    assert_eq!((c.decisions, c.missed_decisions, c.input_mismatches), (10, 0, 0), "{c:?}");
    run
}

fn live_errors(run: &SitlRun) -> Vec<f64> {
    run.result.trace.as_ref().unwrap().rows.iter().map(|r| r.error).collect()
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn a_short_warped_run_with_live_auvs_misses_no_decision_and_is_scored_on_their_estimates() {
    in_private_netns("a_short_warped_run_with_live_auvs_misses_no_decision_and_is_scored_on_their_estimates", || {
        let tmp = tempfile::tempdir().unwrap();
        let (file, sc) = shortened("default.toml", 600.0, tmp.path());
        let opts =
            options(&file, "planner-estimator", Pace::Warp(30.0), Some(live(tmp.path(), BusFaults::default(), None)));
        let started = Instant::now();
        let run = run(&sc, "planner-estimator", &opts).unwrap();
        let wall = started.elapsed().as_secs_f64();
        let (c, a) = (&run.counts, run.auvs.as_ref().unwrap());
        println!("{c:?}\n{:?}\n{a:?}\nwall {wall:.1} s", run.latencies);
        for s in run.auv_summaries.iter().flatten() {
            println!("{s}");
        }
        // 600 s at 30 × takes 20 s of wall time, and not much more.
        assert!(wall >= 20.0 && wall < 40.0, "{wall} s");
        assert_eq!((c.decisions, c.missed_decisions, c.late_commands), (20, 0, 0), "{c:?}");
        assert!(c.silences.is_empty());
        assert_eq!(run.latencies.commands, 20);
        assert!(run.latencies.wall_ms_max < 1000.0 && run.latencies.mission_s_max < 30.0, "{:?}", run.latencies);
        // Every sample (three AUVs, each second) is scored on a navigator's estimate of its
        // own time, after the first reorder window.
        assert_eq!(a.samples_on_live_estimate + a.samples_on_older_estimate + a.samples_on_engine_filter, 1800);
        assert!(a.samples_on_live_estimate >= 1800 - 3 * 5, "{a:?}");
        assert_eq!(a.sensors_published, 3 * 6000);
        assert_eq!(nav_sum(&run, "sensors_applied"), 3 * 6000);
        assert_eq!(nav_sum(&run, "malformed") + nav_sum(&run, "stale") + nav_sum(&run, "duplicates"), 0);
        // The run's error is the live one; it is not the engine filters' (another filter).
        let live_mean = run.result.fleet.error.mean;
        println!("live fleet error {live_mean} m, engine filters' {} m", a.engine_fleet_error_mean);
        assert!(live_mean.is_finite() && live_mean > 0.0 && live_mean != a.engine_fleet_error_mean);
        let rows = &run.result.trace.as_ref().unwrap().rows;
        let r = rows.iter().find(|r| (r.t - 300.0).abs() < 1e-6 && r.auv == 1).unwrap();
        assert!((r.error - (r.est_x - r.true_x).hypot(r.est_y - r.true_y)).abs() < 1e-9);
        assert!(run.auv_logs.iter().all(|l| l.len() == 1 && std::fs::metadata(&l[0]).unwrap().len() > 100_000));
    });
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn reordered_and_slightly_delayed_messages_change_nothing_and_late_ones_are_stale() {
    in_private_netns("reordered_and_slightly_delayed_messages_change_nothing_and_late_ones_are_stale", || {
        let tmp = tempfile::tempdir().unwrap();
        let clean = lockstep_live(tmp.path(), BusFaults::default(), None);
        let reordered = lockstep_live(tmp.path(), BusFaults { reorder_every: 7, ..BusFaults::default() }, None);
        let delayed =
            lockstep_live(tmp.path(), BusFaults { delay_every: 11, delay_s: 1.0, ..BusFaults::default() }, None);
        let late =
            lockstep_live(tmp.path(), BusFaults { delay_every: 11, delay_s: 10.0, ..BusFaults::default() }, None);
        for (run, field) in [(&reordered, "reordered"), (&delayed, "delayed"), (&late, "delayed")] {
            let a = run.auvs.as_ref().unwrap();
            let injected = serde_json::to_value(a).unwrap()[field].as_u64().unwrap();
            assert!(injected > 100, "{field}: {a:?}");
            assert_eq!(nav_received(run), a.sensors_published + a.ranges_published - a.delayed_past_end, "{a:?}");
        }
        // Within the reorder window: applied where they belong, the estimates bit for bit.
        assert_eq!(nav_sum(&reordered, "stale") + nav_sum(&delayed, "stale"), 0);
        assert_eq!(live_errors(&reordered), live_errors(&clean));
        // The messages delayed past the mission's end never arrived: equal up to the last second.
        let until = |r: &SitlRun| -> Vec<f64> {
            r.result.trace.as_ref().unwrap().rows.iter().filter(|r| r.t < 298.95).map(|r| r.error).collect()
        };
        assert_eq!(until(&delayed).len(), 3 * 298);
        assert_eq!(until(&delayed), until(&clean));
        // Past it: every delayed message that arrived is stale, counted and dropped.
        let a = late.auvs.as_ref().unwrap();
        // Those of the last 10 s (about 300 messages, every 11th held) never arrived.
        assert!((20..=35).contains(&a.delayed_past_end), "{a:?}");
        assert_eq!(nav_sum(&late, "stale"), a.delayed - a.delayed_past_end);
        assert_ne!(live_errors(&late), live_errors(&clean));
        assert!(late.result.fleet.error.mean.is_finite());
    });
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn duplicated_messages_are_dropped_and_change_nothing() {
    in_private_netns("duplicated_messages_are_dropped_and_change_nothing", || {
        let tmp = tempfile::tempdir().unwrap();
        let clean = lockstep_live(tmp.path(), BusFaults::default(), None);
        let dup = lockstep_live(tmp.path(), BusFaults { duplicate_every: 5, ..BusFaults::default() }, None);
        let a = dup.auvs.as_ref().unwrap();
        assert!(a.duplicated > 500, "{a:?}");
        assert_eq!(nav_sum(&dup, "duplicates"), a.duplicated);
        assert_eq!(nav_received(&dup), a.sensors_published + a.ranges_published + a.duplicated);
        assert_eq!(live_errors(&dup), live_errors(&clean));
    });
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn dropped_and_malformed_messages_are_counted_and_the_navigators_run_on() {
    in_private_netns("dropped_and_malformed_messages_are_counted_and_the_navigators_run_on", || {
        let tmp = tempfile::tempdir().unwrap();
        let clean = lockstep_live(tmp.path(), BusFaults::default(), None);
        let dropped = lockstep_live(tmp.path(), BusFaults { drop_every: 9, ..BusFaults::default() }, None);
        let bad = lockstep_live(tmp.path(), BusFaults { malformed_every: 13, ..BusFaults::default() }, None);
        let (d, m) = (dropped.auvs.as_ref().unwrap(), bad.auvs.as_ref().unwrap());
        assert!(d.dropped > 500 && m.malformed > 400, "{d:?} {m:?}");
        // What was dropped never arrived; what was spoiled arrived and was counted malformed.
        assert_eq!(nav_received(&dropped), d.sensors_published + d.ranges_published - d.dropped);
        assert_eq!(nav_sum(&dropped, "malformed"), 0);
        assert_eq!(nav_received(&bad), m.sensors_published + m.ranges_published);
        assert_eq!(nav_sum(&bad, "malformed"), m.malformed);
        let applied = |r: &SitlRun| nav_sum(r, "sensors_applied") + nav_sum(r, "ranges_applied");
        assert!(applied(&dropped) < applied(&clean) && applied(&bad) < applied(&clean));
        for run in [&dropped, &bad] {
            assert_ne!(live_errors(run), live_errors(&clean));
            assert!(run.result.fleet.error.mean < 3.0 * clean.result.fleet.error.mean + 5.0);
        }
    });
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn a_live_navigator_killed_and_restarted_mid_mission_resumes() {
    in_private_netns("a_live_navigator_killed_and_restarted_mid_mission_resumes", || {
        let tmp = tempfile::tempdir().unwrap();
        let restart = Restart { auv: 1, kill_at_s: 100.0, restart_at_s: 130.0 };
        let run = lockstep_live(tmp.path(), BusFaults::default(), Some(restart));
        let a = run.auvs.as_ref().unwrap();
        println!("{a:?}\n{:?}", run.auv_summaries[1]);
        assert_eq!(a.restarts, 1);
        // Thirty seconds of sensors at 10 Hz (and any range) were not sent to the dead process.
        assert!(a.withheld_while_down >= 299, "{a:?}");
        assert_eq!(run.auv_summaries[1].len(), 2);
        assert_eq!(run.auv_summaries[1][0]["killed"], true);
        let second = &run.auv_summaries[1][1];
        assert_eq!(second["sensors_applied"].as_u64().unwrap(), 1700, "{second}");
        assert_eq!(run.auv_logs[1].len(), 2);
        // After its restart and one reorder window, AUV 1 is scored on its own estimates again,
        // started from the vehicle's own navigation, and stays near its truth.
        let rows = &run.result.trace.as_ref().unwrap().rows;
        let after: Vec<_> = rows.iter().filter(|r| r.auv == 1 && r.t >= 135.5).collect();
        assert_eq!(after.len(), 165);
        assert_eq!(a.estimate_timeouts, 0, "{a:?}");
        assert!(after.iter().all(|r| r.error < 30.0), "{:?}", after.iter().map(|r| r.error).fold(0.0, f64::max));
        assert!(a.samples_on_older_estimate >= 30, "{a:?}");
    });
}

/// A free-running CNA that stops commanding at decision 5 (the test stops its clock) is reported
/// as one silence to the end of the mission; the CNA holds its last command and the run ends.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn a_free_running_world_reports_a_cna_that_stopped_commanding() {
    in_private_netns("a_free_running_world_reports_a_cna_that_stopped_commanding", || {
        let tmp = tempfile::tempdir().unwrap();
        let (file, sc) = shortened("default.toml", 450.0, tmp.path());
        let stopper = stop_clock_at_decision(URL, 5);
        let opts = options(&file, "planner", Pace::Warp(30.0), None);
        let run = run(&sc, "planner", &opts).unwrap();
        assert!(stopper.join().unwrap());
        let c = &run.counts;
        println!("{c:?}");
        assert_eq!((c.decisions, c.missed_decisions), (15, 9), "{c:?}");
        assert_eq!(c.silences, vec![[180.0, 420.0]]);
        assert_eq!(run.child_summary.unwrap()["decisions"], 6);
        assert!(run.result.fleet.error.mean.is_finite());
    });
}

/// The percentile `q` of `v` (linear between order statistics).
fn percentile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let x = q * (v.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    if i + 1 < v.len() {
        v[i] + f * (v[i + 1] - v[i])
    } else {
        v[i]
    }
}

/// The one-hour five-AUV mission at 30 × with live AUVs: no missed decision, and the fleet's
/// true error (on the live estimates) inside the 2.5–97.5 % range of 20 in-process runs of the
/// same file. The in-process runs go first, outside the namespace (they need no network), into
/// the test's own target directory.
#[test]
#[ignore = "one hour at 30 x (two minutes) and 20 in-process runs of a five-AUV mission: minutes"]
fn one_hour_five_auvs_at_warp_30_with_live_auvs_is_inside_the_in_process_spread() {
    let file = scenario_path("sitl-five-auvs.toml");
    let mc = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sitl-five-auvs-mc");
    let json = mc.join("comparison.json");
    if std::env::var_os("COOPNAV_LIVE_IN_NETNS").is_none() {
        let args = ["simulate", file.to_str().unwrap(), "--runs", "20", "--policy", "planner-estimator"];
        coopnav_ok(&[&args[..], &["-o", mc.to_str().unwrap(), "--force"]].concat(), Duration::from_secs(3600));
    }
    in_private_netns("one_hour_five_auvs_at_warp_30_with_live_auvs_is_inside_the_in_process_spread", || {
        let tmp = tempfile::tempdir().unwrap();
        let sitl = tmp.path().join("sitl");
        let said = coopnav_ok(
            &[
                "sitl",
                file.to_str().unwrap(),
                "--warp",
                "30",
                "--live-auvs",
                "--url",
                URL,
                "-o",
                sitl.to_str().unwrap(),
            ],
            Duration::from_secs(280),
        );
        println!("{said}");
        let read =
            |p: &Path| -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap() };
        let world = read(&sitl.join("sitl.json"));
        for key in ["world", "latencies", "live_auvs", "live_cna"] {
            println!("{key}: {}", world[key]);
        }
        for s in world["live_auv_summaries"].as_array().unwrap() {
            println!("{s}");
        }
        assert_eq!(world["world"]["decisions"], 120);
        assert_eq!(world["world"]["missed_decisions"], 0);
        assert_eq!(world["world"]["late_commands"], 0);
        let live_error = read(&sitl.join("summary.json"))["fleet"]["error"]["mean"].as_f64().unwrap();
        let errors = mc_fleet_errors(&read(&json));
        assert_eq!(errors.len(), 20);
        let (lo, hi) = (percentile(&errors, 0.025), percentile(&errors, 0.975));
        println!("live fleet error {live_error:.3} m; in-process 95 % range [{lo:.3}, {hi:.3}] m: {errors:?}");
        assert!(live_error >= lo && live_error <= hi, "{live_error} outside [{lo}, {hi}]");
    });
}

/// The fleet's mean error of every run in a Monte Carlo JSON.
fn mc_fleet_errors(mc: &serde_json::Value) -> Vec<f64> {
    let policies = if mc["policies"].is_array() { &mc["policies"] } else { &mc["comparison"]["policies"] };
    let runs = policies[0]["runs"].as_array().unwrap_or_else(|| panic!("no runs in {mc}"));
    runs.iter().map(|r| r.as_f64().expect("a run's fleet mean error")).collect()
}

/// A CSV file as rows of named columns.
fn csv(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(str::to_string)).collect()).collect()
}

/// `coopnav sitl --live-auvs` writes each navigator's log as a post-processing log; `hbl
/// postprocess` runs on it unchanged, and its forward filter is the live navigator's estimate at
/// every second the run scored (the run's timeseries), and its truth the world's.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn a_live_navigators_log_postprocesses_to_the_estimates_the_run_scored() {
    in_private_netns("a_live_navigators_log_postprocesses_to_the_estimates_the_run_scored", || {
        let tmp = tempfile::tempdir().unwrap();
        let (file, _) = shortened("default.toml", 300.0, tmp.path());
        let (sitl, post) = (tmp.path().join("sitl"), tmp.path().join("post"));
        let args = ["sitl", file.to_str().unwrap(), "--lockstep", "--live-auvs", "--policy", "planner", "--url", URL];
        println!("{}", coopnav_ok(&[&args[..], &["-o", sitl.to_str().unwrap()]].concat(), Duration::from_secs(200)));
        for name in ["cna.lcm", "auv0.lcm", "auv0.toml", "auv0.log", "auv0.post.toml", "summary.json", "run.alog"] {
            assert!(sitl.join(name).is_file(), "{name}");
        }
        let (log, cfg) = (sitl.join("auv2.log"), sitl.join("auv2.post.toml"));
        coopnav_ok(
            &[
                "hbl",
                "postprocess",
                log.to_str().unwrap(),
                "--config",
                cfg.to_str().unwrap(),
                "--out",
                post.to_str().unwrap(),
            ],
            Duration::from_secs(120),
        );
        let scored: Vec<_> = csv(&sitl.join("timeseries.csv")).into_iter().filter(|r| r["auv"] == "2").collect();
        let filtered = csv(&post.join("estimates.csv"));
        let f = |r: &std::collections::HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
        let mut matched = 0;
        for s in &scored {
            let t = f(s, "t");
            let Some(p) = filtered.iter().find(|p| (f(p, "t") - t).abs() < 1e-6) else { continue };
            assert!((f(p, "filt_e") - f(s, "est_x")).abs() < 1e-6, "t = {t}: {p:?} {s:?}");
            assert!((f(p, "filt_n") - f(s, "est_y")).abs() < 1e-6, "t = {t}: {p:?} {s:?}");
            assert_eq!((f(p, "true_e"), f(p, "true_n")), (f(s, "true_x"), f(s, "true_y")));
            matched += 1;
        }
        assert!(matched >= 295, "{matched} of {} seconds matched", scored.len());
    });
}

/// A software-in-the-loop run's LCM logs, imported with the world's truth: every decision the
/// CNA process logged is a COOPNAV_CNA_DECISION (the decision_t payloads read here with
/// coopnav-lcm's own reader), each AUV has a truth and an estimate track, and the post-processing
/// log and config equal, byte for byte, the ones `sitl` wrote from the same logs.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn a_sitl_runs_logs_import_with_truth_into_a_run_the_tools_read() {
    in_private_netns("a_sitl_runs_logs_import_with_truth_into_a_run_the_tools_read", || {
        use coopnav_lcm::messages::{Decision, Message};
        use coopnav_lcm::{LogReader, Schema};
        let tmp = tempfile::tempdir().unwrap();
        let (file, sc) = shortened("default.toml", 120.0, tmp.path());
        let (sitl, imported) = (tmp.path().join("sitl"), tmp.path().join("imported"));
        let args = ["sitl", file.to_str().unwrap(), "--lockstep", "--live-auvs", "--policy", "planner", "--url", URL];
        coopnav_ok(&[&args[..], &["-o", sitl.to_str().unwrap()]].concat(), Duration::from_secs(200));
        let n = sc.fleet.n_auvs;
        let mut logs = vec![sitl.join("cna.lcm").display().to_string()];
        logs.extend((0..n).map(|k| sitl.join(format!("auv{k}.lcm")).display().to_string()));
        let truth = sitl.join("timeseries.csv");
        let mut import: Vec<&str> = vec!["live", "import"];
        import.extend(logs.iter().map(String::as_str));
        import.extend(["--truth", truth.to_str().unwrap(), "-o", imported.to_str().unwrap()]);
        println!("{}", coopnav_ok(&import, Duration::from_secs(60)));

        let schema = Schema::coopnav();
        let cna_log = std::fs::File::open(sitl.join("cna.lcm")).unwrap();
        let mut seqs: Vec<i64> = LogReader::new(cna_log)
            .map(|e| e.unwrap())
            .filter(|e| e.channel == "COOPNAV_CNA_DECISION")
            .map(|e| Decision::decode(&schema, &e.data).unwrap().seq)
            .collect();
        seqs.sort();
        seqs.dedup();
        let world: serde_json::Value = serde_json::from_slice(&std::fs::read(sitl.join("sitl.json")).unwrap()).unwrap();
        assert_eq!(seqs.len() as u64, world["world"]["decisions"].as_u64().unwrap());
        assert!(seqs.len() >= 3, "{} decisions", seqs.len());
        let alog = coopnav_moos::read_alog_file(&imported.join("run.alog")).unwrap();
        let posted: Vec<i64> =
            alog.postings("COOPNAV_CNA_DECISION").map(|e| e.field("seq").unwrap().parse().unwrap()).collect();
        assert_eq!(posted, seqs);
        for k in 0..n {
            let reports =
                |name: String| alog.postings("NODE_REPORT").filter(|e| e.field("NAME") == Some(name.as_str())).count();
            assert!(reports(format!("auv{k}")) >= 115, "auv{k} truth");
            assert!(reports(format!("auv{k}_est")) >= 115, "auv{k} estimate");
            for name in [format!("auv{k}.log"), format!("auv{k}.post.toml")] {
                assert_eq!(
                    std::fs::read(imported.join(&name)).unwrap(),
                    std::fs::read(sitl.join(&name)).unwrap(),
                    "{name}"
                );
            }
        }
        assert!(alog.postings("VIEW_RANGE_PULSE").count() > 0 && alog.postings("VIEW_COMMS_PULSE").count() > 0);
        let scenario = alog.postings("COOPNAV_SCENARIO").next().unwrap();
        assert!(scenario.value.contains("truth from the simulated world"), "{}", scenario.value);
        coopnav_ok(&["view", imported.to_str().unwrap()], Duration::from_secs(60));
    });
}
