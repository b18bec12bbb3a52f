//! Work and memory are bounded before they are spent: each input that asks for
//! hours of work or gigabytes of memory is refused at once, exit 1, with a message naming the
//! fields, the estimate and `--allow-large`. Each probe's CPU time and peak memory are measured
//! from the kernel's accounting of the child (wait4).

mod common;

use common::{coopnav, edited_example, measured};
use std::path::Path;
use std::time::{Duration, Instant};

/// CPU seconds and peak resident memory one refused probe may use.
const MAX_CPU_S: f64 = 1.0;
const MAX_PEAK_KB: u64 = 100_000;
/// Wall time, generous for a loaded machine: the CPU bound above is the real check.
const MAX_WALL: Duration = Duration::from_secs(5);

/// Runs `coopnav ARGS` in `dir` and checks it is refused quickly and cheaply, naming `fields`:
/// its CPU time and peak memory as the kernel accounted them (wait4).
fn refused(dir: &Path, args: &[&str], fields: &[&str]) {
    let start = Instant::now();
    let (out, usage) = measured(dir, args);
    let wall = start.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(err.contains("too large to run") && err.contains("--allow-large"), "{args:?}: {err}");
    for field in fields {
        assert!(err.contains(field), "{args:?} does not name {field}: {err}");
    }
    assert!(wall < MAX_WALL, "{args:?} took {wall:?}");
    assert!(usage.cpu_s < MAX_CPU_S, "{args:?} used {} s CPU", usage.cpu_s);
    assert!(usage.peak_kb < MAX_PEAK_KB, "{args:?} peaked at {} kB", usage.peak_kb);
    assert!(!dir.join("out").exists(), "{args:?} wrote its output directory");
}

#[test]
fn plan_heading_options_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(
        tmp.path(),
        &["plan", "--example"],
        "s.toml",
        &[("heading_options = 5", "heading_options = 1000000000")],
    );
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["policy.planner.tree.heading_options", "planner leaves"]);
}

#[test]
fn plan_lanes_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["plan", "--example"], "s.toml", &[("lanes = 3", "lanes = 1000000000")]);
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["auv[0].lawnmower lanes", "track samples"]);
}

#[test]
fn plan_tau_1e_minus_6() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["plan", "--example"], "s.toml", &[("tau = 10.0", "tau = 0.000001")]);
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["platform.tau", "planner decisions"]);
}

#[test]
fn plan_look_ahead_16() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["plan", "--example"], "s.toml", &[("look_ahead = 4", "look_ahead = 16")]);
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["policy.planner.tree.look_ahead", "1.526e11"]);
}

#[test]
fn plan_with_1e5_auvs() {
    let tmp = tempfile::tempdir().unwrap();
    let example = String::from_utf8(coopnav(tmp.path(), &["plan", "--example"]).stdout).unwrap();
    let head = &example[..example.find("[[auv]]").unwrap()];
    let auv = r#"{ name = "a", lawnmower = { origin = [0.0, 0.0], lane_heading_compass_deg = 0.0, lane_length = 600.0, spacing = -50.0, lanes = 3, speed = 1.5, depth = { kind = "constant", depth = 90.0 } } }"#;
    let auvs = vec![auv; 100_000].join(",\n");
    std::fs::write(tmp.path().join("s.toml"), format!("{head}auv = [\n{auvs}\n]\n")).unwrap();
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["input file (bytes)", "s.toml"]);
}

#[test]
fn simulate_duration_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["simulate", "--example"], "s.toml", &[("duration_s = 3600.0", "duration_s = 1e9")]);
    refused(tmp.path(), &["simulate", "s.toml", "-o", "out"], &["duration_s / dt", "vehicle-steps"]);
}

#[test]
fn simulate_runs_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    refused(tmp.path(), &["simulate", "--runs", "1000000000", "-o", "out"], &["--runs", "vehicle-steps"]);
}

#[test]
fn simulate_lanes_and_heading_options_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["simulate", "--example"], "s.toml", &[("lanes = 6", "lanes = 1000000000")]);
    refused(tmp.path(), &["simulate", "s.toml", "-o", "out"], &["fleet.lanes"]);
    edited_example(
        tmp.path(),
        &["simulate", "--example"],
        "s.toml",
        &[("heading_options = 5", "heading_options = 1000000000")],
    );
    refused(tmp.path(), &["simulate", "s.toml", "-o", "out"], &["policy.planner.tree.heading_options"]);
}

#[test]
fn hbl_duration_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    let long = [("duration_s = 130.0", "duration_s = 1e9")];
    edited_example(tmp.path(), &["hbl", "example", "scenario"], "h.toml", &long);
    refused(tmp.path(), &["hbl", "simulate", "h.toml", "-o", "out"], &["duration_s / dt"]);
}

#[test]
fn hbl_montecarlo_runs_1e9() {
    let tmp = tempfile::tempdir().unwrap();
    refused(tmp.path(), &["hbl", "montecarlo", "--runs", "1000000000", "-o", "out"], &["--runs"]);
}

#[test]
fn hbl_grid_spacing_1mm() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("g.toml"), "spacing = 0.001\n").unwrap();
    refused(tmp.path(), &["hbl", "grid", "--grid", "g.toml", "-o", "out"], &["grid x, y, spacing", "grid cells"]);
}

#[test]
fn channel_step_1e_minus_6() {
    let tmp = tempfile::tempdir().unwrap();
    refused(tmp.path(), &["channel", "--step", "1e-6", "-o", "out"], &["--max-range / --step"]);
}

/// A relative-time log whose rows are 500 s apart (each silence under `max_gap_s`, so each is
/// predicted in `auv.step_s` pieces) over 11.6 days: 10⁷ filter steps, ≈ 13 GB of history.
#[test]
fn hbl_postprocess_log_spanning_11_days() {
    let tmp = tempfile::tempdir().unwrap();
    let rows: String = (1..=2000).map(|i| format!("{},speed,,1,,,\n", 500 * i)).collect();
    std::fs::write(tmp.path().join("log.csv"), format!("t,kind,src,v1,v2,v3,v4\n0,init,,0,0,1,90\n{rows}")).unwrap();
    refused(
        tmp.path(),
        &["hbl", "postprocess", "log.csv", "-o", "out"],
        &["memory of the filter history", "max_gap_s", "auv.step_s"],
    );
}

#[test]
fn allow_large_lifts_the_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let example = String::from_utf8(coopnav(tmp.path(), &["plan", "--example"]).stdout).unwrap();
    let padding = "# padding\n".repeat(110_000);
    std::fs::write(tmp.path().join("s.toml"), format!("{padding}{example}")).unwrap();
    refused(tmp.path(), &["plan", "s.toml", "-o", "out"], &["input file (bytes)"]);
    let out = coopnav(tmp.path(), &["plan", "s.toml", "-o", "out", "--allow-large"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// Devices and pipes are bounded as files are: every input goes through one bounded reader, so
/// an endless `/dev/zero` or a pipe larger than the limit is refused after the limit is read.
#[test]
fn endless_devices_and_large_pipes_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    refused(tmp.path(), &["simulate", "/dev/zero", "-o", "out"], &["input file (bytes)", "/dev/zero"]);
    refused(tmp.path(), &["plan", "/dev/zero", "-o", "out"], &["input file (bytes)", "/dev/zero"]);
    // A log may be as large as its parsed rows fit the memory limit: that much is read, no more.
    let (out, usage) = measured(tmp.path(), &["hbl", "postprocess", "/dev/zero", "-o", "out"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("post-processing log (bytes)") && err.contains("--allow-large"), "{err}");
    let limit_kb = (coopnav_sim::batch::work::max_postprocess_log_bytes() / 1024.0) as u64;
    assert!(
        usage.peak_kb < limit_kb + MAX_PEAK_KB,
        "read {} kB of an endless log (limit {limit_kb} kB)",
        usage.peak_kb
    );
    let fifo = tmp.path().join("big.toml");
    let path = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo touches nothing else.
    assert_eq!(unsafe { libc::mkfifo(path.as_ptr(), 0o600) }, 0, "mkfifo: {}", std::io::Error::last_os_error());
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            use std::io::Write;
            let mut pipe = std::fs::OpenOptions::new().write(true).open(&fifo).unwrap();
            let block = vec![b'#'; 1 << 16];
            // 3 MB, three times the limit; the reader closes the pipe once past the limit.
            (0..48).try_for_each(|_| pipe.write_all(&block)).is_err()
        })
    };
    refused(tmp.path(), &["simulate", "big.toml", "-o", "out"], &["input file (bytes)", "big.toml"]);
    assert!(writer.join().unwrap(), "the reader stopped before the whole 3 MB was written");
}

/// A Nams experiment's work is estimated like every other command's: 100 000 runs, or a
/// nanosecond vehicle step, is refused at once.
#[test]
fn nams_runs_and_timestep() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(tmp.path(), &["nams", "--example"], "runs.toml", &[("runs = 40", "runs = 100000")]);
    refused(tmp.path(), &["nams", "runs.toml", "-o", "out"], &["experiment.runs", "vehicle.timestep"]);
    edited_example(tmp.path(), &["nams", "--example"], "step.toml", &[("timestep = 0.1", "timestep = 1e-9")]);
    refused(tmp.path(), &["nams", "step.toml", "-o", "out"], &["vehicle.timestep"]);
    edited_example(tmp.path(), &["nams", "--example"], "shelf.toml", &[("\nspacing = 50.0", "\nspacing = 1e-3")]);
    refused(tmp.path(), &["nams", "shelf.toml", "-o", "out"], &["experiment.shelf", "spacing"]);
}

/// A shelf spacing of a millimetre asks for 1.6·10¹³ grid nodes: refused from the estimate,
/// before the grid is built.
#[test]
fn simulate_shelf_spacing_1mm() {
    let tmp = tempfile::tempdir().unwrap();
    let edits = [("# shelf = { shallow", "shelf = { shallow"), ("spacing = 50.0 }", "spacing = 1e-3 }")];
    edited_example(tmp.path(), &["simulate", "--example"], "s.toml", &edits);
    refused(tmp.path(), &["simulate", "s.toml", "-o", "out"], &["fleet.shelf", "spacing"]);
}
