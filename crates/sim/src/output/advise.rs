//! The run directory of `coopnav advise`: one self-contained page (`advice.html`) with the
//! recommendation, its margin and paired CI, every candidate's expected per-AUV mean and p95 true
//! error and a map of where in the survey the error peaks (`error-map.svg`); the plan to fly
//! (`plan/`: the CNA's `cna.moos` and `cna.bhv` for pAntler with uSimMarine and pMarineViewer,
//! each survey AUV's `auvN.bhv`, and every waypoint in `waypoints.csv`); `advice.json` and
//! `manifest.json`.

use crate::batch::advise::{Advice, ErrorMap};
use crate::output::{Manifest, RunDir, WriteError};
use crate::scenario::world::Scenario;
use coopnav_core::{CompassDeg, Heading, LatLon, LocalFrame};
use coopnav_moos::mission::EXAMPLE_ORIGIN_DEG;
use coopnav_moos::{mission_files, MissionSpec, Waypoint};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The page's file name.
pub const PAGE: &str = "advice.html";
/// The map's file name.
pub const MAP: &str = "error-map.svg";

/// The map's colour at `f` in [0, 1]: the shared colour-blind-safe sequential scale (viridis).
fn colour(f: f64) -> String {
    coopnav_moos::palette::hex(coopnav_moos::palette::sequential(f))
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The error map of the recommended candidate, with the survey paths, the CNA's path and the
/// peak cell marked.
pub fn map_svg(sc: &Scenario, map: &ErrorMap, cna_path: &[(f64, f64)]) -> String {
    let (w, h, pad, bar) = (560.0, 560.0, 56.0, 70.0);
    let side = map.cell_m * map.nx as f64;
    let scale = (w - 2.0 * pad) / side;
    let px = |x: f64| pad + (x - map.x0) * scale;
    let py = |y: f64| h - pad - (y - map.y0) * scale;
    let means = map.means();
    let (lo, hi) = means.iter().flatten().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &m| (a.0.min(m), a.1.max(m)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{h}" viewBox="0 0 {} {h}" font-family="sans-serif" font-size="13">"#,
        w + bar,
        w + bar
    );
    let _ = write!(s, r##"<rect width="100%" height="100%" fill="#ffffff"/>"##);
    for (k, m) in means.iter().enumerate() {
        let Some(m) = m else { continue };
        let (i, j) = (k % map.nx, k / map.nx);
        let (x, y) = (map.x0 + i as f64 * map.cell_m, map.y0 + (j + 1) as f64 * map.cell_m);
        let c = map.cell_m * scale;
        let _ = write!(
            s,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.2}" height="{:.2}" fill="{}"><title>{:.2} m</title></rect>"#,
            px(x),
            py(y),
            c + 0.3,
            c + 0.3,
            colour((m - lo) / span),
            m
        );
    }
    for k in 0..sc.fleet.n_auvs {
        let pts: Vec<String> =
            sc.lawnmower(k).waypoints().iter().map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1))).collect();
        let _ = write!(s, r##"<polyline points="{}" fill="none" stroke="#000000" stroke-width="1"/>"##, pts.join(" "));
    }
    if !cna_path.is_empty() {
        let pts: Vec<String> = cna_path.iter().map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1))).collect();
        let _ = write!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#d55e00" stroke-width="1.5" stroke-dasharray="5 3"/>"##,
            pts.join(" ")
        );
    }
    if let Some(((x, y), m)) = map.peak() {
        let _ = write!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="{:.1}" fill="none" stroke="#cc79a7" stroke-width="3"/><text x="{:.1}" y="{:.1}" fill="#000000">peak {:.2} m</text>"##,
            px(x),
            py(y),
            (map.cell_m * scale).max(8.0),
            px(x) + 10.0,
            py(y) - 10.0,
            m
        );
    }
    // Axes: east and north, m, labelled at the frame's corners.
    let _ = write!(
        s,
        r##"<rect x="{pad}" y="{pad}" width="{:.1}" height="{:.1}" fill="none" stroke="#444444"/>"##,
        w - 2.0 * pad,
        h - 2.0 * pad
    );
    for (x, y, anchor, text) in [
        (pad, h - pad + 18.0, "middle", format!("{:.0}", map.x0)),
        (w - pad, h - pad + 18.0, "middle", format!("{:.0} m east", map.x0 + side)),
        (4.0, h - pad - 4.0, "start", format!("{:.0}", map.y0)),
        (4.0, pad - 8.0, "start", format!("{:.0} m north", map.y0 + side)),
    ] {
        let _ = write!(s, r#"<text x="{x:.1}" y="{y:.1}" text-anchor="{anchor}">{}</text>"#, esc(&text));
    }
    // Colour bar.
    let (bx, by, bh) = (w + 10.0, pad, h - 2.0 * pad);
    for i in 0..50 {
        let f = i as f64 / 49.0;
        let _ = write!(
            s,
            r#"<rect x="{bx:.1}" y="{:.1}" width="16" height="{:.2}" fill="{}"/>"#,
            by + (1.0 - f) * (bh - bh / 50.0),
            bh / 50.0 + 0.5,
            colour(f)
        );
    }
    let _ = write!(s, r#"<text x="{:.1}" y="{:.1}">{:.2} m</text>"#, bx, by - 8.0, hi);
    let _ = write!(s, r#"<text x="{:.1}" y="{:.1}">{:.2} m</text>"#, bx, by + bh + 18.0, lo);
    s.push_str("</svg>\n");
    s
}

/// A survey path as a MOOS-IvP behaviour file.
fn auv_bhv(name: &str, points: &[(f64, f64)], speed: f64) -> String {
    let pts: Vec<String> = points.iter().map(|p| format!("{:.2},{:.2}", p.0, p.1)).collect();
    format!(
        "// coopnav advise: survey AUV {name}'s path for pHelmIvP, local metres about the .moos LatOrigin/LongOrigin.\n\
         initialize DEPLOY = true\n\nBehavior = BHV_Waypoint\n{{\n  name      = {name}_survey\n  pwt       = 100\n  \
         condition = DEPLOY = true\n  speed     = {speed}\n  points    = {}\n}}\n",
        pts.join(":")
    )
}

/// Writes `advice` for `sc` into `dir` and finishes it.
pub fn write_advice(dir: RunDir, sc: &Scenario, advice: &Advice, command: &str) -> Result<PathBuf, WriteError> {
    let inputs = serde_json::json!({ "scenario": sc, "advise": advice.spec });
    dir.write_json("manifest.json", &Manifest::new(command, Some(sc.seed), inputs))?;
    dir.write_json("advice.json", advice)?;
    let best = &advice.candidates[advice.recommended];
    let svg = map_svg(sc, &best.map, &advice.cna_path);
    dir.write_text(MAP, &svg)?;
    // The plan to fly.
    let origin = sc.site.origin.map_or_else(
        || LatLon::new(EXAMPLE_ORIGIN_DEG.0, EXAMPLE_ORIGIN_DEG.1).expect("the example origin is valid"),
        |o| o.latlon(),
    );
    let frame = sc.site.origin.map(LocalFrame::new);
    let start = crate::scenario::start::cna_start(sc);
    let heading_to =
        |a: (f64, f64), b: (f64, f64)| CompassDeg::from(Heading::from_radians((b.1 - a.1).atan2(b.0 - a.0))).0;
    let mut prev = (start.pos.x, start.pos.y);
    let waypoints: Vec<Waypoint> = advice
        .cna_path
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, &p)| {
            let w = Waypoint {
                t: i as f64 * best.tau,
                x: p.0,
                y: p.1,
                depth: start.pos.z,
                heading_compass_deg: heading_to(prev, p),
            };
            prev = p;
            w
        })
        .collect();
    let files = mission_files(&MissionSpec {
        community: "cna".into(),
        server_port: 9000,
        origin,
        speed: sc.cna.speed,
        auv: sc.cna.auv.is_some(),
        start: Waypoint {
            t: 0.0,
            x: start.pos.x,
            y: start.pos.y,
            depth: start.pos.z,
            heading_compass_deg: CompassDeg::from(start.heading).0,
        },
        waypoints,
        capture_radius_m: 5.0,
    });
    dir.write_text(&format!("plan/{}", files.moos_name), &files.moos)?;
    dir.write_text(&format!("plan/{}", files.bhv_name), &files.bhv)?;
    let mut csv = String::from("vehicle,index,x,y,lat,lon\n");
    let mut row = |who: &str, i: usize, p: (f64, f64)| {
        let ll = frame.as_ref().and_then(|f| f.from_plane(p.0, p.1).ok());
        let (lat, lon) = ll
            .map_or((String::new(), String::new()), |l| (format!("{:.8}", l.lat_deg()), format!("{:.8}", l.lon_deg())));
        let _ = writeln!(csv, "{who},{i},{:.2},{:.2},{lat},{lon}", p.0, p.1);
    };
    for (i, &p) in advice.cna_path.iter().enumerate() {
        row("cna", i, p);
    }
    for k in 0..sc.fleet.n_auvs {
        let name = format!("auv{k}");
        let pts = sc.lawnmower(k).waypoints();
        for (i, &p) in pts.iter().enumerate() {
            row(&name, i, p);
        }
        dir.write_text(&format!("plan/{name}.bhv"), &auv_bhv(&name, &pts, sc.fleet.speed))?;
    }
    dir.write_text("plan/waypoints.csv", &csv)?;
    dir.write_text(PAGE, &page(sc, advice, &svg, origin, command))?;
    Ok(dir.finish()?)
}

fn page(sc: &Scenario, a: &Advice, svg: &str, origin: LatLon, command: &str) -> String {
    let best = &a.candidates[a.recommended];
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>coopnav advice</title><style>\
         body{{font-family:sans-serif;max-width:980px;margin:2em auto;font-size:15px;color:#111}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #999;padding:3px 8px;text-align:right}}\
         th{{background:#eee}}td:first-child,th:first-child{{text-align:left}}.best{{background:#e8f1fa}}\
         </style></head><body>\n<h1>Where the CNA should drive, and how good the navigation will be</h1>\n"
    );
    let _ = writeln!(h, "<p id=\"recommendation\"><b>Recommendation: {}</b>.", esc(&best.label));
    let c = &a.confirmed.mean_error;
    let _ = write!(
        h,
        " Expected fleet mean true error {:.2} m (95 % CI {:.2} to {:.2} m) over {} runs on seed {}, which the choice never saw.",
        c.mean,
        c.low,
        c.high,
        a.confirmed.runs.len(),
        a.seed.wrapping_add(1)
    );
    match &a.margin {
        Some(m) if m.decided => {
            let _ = write!(
                h,
                " <span id=\"margin\">It beats the runner-up, {}, by {:.2} m (paired 95 % CI {:.2} to {:.2} m).</span>",
                esc(&m.runner_up),
                -m.difference.mean,
                -m.difference.high,
                -m.difference.low
            );
        }
        Some(m) => {
            let _ = write!(
                h,
                " <span id=\"margin\">Undecided against the runner-up, {}: difference {:.2} m, paired 95 % CI {:.2} to {:.2} m includes zero; more runs (--runs) may separate them.</span>",
                esc(&m.runner_up),
                m.difference.mean,
                m.difference.low,
                m.difference.high
            );
        }
        None => {
            let _ = write!(h, " <span id=\"margin\">It was the only candidate.</span>");
        }
    }
    h.push_str("</p>\n");
    let _ = writeln!(
        h,
        "<p>Errors are the survey AUVs' <b>true</b> horizontal navigation errors (estimate against truth), sampled every second of the simulated mission; \
         p95 is the 95th percentile of an AUV's error over its mission. Candidates were chosen on {} runs each of seed {}; \
         mission {} s, {} survey AUVs.</p>",
        a.spec.runs,
        a.seed,
        sc.duration_s,
        sc.fleet.n_auvs
    );
    h.push_str("<h2>Every candidate</h2>\n<table id=\"candidates\"><tr><th>candidate</th><th>fleet mean [m]</th><th>95 % CI [m]</th>");
    for k in 0..sc.fleet.n_auvs {
        let _ = write!(h, "<th>auv{k} mean</th><th>auv{k} p95</th>");
    }
    h.push_str("</tr>\n");
    let mut order: Vec<usize> = (0..a.candidates.len()).collect();
    order.sort_by(|&x, &y| a.candidates[x].mean_error.mean.total_cmp(&a.candidates[y].mean_error.mean));
    for i in order {
        let r = &a.candidates[i];
        let class = if i == a.recommended { " class=\"best\"" } else { "" };
        let _ = write!(
            h,
            "<tr{class}><td>{}</td><td>{:.2}</td><td>{:.2} to {:.2}</td>",
            esc(&r.label),
            r.mean_error.mean,
            r.mean_error.low,
            r.mean_error.high
        );
        for (m, p) in r.auv_mean.iter().zip(&r.auv_p95) {
            let _ = write!(h, "<td>{m:.2}</td><td>{p:.2}</td>");
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    if !a.skipped.is_empty() {
        h.push_str("<p>Settings left out (the scenario's schedule does not fit them):</p><ul>");
        for s in &a.skipped {
            let _ = write!(h, "<li>{}</li>", esc(s));
        }
        h.push_str("</ul>\n");
    }
    h.push_str("<h2>Where in the survey the error peaks</h2>\n");
    let _ = writeln!(
        h,
        "<p>Mean true error of the recommended candidate in each cell the survey AUVs crossed (all its choosing runs); \
         black: the survey paths; dashed orange: the CNA's path in the first confirming run; circled: the peak cell.</p>\n<div id=\"map\">{svg}</div>"
    );
    h.push_str("<h2>The plan to fly</h2>\n<ul>");
    let _ = write!(
        h,
        "<li><code>plan/cna.moos</code>, <code>plan/cna.bhv</code>: the CNA's path for pHelmIvP, with uSimMarine and pMarineViewer \
         (<code>pAntler plan/cna.moos</code>); LatOrigin {:.6}, LongOrigin {:.6}.</li>",
        origin.lat_deg(),
        origin.lon_deg()
    );
    h.push_str("<li><code>plan/auvN.bhv</code>: each survey AUV's path.</li><li><code>plan/waypoints.csv</code>: every waypoint, in local metres and latitude/longitude.</li></ul>\n");
    let _ = writeln!(h, "<p><small>{}</small></p></body></html>", esc(command));
    h
}
