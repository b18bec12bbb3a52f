//! MOOS-IvP output end to end: the `run.alog` of simulate, plan and hbl runs read back with
//! coopnav's alog reader and checked against the run's own CSVs, `coopnav view` on good and bad
//! run directories, and the replay page opened in a real headless Chromium.

use coopnav_moos::{read_alog_file, Alog, AlogEntry};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn coopnav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).env("RUST_BACKTRACE", "0").output().expect("run coopnav")
}

fn succeed(args: &[&str]) {
    let o = coopnav(args);
    assert!(o.status.success(), "coopnav {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// A 300 s closed-loop run with the default fleet, written to `dir/sim`.
fn short_simulation(dir: &Path) -> PathBuf {
    let example = coopnav(&["simulate", "--example"]);
    let text = String::from_utf8(example.stdout).unwrap();
    let short: String = text
        .lines()
        .map(|l| if l.starts_with("duration_s") { "duration_s = 300.0".to_string() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    let scenario = dir.join("short.toml");
    std::fs::write(&scenario, short).unwrap();
    let out = dir.join("sim");
    succeed(&["simulate", scenario.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    out
}

/// The AUV-CNA library file (its CNA surfaces for GPS fixes once its σ passes 3 m), 1,200 s, in
/// `dir/auv-cna`.
fn short_auv_cna_simulation(dir: &Path) -> PathBuf {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/sloping-auv-cna.toml");
    let text = std::fs::read_to_string(file).unwrap();
    // A cruise depth of its own: the file's "cast" depth for 3 AUVs is the surface, where the CNA
    // would never change depth.
    for line in ["duration_s = 3600.0", "depth = \"cast\""] {
        assert!(text.contains(line), "the library file's `{line}` moved");
    }
    let short = text.replace("duration_s = 3600.0", "duration_s = 1200.0").replace("depth = \"cast\"", "depth = 10.0");
    let scenario = dir.join("auv-cna.toml");
    std::fs::write(&scenario, short).unwrap();
    let out = dir.join("auv-cna");
    succeed(&["simulate", scenario.to_str().unwrap(), "--policy", "centroid-standoff", "-o", out.to_str().unwrap()]);
    out
}

/// A CSV file as rows of named fields.
fn csv_rows(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(String::from)).collect()).collect()
}

fn num(row: &HashMap<String, String>, key: &str) -> f64 {
    row[key].parse().unwrap_or_else(|_| panic!("{key} = {:?}", row[key]))
}

fn field(e: &AlogEntry, key: &str) -> f64 {
    e.field(key).unwrap_or_else(|| panic!("no {key} in {}", e.value)).parse().unwrap()
}

/// The NODE_REPORT key of vehicle `name` at a time-series row's time.
fn at_row(name: &str, row: &HashMap<String, String>) -> (String, i64) {
    (name.to_string(), (num(row, "t") * 1000.0).round() as i64)
}

/// NODE_REPORTs by (NAME, time in ms).
fn reports(log: &Alog) -> HashMap<(String, i64), &AlogEntry> {
    log.postings("NODE_REPORT")
        .map(|e| ((e.field("NAME").unwrap().to_string(), (e.time * 1000.0).round() as i64), e))
        .collect()
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

/// An AUV CNA's NODE_REPORTs carry its true depth: cruising, climbing and at the surface.
#[test]
fn an_auv_cnas_alog_depth_is_its_true_depth() {
    let tmp = tempfile::tempdir().unwrap();
    let run = short_auv_cna_simulation(tmp.path());
    let log = read_alog_file(&run.join("run.alog")).unwrap();
    let by_key = reports(&log);
    let rows = csv_rows(&run.join("timeseries.csv"));
    let mut depths = Vec::new();
    for row in rows.iter().filter(|r| r["auv"] == "0") {
        let cna = by_key[&at_row("cna", row)];
        close(field(cna, "DEP"), num(row, "cna_z"), 5e-4, "cna depth");
        depths.push(num(row, "cna_z"));
    }
    let (shallowest, deepest) = depths.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &z| (lo.min(z), hi.max(z)));
    assert!(shallowest < 0.5 && deepest > 9.5, "the CNA cruises at 10 m and surfaces: {shallowest}..{deepest} m");
}

#[test]
fn the_simulate_alog_holds_every_vehicle_track_of_the_time_series() {
    let tmp = tempfile::tempdir().unwrap();
    let run = short_simulation(tmp.path());
    let log = read_alog_file(&run.join("run.alog")).unwrap();
    let by_key = reports(&log);
    let rows = csv_rows(&run.join("timeseries.csv"));
    assert!(rows.len() >= 3 * 299, "{} rows", rows.len());
    for row in &rows {
        let auv = format!("auv{}", num(row, "auv") as usize);
        let truth = by_key.get(&at_row(&auv, row)).unwrap_or_else(|| panic!("no report of {auv} at {}", row["t"]));
        let estimate = by_key[&at_row(&format!("{auv}_est"), row)];
        let cna = by_key[&at_row("cna", row)];
        // The alog keeps millimetres.
        close(field(truth, "X"), num(row, "true_x"), 5e-4, "true x");
        close(field(truth, "Y"), num(row, "true_y"), 5e-4, "true y");
        close(field(truth, "DEP"), num(row, "true_z"), 5e-4, "depth");
        close(field(estimate, "X"), num(row, "est_x"), 5e-4, "estimated x");
        close(field(estimate, "Y"), num(row, "est_y"), 5e-4, "estimated y");
        close(field(estimate, "NAV_SD"), num(row, "est_sd"), 5e-4, "filter sigma");
        for (alog, csv) in [("NAV_PEE", "p_ee"), ("NAV_PEN", "p_en"), ("NAV_PNN", "p_nn")] {
            close(field(estimate, alog), num(row, csv), 5e-5 + 1e-9 * num(row, csv).abs(), "filter covariance");
        }
        close(field(cna, "X"), num(row, "cna_x"), 5e-4, "cna x");
        close(field(cna, "Y"), num(row, "cna_y"), 5e-4, "cna y");
        close(field(cna, "DEP"), 0.0, 0.0, "a surface craft's depth");
        assert_eq!((truth.field("GROUP"), estimate.field("GROUP")), (Some("truth"), Some("estimate")));
    }
    let vehicles = 2 * 3 + 1;
    assert_eq!(by_key.len(), rows.len() / 3 * vehicles, "one report per vehicle per second, nothing else");
    let comms = csv_rows(&run.join("comms.csv"));
    let pulses = |variable, direction| {
        let fates = |lost: bool| {
            let logged = log.postings(variable).filter(|e| (e.field("msg") == Some("lost")) == lost).count();
            let recorded =
                comms.iter().filter(|c| c["direction"] == direction && (c["received"] == "false") == lost).count();
            (logged, recorded)
        };
        (fates(false), fates(true))
    };
    let ((down_rx, down_rx_csv), (down_lost, down_lost_csv)) = pulses("VIEW_RANGE_PULSE", "down");
    assert_eq!((down_rx, down_lost), (down_rx_csv, down_lost_csv), "range pulses = broadcasts, fates kept");
    let ((up_rx, up_rx_csv), (up_lost, up_lost_csv)) = pulses("VIEW_COMMS_PULSE", "up");
    assert_eq!((up_rx, up_lost), (up_rx_csv, up_lost_csv), "comms pulses = status packets, fates kept");
    assert!(down_rx > 0 && up_rx > 0);
    // Every CNA decision (τ = 30 s) that steers for a point is a leg starting where the CNA was.
    let legs: Vec<&AlogEntry> = log.postings("VIEW_SEGLIST").collect();
    assert!((5..=11).contains(&legs.len()), "{} legs in 300 s", legs.len());
    for leg in legs.iter().filter(|l| l.time >= 1.0) {
        let pts = leg.value.split_once("pts={").unwrap().1.split_once('}').unwrap().0;
        let start: Vec<f64> = pts.split(':').next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
        let cna = by_key[&("cna".to_string(), (leg.time * 1000.0).round() as i64)];
        // Each side is the same position rounded: VIEW_SEGLIST to 0.01 m, NODE_REPORT to 0.001 m.
        let rounding = 0.005 + 0.0005 + 1e-9;
        close(start[0], field(cna, "X"), rounding, "leg start x");
        close(start[1], field(cna, "Y"), rounding, "leg start y");
    }
    let report = std::fs::read_to_string(run.join("report.html")).unwrap();
    assert!(report.contains("<a href=\"replay.html\">"), "report.html links the replay");
    assert!(run.join("replay.html").is_file());
}

#[test]
fn the_plan_alog_flies_the_planned_waypoints_as_legs() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("plan");
    succeed(&["plan", "-o", run.to_str().unwrap()]);
    let log = read_alog_file(&run.join("run.alog")).unwrap();
    let waypoints = csv_rows(&run.join("cna_waypoints.csv"));
    let legs: Vec<&AlogEntry> = log.postings("VIEW_SEGLIST").collect();
    assert_eq!(legs.len(), waypoints.len());
    for (i, (leg, wp)) in legs.iter().zip(&waypoints).enumerate() {
        let pts = leg.value.split_once("pts={").unwrap().1.split_once('}').unwrap().0;
        let end: Vec<f64> = pts.split(':').nth(1).unwrap().split(',').map(|v| v.parse().unwrap()).collect();
        close(end[0], num(wp, "x"), 5e-3, "leg end x");
        close(end[1], num(wp, "y"), 5e-3, "leg end y");
        close(end[2], num(wp, "depth"), 5e-3, "leg end depth");
        assert!(leg.time < num(wp, "t"), "a leg is chosen before it is flown");
        if i > 0 {
            close(leg.time, num(&waypoints[i - 1], "t"), 1e-3, "a leg starts at the previous waypoint");
        }
    }
    let by_key = reports(&log);
    for wp in &waypoints {
        let cna = by_key[&("cna".to_string(), (num(wp, "t") * 1000.0).round() as i64)];
        close(field(cna, "X"), num(wp, "x"), 5e-4, "cna x at its waypoint time");
        close(field(cna, "Y"), num(wp, "y"), 5e-4, "cna y at its waypoint time");
    }
}

#[test]
fn the_hbl_alog_has_the_auv_truth_and_estimate() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("hbl");
    succeed(&["hbl", "simulate", "--seed", "4", "--out", run.to_str().unwrap()]);
    let log = read_alog_file(&run.join("run.alog")).unwrap();
    let by_key = reports(&log);
    let trace = csv_rows(&run.join("trace.csv"));
    let mut checked = 0;
    for row in trace.iter().filter(|r| num(r, "t").fract().abs() < 1e-9) {
        let at = |name: &str| by_key[&(name.to_string(), (num(row, "t") * 1000.0).round() as i64)];
        close(field(at("auv0"), "X"), num(row, "auv_e"), 5e-4, "auv east");
        close(field(at("auv0_est"), "Y"), num(row, "est_n"), 5e-4, "estimate north");
        close(field(at("cna"), "X"), num(row, "ship_e"), 5e-4, "ship east");
        checked += 1;
    }
    assert!(checked > 100, "{checked} whole-second rows");
}

#[test]
fn view_rewrites_the_replay_and_refuses_bad_run_directories() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("plan");
    succeed(&["plan", "-o", run.to_str().unwrap()]);
    std::fs::remove_file(run.join("replay.html")).unwrap();
    succeed(&["view", run.to_str().unwrap()]);
    assert!(std::fs::read_to_string(run.join("replay.html")).unwrap().contains("\"command\":\"plan\""));

    let not_a_dir = run.join("summary.json");
    let o = coopnav(&["view", not_a_dir.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("is not a directory"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );

    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = coopnav(&["view", empty.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("has no run.alog"), "{err}");
    assert_eq!(std::fs::read_dir(&empty).unwrap().count(), 0, "nothing written");

    let broken = tmp.path().join("broken");
    std::fs::create_dir(&broken).unwrap();
    std::fs::write(broken.join("run.alog"), "%% LOGSTART 0\n0.0 NODE_REPORT coopnav NAME=a,X=1,Y=2\nbad line\n")
        .unwrap();
    let o = coopnav(&["view", broken.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("run.alog") && err.contains("line 3"), "{err}");
    assert!(!broken.join("replay.html").exists(), "nothing written");
}

/// Chromium, as crates/cli/build.rs found it (the test is ignored when it did not).
fn chromium() -> PathBuf {
    PathBuf::from(option_env!("COOPNAV_CHROMIUM_FOUND").expect("build.rs sets it with cfg chromium_installed"))
}

/// Loads `page#fragment` headless; `extra` picks the output (`--dump-dom`, `--screenshot=…`).
fn headless(chromium: &Path, profile: &Path, url: &str, extra: &[&str]) -> Output {
    let profile = format!("--user-data-dir={}", profile.display());
    let mut args = vec![
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        profile.as_str(),
        "--virtual-time-budget=3000",
        "--window-size=1000,1200",
        "--enable-logging=stderr",
        "--v=0",
    ];
    args.extend_from_slice(extra);
    args.push(url);
    Command::new(chromium).args(&args).output().expect("run chromium")
}

/// The `data-x`/`data-y` of the positions-table row of `name` in a dumped DOM.
fn drawn_position(dom: &str, name: &str) -> (f64, f64) {
    let row = &dom[dom.find(&format!("id=\"pos-{name}\"")).unwrap_or_else(|| panic!("no row for {name}"))..];
    let attr = |a: &str| -> f64 {
        let start = row.find(&format!("{a}=\"")).unwrap() + a.len() + 2;
        row[start..start + row[start..].find('"').unwrap()].parse().unwrap()
    };
    (attr("data-x"), attr("data-y"))
}

#[test]
#[cfg_attr(not(chromium_installed), ignore = "Chromium is not installed: run scripts/install-chromium.sh")]
fn the_replay_shows_the_run_positions_in_a_real_browser() {
    let chromium = chromium();
    let tmp = tempfile::tempdir().unwrap();
    let run = short_simulation(tmp.path());
    let rows = csv_rows(&run.join("timeseries.csv"));
    let mut ids: Vec<usize> = rows.iter().map(|r| num(r, "auv") as usize).collect();
    ids.sort_unstable();
    ids.dedup();
    let auvs = ids.len();
    assert!(auvs >= 2, "the example has a team: {auvs} AUVs in the time series");
    let page = format!("file://{}", run.join("replay.html").display());
    for t in [1.0, 60.0, 150.0, 299.0] {
        let profile = tempfile::tempdir().unwrap();
        let o = headless(&chromium, profile.path(), &format!("{page}#t={t}"), &["--dump-dom"]);
        let dom = String::from_utf8_lossy(&o.stdout);
        let console = String::from_utf8_lossy(&o.stderr);
        assert!(dom.contains("data-status=\"ready\""), "the page did not finish painting at t = {t}:\n{console}");
        assert!(dom.contains("<pre id=\"problems\"></pre>"), "the page reported errors");
        // Chromium logs every console message (and uncaught exception) as `…:CONSOLE…`; the page writes none.
        let messages: Vec<&str> = console.lines().filter(|l| l.contains(":CONSOLE")).collect();
        assert!(messages.is_empty(), "console messages at t = {t}:\n{}", messages.join("\n"));
        assert!(dom.contains(&format!("<span id=\"time\">{t:.1}</span>")), "the slider is not at {t}");
        // The CSV's times are sums of steps (60.00000000000001): matched to within a microsecond,
        // far below the step, and every AUV's row must be found.
        let at_t: Vec<_> = rows.iter().filter(|r| (num(r, "t") - t).abs() < 1e-6).collect();
        assert_eq!(at_t.len(), auvs, "rows at t = {t}");
        for row in at_t {
            let auv = format!("auv{}", num(row, "auv") as usize);
            // The page keeps 0.1 m.
            let (x, y) = drawn_position(&dom, &auv);
            close(x, num(row, "true_x"), 0.051, &format!("{auv} x at {t}"));
            close(y, num(row, "true_y"), 0.051, &format!("{auv} y at {t}"));
            let (x, y) = drawn_position(&dom, &format!("{auv}_est"));
            close(x, num(row, "est_x"), 0.051, &format!("{auv}_est x at {t}"));
            close(y, num(row, "est_y"), 0.051, &format!("{auv}_est y at {t}"));
            let (x, y) = drawn_position(&dom, "cna");
            close(x, num(row, "cna_x"), 0.051, &format!("cna x at {t}"));
            close(y, num(row, "cna_y"), 0.051, &format!("cna y at {t}"));
        }
    }
    let shots = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("replay-browser");
    std::fs::create_dir_all(&shots).unwrap();
    let shot = shots.join("replay-t150.png");
    let profile = tempfile::tempdir().unwrap();
    let o =
        headless(&chromium, profile.path(), &format!("{page}#t=150"), &[&format!("--screenshot={}", shot.display())]);
    assert!(
        o.status.success() && std::fs::metadata(&shot).map_or(0, |m| m.len()) > 10_000,
        "no screenshot at {}",
        shot.display()
    );
    eprintln!("screenshot: {}", shot.display());
}

#[test]
#[cfg_attr(not(chromium_installed), ignore = "Chromium is not installed: run scripts/install-chromium.sh")]
fn the_replay_draws_auv_k_in_the_plots_colour_k_beyond_ten_auvs() {
    let chromium = chromium();
    let tmp = tempfile::tempdir().unwrap();
    let text = String::from_utf8(coopnav(&["simulate", "--example"]).stdout).unwrap();
    let eleven: String = text
        .lines()
        .map(|l| match l {
            l if l.starts_with("duration_s") => "duration_s = 120.0".to_string(),
            l if l.starts_with("n_auvs") => "n_auvs = 11".to_string(),
            // Twelve slots of 5 s, each holding a packet's air time and travel, and a turn rate
            // that keeps a decision's turns under 180 degrees.
            l if l.starts_with("tau ") => "tau = 60.0".to_string(),
            l if l.starts_with("max_turn_rate_deg_s") => "max_turn_rate_deg_s = 2.0".to_string(),
            l => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let scenario = tmp.path().join("eleven.toml");
    std::fs::write(&scenario, eleven).unwrap();
    let run = tmp.path().join("sim");
    succeed(&["simulate", scenario.to_str().unwrap(), "--policy", "none", "-o", run.to_str().unwrap()]);
    let profile = tempfile::tempdir().unwrap();
    let page = format!("file://{}#t=30", run.join("replay.html").display());
    let dom = String::from_utf8_lossy(&headless(&chromium, profile.path(), &page, &["--dump-dom"]).stdout).to_string();
    assert!(dom.contains("data-status=\"ready\""), "the page did not finish painting");
    // The legend's entry of each AUV and its colour. The alog's names sort
    // auv0, auv1, auv10, auv2, ...; the plots draw auvK in colour K of the eight.
    let legend_colour = |name: &str| -> String {
        let entry = dom.find(&format!("● {name} ")).unwrap_or_else(|| panic!("no legend entry of {name}"));
        let style = &dom[dom[..entry].rfind("style=\"").unwrap()..entry];
        style.split("color:").nth(1).unwrap().split([';', '"']).next().unwrap().trim().to_string()
    };
    for (name, rgb) in
        [("auv0", "#0072b2"), ("auv2", "#009e73"), ("auv7", "#999933"), ("auv9", "#d55e00"), ("auv10", "#009e73")]
    {
        assert_eq!(legend_colour(name), rgb, "{name}");
    }
}

/// Drives the replay's map the way a person does, with the browser's own mouse and wheel events
/// dispatched to the page's handlers: the wheel zooms about the cursor, a drag pans, a click picks
/// the vehicle under it and shows its state, and following a vehicle keeps it at the centre as
/// time moves. What each action did is read back from the page's own pixel positions.
const DRIVE_THE_MAP: &str = r#"<pre id="test-out"></pre>
<script>
(() => {
  const map = document.getElementById("map"), r = map.getBoundingClientRect();
  const [left, top] = [r.left + map.clientLeft, r.top + map.clientTop];
  const row = (n) => document.getElementById("pos-" + n);
  const px = (n) => [Number(row(n).dataset.px), Number(row(n).dataset.py)];
  const mouse = (target, type, X, Y) =>
    target.dispatchEvent(new MouseEvent(type, { bubbles: true, clientX: left + X, clientY: top + Y, button: 0 }));
  const out = {};
  out.a0 = px("auv0"); out.b0 = px("auv1");
  const wheel = new WheelEvent("wheel", { bubbles: true, cancelable: true, clientX: left + out.a0[0], clientY: top + out.a0[1], deltaY: -500 });
  // Where the event is, as the browser keeps it (whole CSS pixels), in the canvas's pixels.
  out.cursor = [wheel.clientX - left, wheel.clientY - top];
  map.dispatchEvent(wheel);
  out.zoom = Number(map.dataset.zoom); out.a1 = px("auv0"); out.b1 = px("auv1");
  mouse(map, "mousedown", 100, 100); mouse(map, "mousemove", 120, 90); mouse(map, "mousemove", 140, 70); mouse(map, "mouseup", 140, 70);
  out.b2 = px("auv1");
  const cna = px("cna").map(Math.round);
  mouse(map, "mousedown", cna[0], cna[1]); mouse(map, "mouseup", cna[0], cna[1]);
  const picked = document.getElementById("picked");
  out.picked = picked.dataset.name; out.pickedText = picked.textContent;
  out.cnaRow = [row("cna").dataset.x, row("cna").dataset.y, row("cna").className];
  const follow = document.getElementById("follow");
  follow.value = "auv1"; follow.dispatchEvent(new Event("change"));
  out.f0 = px("auv1"); out.w0 = [row("auv1").dataset.x, row("auv1").dataset.y];
  const slider = document.getElementById("slider");
  slider.value = 250; slider.dispatchEvent(new Event("input"));
  out.f1 = px("auv1"); out.w1 = [row("auv1").dataset.x, row("auv1").dataset.y];
  out.size = [map.width, map.height];
  document.getElementById("test-out").textContent = JSON.stringify(out);
})();
</script>
"#;

#[test]
#[cfg_attr(not(chromium_installed), ignore = "Chromium is not installed: run scripts/install-chromium.sh")]
fn the_replay_zooms_pans_picks_and_follows_in_a_real_browser() {
    let chromium = chromium();
    let tmp = tempfile::tempdir().unwrap();
    let run = short_simulation(tmp.path());
    let page = std::fs::read_to_string(run.join("replay.html")).unwrap();
    let driven = tmp.path().join("driven.html");
    let at = page.rfind("</body>").expect("the page ends its body");
    std::fs::write(&driven, format!("{}{DRIVE_THE_MAP}{}", &page[..at], &page[at..])).unwrap();
    let profile = tempfile::tempdir().unwrap();
    let o = headless(&chromium, profile.path(), &format!("file://{}#t=150", driven.display()), &["--dump-dom"]);
    let dom = String::from_utf8_lossy(&o.stdout);
    let console = String::from_utf8_lossy(&o.stderr);
    assert!(dom.contains("data-status=\"ready\""), "the page did not finish painting:\n{console}");
    let messages: Vec<&str> = console.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(messages.is_empty(), "console messages:\n{}", messages.join("\n"));
    let start = dom.find("<pre id=\"test-out\">").expect("the driver's output") + "<pre id=\"test-out\">".len();
    let text = &dom[start..start + dom[start..].find("</pre>").unwrap()];
    let out: serde_json::Value =
        serde_json::from_str(&text.replace("&amp;", "&")).unwrap_or_else(|e| panic!("{e}: {text}"));
    let pair = |k: &str| -> (f64, f64) {
        let v = &out[k];
        let n = |i: usize| v[i].as_f64().or_else(|| v[i].as_str().and_then(|s| s.parse().ok())).unwrap();
        (n(0), n(1))
    };
    let near = |got: (f64, f64), want: (f64, f64), tol: f64, what: &str| {
        assert!((got.0 - want.0).abs() <= tol && (got.1 - want.1).abs() <= tol, "{what}: {got:?}, want {want:?}");
    };
    // The wheel (deltaY −500) over auv0 zooms in about the cursor: the pixel under it stays, and
    // every other point moves away from it by the zoom.
    let zoom = out["zoom"].as_f64().unwrap();
    assert!((2.0..2.3).contains(&zoom), "zoom {zoom}");
    let (c, a0, b0, a1, b1) = (pair("cursor"), pair("a0"), pair("b0"), pair("a1"), pair("b1"));
    let zoomed = |p: (f64, f64)| (c.0 + zoom * (p.0 - c.0), c.1 + zoom * (p.1 - c.1));
    near(a1, zoomed(a0), 0.15, "auv0, under the cursor");
    near(b1, zoomed(b0), 0.15, "auv1");
    assert!((b0.0 - a0.0).hypot(b0.1 - a0.1) > 5.0, "the two AUVs are apart on the map: {a0:?} {b0:?}");
    // The drag moved everything by (+40, −30) pixels.
    let b2 = pair("b2");
    near((b2.0 - b1.0, b2.1 - b1.1), (40.0, -30.0), 0.15, "the pan");
    // The click on the CNA picked it: its state below the map, its row marked.
    assert_eq!(out["picked"].as_str(), Some("cna"), "{out}");
    let (cx, cy) = pair("cnaRow");
    let shown = out["pickedText"].as_str().unwrap();
    assert!(shown.starts_with("cna (cna) at t = 150.0 s"), "{shown}");
    assert!(shown.contains(&format!("x {cx:.1} m, y {cy:.1} m")), "{shown} against the row's {cx}, {cy}");
    assert_eq!(out["cnaRow"][2].as_str(), Some("picked"));
    // Following auv1 centres it, and keeps it centred when the time moves on, as it moves.
    let centre = (out["size"][0].as_f64().unwrap() / 2.0, out["size"][1].as_f64().unwrap() / 2.0);
    near(pair("f0"), centre, 0.15, "auv1 followed at t = 150");
    near(pair("f1"), centre, 0.15, "auv1 followed at t = 250");
    let (w0, w1) = (pair("w0"), pair("w1"));
    assert!((w1.0 - w0.0).hypot(w1.1 - w0.1) > 20.0, "auv1 moved between the two times: {w0:?} {w1:?}");
}

/// The Python that has pymoos2, as crates/cli/build.rs found it (the test is ignored when it did not).
fn pymoos_python() -> PathBuf {
    PathBuf::from(option_env!("COOPNAV_PYMOOS_FOUND").expect("build.rs sets it with cfg pymoos_installed"))
}

/// Reads the mission files with pymoos2: the .moos with its MissionReader (globals and each
/// ProcessConfig block), every BHV_Waypoint `points` of the .bhv with its XYSegList parser.
const PYMOOS_READ: &str = r#"
import json, sys
from pymoos2.core.MissionReader import MissionReader
from pymoos2.dtos.geometry.XYSegList import XYSegList
moos, bhv = sys.argv[1], sys.argv[2]
apps = ["ANTLER", "uSimMarine", "pHelmIvP", "pMarinePIDV22", "pNodeReporter", "pLogger"]
runs = []
for line in open(bhv):
    line = line.split("//")[0].strip()
    if line.startswith("points"):
        seg = XYSegList.from_spec("pts={" + line.split("=", 1)[1].strip() + "}")
        runs.append([[x, y] for x, y in zip(seg.vx, seg.vy)])
print(json.dumps({
    "globals": MissionReader(moos).get_all_globals(),
    "configs": {app: MissionReader(moos, app).get_config_list() for app in apps},
    "runs": runs,
}))
"#;

/// The depth each BHV_ConstantDepth holds, in file order.
fn constant_depths(bhv: &str) -> Vec<f64> {
    bhv.split("Behavior = ")
        .filter(|b| b.starts_with("BHV_ConstantDepth"))
        .map(|b| {
            b.lines()
                .find_map(|l| l.trim().strip_prefix("depth"))
                .unwrap()
                .trim_start_matches([' ', '='])
                .parse()
                .unwrap()
        })
        .collect()
}

#[test]
#[cfg_attr(not(pymoos_installed), ignore = "pymoos2 is not installed: run scripts/install-pymoos.sh")]
fn plan_mission_files_parse_with_pymoos2_and_fly_the_planned_points() {
    let python = pymoos_python();
    let tmp = tempfile::tempdir().unwrap();
    let example = String::from_utf8(coopnav(&["plan", "--example"]).stdout).unwrap();
    let auv = tmp.path().join("auv.toml");
    let auv_example = example.replace("cna = { kind = \"asc\" }", "cna = { kind = \"auv\", pitch_options = 3 }");
    assert_ne!(auv_example, example, "the example names its CNA kind");
    std::fs::write(&auv, auv_example).unwrap();
    for (is_auv, scenario) in [(false, None), (true, Some(auv.to_str().unwrap()))] {
        let run = tmp.path().join(if is_auv { "auv" } else { "asc" });
        let mut args = vec!["plan", "--moos", "--moos-origin", "47.6,-122.3", "-o", run.to_str().unwrap()];
        args.extend(scenario);
        succeed(&args);
        let o = Command::new(&python)
            .args(["-c", PYMOOS_READ, run.join("cna.moos").to_str().unwrap(), run.join("cna.bhv").to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let read: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let globals = &read["globals"];
        assert_eq!((globals["ServerPort"].as_str(), globals["Community"].as_str()), (Some("9000"), Some("cna")));
        let lat: f64 = globals["LatOrigin"].as_str().unwrap().parse().unwrap();
        let lon: f64 = globals["LongOrigin"].as_str().unwrap().parse().unwrap();
        assert_eq!((lat, lon), (47.6, -122.3));
        let configs = &read["configs"];
        assert_eq!(configs["pHelmIvP"]["behaviors"], "cna.bhv");
        assert_eq!(configs["uSimMarine"]["start_pos"], "x=140.00,y=0.00,heading=90.0,speed=0,depth=0.00");
        assert_eq!(configs["pMarinePIDV22"]["depth_control"], if is_auv { "true" } else { "false" });
        assert_eq!(configs["pNodeReporter"]["platform_type"], if is_auv { "UUV" } else { "SHIP" });
        assert!(configs["ANTLER"]["run"].as_str().is_some() && configs["pLogger"]["file"] == "LOG_CNA");

        let waypoints = csv_rows(&run.join("cna_waypoints.csv"));
        let runs: Vec<Vec<[f64; 2]>> = serde_json::from_value(read["runs"].clone()).unwrap();
        let flown: Vec<[f64; 2]> = runs.iter().flatten().copied().collect();
        assert_eq!(flown.len(), waypoints.len(), "every planned waypoint is flown once");
        for (p, wp) in flown.iter().zip(&waypoints) {
            close(p[0], num(wp, "x"), 0.005, "waypoint x");
            close(p[1], num(wp, "y"), 0.005, "waypoint y");
        }
        let bhv = std::fs::read_to_string(run.join("cna.bhv")).unwrap();
        let depths = constant_depths(&bhv);
        if is_auv {
            assert_eq!(depths.len(), runs.len(), "one depth per run of waypoints");
            let mut planned = waypoints.iter();
            for (points, depth) in runs.iter().zip(&depths) {
                for wp in planned.by_ref().take(points.len()) {
                    close(num(wp, "depth"), *depth, 0.1, "the run's depth is its waypoints' depth");
                }
            }
            assert!(depths.iter().any(|d| *d > 1.0), "the AUV CNA dives: {depths:?}");
        } else {
            assert!(depths.is_empty() && runs.len() == 1, "an ASC flies one behaviour at the surface");
        }
        assert_eq!(bhv.matches("// leg ").count(), waypoints.len(), "every leg's timing is a comment");
    }
}
