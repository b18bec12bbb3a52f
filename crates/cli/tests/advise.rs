//! `coopnav advise` end to end: the library's geographic survey (a `.bhv` lawnmower pair about a
//! MOOS origin, over an ESRI grid in degrees) runs through the candidates' Monte Carlo to one page
//! with a recommendation, an error map and the MOOS files to fly; and the page loads in a real
//! Chromium (ignored, with the reason, when it is absent).

mod common;

use common::{coopnav, copy_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the advice on a 5-minute look at the survey, 2 runs per candidate; its run directory.
fn advised(tmp: &Path) -> PathBuf {
    let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    std::fs::copy(lib.join("geographic-survey.toml"), tmp.join("survey.toml")).unwrap();
    copy_dir(&lib.join("site"), &tmp.join("site"));
    let args = [
        "advise",
        "survey.toml",
        "--runs",
        "2",
        "--duration",
        "300",
        "--policy",
        "planner-estimator,none",
        "-o",
        "adv",
    ];
    let out = coopnav(tmp, &args);
    assert!(out.status.success(), "advise failed: {}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("recommended: ") && stdout.contains("adv/advice.html"), "{stdout}");
    tmp.join("adv")
}

fn mean(v: &[serde_json::Value]) -> f64 {
    v.iter().map(|x| x.as_f64().unwrap()).sum::<f64>() / v.len() as f64
}

#[test]
fn a_bhv_survey_in_lat_lon_over_a_grid_gets_a_recommendation_a_map_and_a_plan() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = advised(tmp.path());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("advice.json")).unwrap()).unwrap();
    let cands = json["candidates"].as_array().unwrap();
    assert_eq!(cands.len(), 2, "two policies under the scenario's one setting");
    // The recommendation is the candidate with the lowest mean of its runs' fleet errors.
    let means: Vec<f64> = cands.iter().map(|c| mean(c["runs"].as_array().unwrap())).collect();
    let best = (0..means.len()).min_by(|&a, &b| means[a].total_cmp(&means[b])).unwrap();
    assert_eq!(json["recommended"].as_u64().unwrap() as usize, best, "{means:?}");
    for c in cands {
        assert_eq!(c["runs"].as_array().unwrap().len(), 2);
        assert_eq!(c["auv_mean"].as_array().unwrap().len(), 2, "two survey AUVs from the .bhv");
        let (m, p) = (c["auv_mean"][0].as_f64().unwrap(), c["auv_p95"][0].as_f64().unwrap());
        assert!(m > 0.0 && p >= m, "an AUV's p95 is at least its mean: {m} {p}");
    }
    // The margin is measured on the confirming seed, paired with the runner-up.
    let margin = &json["margin"];
    let runner = margin["runner_up"].as_str().unwrap();
    assert_eq!(margin["seed"].as_u64(), Some(json["seed"].as_u64().unwrap() + 1));
    let d = &margin["difference"];
    assert!(d["low"].as_f64().unwrap() <= d["mean"].as_f64().unwrap(), "{d}");
    assert_eq!(margin["decided"].as_bool().unwrap(), d["high"].as_f64().unwrap() < 0.0);
    let label = cands[best]["label"].as_str().unwrap();
    let page = std::fs::read_to_string(dir.join("advice.html")).unwrap();
    assert!(page.contains(&format!("<b>Recommendation: {label}</b>")), "{page}");
    assert!(page.contains(runner), "the page names the runner-up");
    for c in cands {
        assert!(page.contains(c["label"].as_str().unwrap()), "every candidate has its row");
    }
    assert!(
        page.contains("<th>auv0 mean</th>")
            && page.contains("<th>auv1 p95</th>")
            && !page.contains("<th>auv2 ")
            && page.contains("<svg"),
        "per-AUV columns (auv0 and auv1) and the inline map"
    );
    let map = std::fs::read_to_string(dir.join("error-map.svg")).unwrap();
    assert!(map.contains("peak ") && map.matches("<polyline").count() >= 3, "paths, CNA path and peak");
    // The plan to fly: MOOS files with a simulator and a viewer, at the site's origin.
    let moos = std::fs::read_to_string(dir.join("plan/cna.moos")).unwrap();
    for needle in [
        "Run = uSimMarine",
        "Run = pMarineViewer",
        "ProcessConfig = pMarineViewer",
        "LatOrigin    = 43.65000000",
        "behaviors = cna.bhv",
    ] {
        assert!(moos.contains(needle), "cna.moos lacks {needle:?}:\n{moos}");
    }
    let bhv = std::fs::read_to_string(dir.join("plan/cna.bhv")).unwrap();
    assert!(bhv.contains("Behavior = BHV_Waypoint") && bhv.contains("points"), "{bhv}");
    // Survey AUV 0 (auv0, as everywhere) flies the .bhv's first lawnmower, now about the site origin: its first point is
    // (−706.75, 655.53) m (crates/sim/tests/site.rs computes it by hand).
    let auv = std::fs::read_to_string(dir.join("plan/auv0.bhv")).unwrap();
    let pts = auv.lines().find_map(|l| l.trim().strip_prefix("points    = ")).unwrap();
    let first: Vec<f64> = pts.split(':').next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    assert!((first[0] + 706.75).abs() < 0.25 && (first[1] - 655.53).abs() < 0.25, "{first:?}");
    let csv = std::fs::read_to_string(dir.join("plan/waypoints.csv")).unwrap();
    let row = csv.lines().find(|l| l.starts_with("auv0,0,")).unwrap();
    let f: Vec<&str> = row.split(',').collect();
    // Back on the Earth: MOOS local (100, 100) about (43.655, −70.21).
    let (lat, lon): (f64, f64) = (f[4].parse().unwrap(), f[5].parse().unwrap());
    assert!((lat - 43.655900).abs() < 3e-6 && (lon + 70.208760).abs() < 3e-6, "{row}");
}

#[test]
fn a_bad_candidate_list_is_refused_before_any_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = coopnav(tmp.path(), &["advise", "--runs", "1", "-o", "adv"]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("runs = 1") && e.contains(">= 2"), "{e}");
    let out = coopnav(tmp.path(), &["advise", "--policy", "nonsense", "-o", "adv"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("nonsense"));
    assert!(!tmp.path().join("adv").exists(), "nothing written");
}

#[test]
#[cfg_attr(not(chromium_installed), ignore = "Chromium is not installed: run scripts/install-chromium.sh")]
fn the_advice_page_loads_in_a_real_browser() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = advised(tmp.path());
    let chromium =
        PathBuf::from(option_env!("COOPNAV_CHROMIUM_FOUND").expect("build.rs sets it with cfg chromium_installed"));
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            &format!("--user-data-dir={}", profile.path().display()),
            "--virtual-time-budget=2000",
            "--enable-logging=stderr",
            "--v=0",
            "--dump-dom",
            &format!("file://{}", dir.join("advice.html").display()),
        ])
        .output()
        .expect("run chromium");
    let dom = String::from_utf8_lossy(&out.stdout);
    let console = String::from_utf8_lossy(&out.stderr);
    assert!(dom.contains("id=\"recommendation\"") && dom.contains("Recommendation: "), "{dom}");
    assert!(dom.contains("<div id=\"map\"><svg"), "the map is parsed as inline SVG");
    let messages: Vec<&str> = console.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(messages.is_empty(), "console messages:\n{}", messages.join("\n"));
}
