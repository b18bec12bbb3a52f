//! The memory estimate of a recorded closed-loop run (`coopnav_sim::batch::work::recorded_run_bytes`)
//! against the peak resident memory the kernel measured for `simulate`. Alone in its test binary:
//! a child's peak as wait4 reports it starts from its parent's at the exec, so the parent must be
//! small beside what it measures.

mod common;

use common::{coopnav, measured};
use std::path::Path;

/// This process's own peak resident memory, kB (what a child's measured peak starts from).
fn own_peak_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// The memory estimate of a recorded run is what `simulate` really holds: within 2x of the peak
/// resident memory the kernel measured, for short and long missions and small and large fleets.
#[test]
fn the_recorded_run_estimate_is_within_twice_the_measured_peak() {
    let tmp = tempfile::tempdir().unwrap();
    for (n, duration) in [(1, 2000.0), (1, 20_000.0), (5, 5000.0), (5, 40_000.0)] {
        let example = String::from_utf8(coopnav(tmp.path(), &["simulate", "--example"]).stdout).unwrap();
        let text = example.replacen("duration_s = 3600.0", &format!("duration_s = {duration:.1}"), 1).replacen(
            "n_auvs = 3",
            &format!("n_auvs = {n}"),
            1,
        );
        assert!(text.contains(&format!("n_auvs = {n}")) && text.contains(&format!("duration_s = {duration:.1}")));
        std::fs::write(tmp.path().join("m.toml"), &text).unwrap();
        let sc = coopnav_sim::scenario::Scenario::parse(&text, Path::new("m.toml")).unwrap();
        let estimate = coopnav_sim::batch::work::closed_loop(&sc, 1, 1)
            .into_iter()
            .find(|e| e.what == "memory of one recorded run (bytes)")
            .expect("the estimate is made")
            .value;
        let (out, usage) =
            measured(tmp.path(), &["simulate", "m.toml", "--policy", "centroid", "-o", "run", "--force"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let peak = usage.peak_kb as f64 * 1024.0;
        let inherited = own_peak_kb();
        assert!(usage.peak_kb > 2 * inherited, "the test process ({inherited} kB) is too large to measure a child");
        assert!(
            estimate <= 2.0 * peak && peak <= 2.0 * estimate,
            "{n} AUVs, {duration} s: estimated {:.0} MB, peak {:.0} MB",
            estimate / 1e6,
            peak / 1e6
        );
    }
}
