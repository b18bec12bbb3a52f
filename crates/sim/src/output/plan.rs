//! The pre-deployment run directory: CNA waypoints (CSV and a MOOS-IvP waypoint-behaviour file,
//! compass headings at that boundary), time series (CSV), summary.json, manifest.json and SVG
//! plots (tracks; error and distance against time).

use crate::output::plot::{line_svg, track_svg, Labels, Series};
use crate::output::{Manifest, RunDir, WriteError};
use coopnav_core::CompassDeg;
use coopnav_plan::predeploy::metrics::StepRecord;
use coopnav_plan::predeploy::runner::RunResult;
use coopnav_plan::predeploy::Mission;
use serde::Serialize;
use std::fmt::Write;

#[derive(Serialize)]
struct WaypointRow {
    step: usize,
    t: f64,
    x: f64,
    y: f64,
    depth: f64,
    heading_compass_deg: f64,
    pitch_deg: f64,
}

#[derive(Serialize)]
struct StepRow {
    step: usize,
    t: f64,
    cna_x: f64,
    cna_y: f64,
    cna_depth: f64,
    cost: f64,
    penalised_cost: f64,
    max_error: f64,
    min_distance: f64,
    max_distance: f64,
    levels_searched: Option<usize>,
}

#[derive(Serialize)]
struct AuvRow<'a> {
    step: usize,
    t: f64,
    auv: &'a str,
    x: f64,
    y: f64,
    z: f64,
    sigma: f64,
    epsilon: f64,
    error: f64,
    distance: f64,
}

/// Writes the whole run into `dir` and moves it into place.
pub fn write_run(
    dir: RunDir,
    mission: &Mission,
    inputs: serde_json::Value,
    result: &RunResult,
) -> Result<std::path::PathBuf, WriteError> {
    let steps = &result.steps;
    dir.write_csv(
        "cna_waypoints.csv",
        steps[1..].iter().map(|s| WaypointRow {
            step: s.step,
            t: s.t,
            x: s.cna.pos.x,
            y: s.cna.pos.y,
            depth: s.cna.pos.z,
            heading_compass_deg: CompassDeg::from(s.cna.heading).0,
            pitch_deg: s.cna.pitch.to_degrees(),
        }),
    )?;
    dir.write_text("cna_waypoints.moos", &moos_points(mission, result))?;
    dir.write_csv(
        "timeseries.csv",
        steps.iter().map(|s| StepRow {
            step: s.step,
            t: s.t,
            cna_x: s.cna.pos.x,
            cna_y: s.cna.pos.y,
            cna_depth: s.cna.pos.z,
            cost: s.cost,
            penalised_cost: s.penalised_cost,
            max_error: s.errors.iter().map(|e| e.total()).fold(0.0, f64::max),
            min_distance: s.distance.iter().cloned().fold(f64::INFINITY, f64::min),
            max_distance: s.distance.iter().cloned().fold(0.0, f64::max),
            levels_searched: s.step.checked_sub(1).map(|i| result.decisions[i].levels_searched),
        }),
    )?;
    dir.write_csv(
        "auv_timeseries.csv",
        steps.iter().flat_map(|s| {
            (0..s.errors.len()).map(move |k| AuvRow {
                step: s.step,
                t: s.t,
                auv: &mission.names[k],
                x: s.auv[k].x,
                y: s.auv[k].y,
                z: s.auv[k].z,
                sigma: s.errors[k].sigma2.sqrt(),
                epsilon: s.errors[k].eps2.sqrt(),
                error: s.errors[k].total(),
                distance: s.distance[k],
            })
        }),
    )?;
    dir.write_json("summary.json", &result.summary)?;
    dir.write_json("manifest.json", &Manifest::new("plan", None, inputs))?;
    write_plots(&dir, mission, result)?;
    crate::output::moos_export::write_moos_files(&dir, &crate::output::moos_export::plan_run(mission, result))?;
    Ok(dir.finish()?)
}

/// `points = x,y:x,y:…` for BHV_Waypoint, with speed and the leg headings (compass) as comments.
fn moos_points(mission: &Mission, result: &RunResult) -> String {
    let wps = &result.steps[1..];
    let mut s = String::new();
    let _ = writeln!(s, "// coopnav plan: CNA waypoints for the MOOS-IvP waypoint behaviour (BHV_Waypoint).");
    let _ = writeln!(
        s,
        "// One waypoint every tau = {} s. Headings are compass degrees (0 = north, clockwise).",
        mission.planner.motion.tau
    );
    let heads: Vec<String> = wps.iter().map(|w| format!("{:.1}", CompassDeg::from(w.cna.heading).0)).collect();
    let _ = writeln!(s, "// leg headings: {}", heads.join(", "));
    let pts: Vec<String> = wps.iter().map(|w| format!("{:.1},{:.1}", w.cna.pos.x, w.cna.pos.y)).collect();
    let _ = writeln!(s, "speed = {}", mission.planner.motion.speed);
    let _ = writeln!(s, "points = {}", pts.join(":"));
    s
}

fn write_plots(dir: &RunDir, mission: &Mission, result: &RunResult) -> Result<(), WriteError> {
    let steps = &result.steps;
    let n = mission.names.len();
    // Each vehicle in its one colour (coopnav_moos::palette), as the closed-loop plots and the replay draw it.
    let mut tracks = vec![Series::new("CNA", steps.iter().map(|s| (s.cna.pos.x, s.cna.pos.y)).collect()).cna()];
    let per_auv = |f: &dyn Fn(usize, &StepRecord) -> (f64, f64)| -> Vec<Series> {
        (0..n)
            .map(|k| Series::new(mission.names[k].clone(), steps.iter().map(|s| f(k, s)).collect()).colour(k))
            .collect()
    };
    tracks.extend(per_auv(&|k, s| (s.auv[k].x, s.auv[k].y)));
    dir.write_text(
        "tracks.svg",
        &track_svg(Labels { title: "CNA and survey AUV tracks", x: "x east (m)", y: "y north (m)" }, &tracks)?,
    )?;
    let errors = per_auv(&|k, s| (s.t, s.errors[k].total()));
    dir.write_text(
        "error.svg",
        &line_svg(
            Labels { title: "Modelled survey-AUV position error", x: "time (s)", y: "error sqrt(sigma^2 + eps^2) (m)" },
            &errors,
        )?,
    )?;
    let mut dist = per_auv(&|k, s| (s.t, s.distance[k]));
    let (t0, t1) = (steps[0].t, steps[steps.len() - 1].t);
    let limit = |name: &str, d: f64| Series::new(name, vec![(t0, d), (t1, d)]).reference();
    dist.push(limit("min limit", mission.planner.limits.min));
    dist.push(limit("max limit", mission.planner.limits.max).dashed());
    dir.write_text(
        "distance.svg",
        &line_svg(Labels { title: "CNA to survey AUV distance", x: "time (s)", y: "3-D distance (m)" }, &dist)?,
    )?;
    Ok(())
}
