//! `coopnav bench generated-mission` flies the generalization study's missions as the study does:
//! its run of each policy is run 0 of `coopnav simulate` on the file `coopnav generate` writes.

mod common;

use common::coopnav;

/// Mission 7 of the study's generator file (N = 2, 73 min), two policies: the benchmark's fleet
/// error of each is, bit for bit, run 0 of `simulate --runs 1` on the generated file, and its
/// figures per mission-hour are its CPU and wall seconds over the mission's hours.
#[test]
fn the_generated_mission_bench_flies_the_studys_run_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let ranges =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/generators/generalization.toml");
    let out = coopnav(tmp.path(), &["generate", ranges.to_str().unwrap(), "--missions", "8", "-o", "g"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let policies = "none,zigzag";
    let sim = coopnav(tmp.path(), &["simulate", "g/mission-007.toml", "--runs", "1", "--policy", policies, "--json"]);
    assert!(sim.status.success(), "{}", String::from_utf8_lossy(&sim.stderr));
    let mc: serde_json::Value = serde_json::from_slice(&sim.stdout).unwrap();

    let bench = coopnav(tmp.path(), &["bench", "generated-mission", "--missions", "7", "--policy", policies]);
    assert!(bench.status.success(), "{}", String::from_utf8_lossy(&bench.stderr));
    let json: serde_json::Value = serde_json::from_slice(&bench.stdout).unwrap();
    assert_eq!(json["target"], "generated-mission");
    let missions = json["missions"].as_array().unwrap();
    assert_eq!(missions.len(), 1);
    let mission = &missions[0];
    assert_eq!(mission["mission"], 7);
    assert_eq!(mission["n_auvs"], 2);
    let hours = mission["mission_h"].as_f64().unwrap();
    assert!((hours - 73.0 / 60.0).abs() < 1e-12, "{hours}");
    let rows = mission["policies"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, name) in rows.iter().zip(policies.split(',')) {
        assert_eq!(row["policy"], name);
        let simulated = mc["policies"].as_array().unwrap().iter().find(|p| p["policy"] == name).unwrap();
        assert_eq!(row["fleet_mean_true_error_m"], simulated["runs"][0], "{name}");
        let (cpu, wall) = (row["cpu_s"].as_f64().unwrap(), row["wall_s"].as_f64().unwrap());
        assert!(cpu > 0.0 && wall > 0.0, "{row}");
        // serde_json (without its `float_roundtrip` feature) may read a number back 1 ulp off, so
        // a quotient of numbers read back is compared to within a few ulps.
        let ulps = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs();
        let (cpu_h, wall_h) =
            (row["cpu_s_per_mission_hour"].as_f64().unwrap(), row["wall_s_per_mission_hour"].as_f64().unwrap());
        assert!(ulps(cpu_h, cpu / hours), "{cpu_h} against {}", cpu / hours);
        assert!(ulps(wall_h, wall / hours), "{wall_h} against {}", wall / hours);
    }
}
