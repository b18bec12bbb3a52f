//! Runs with a time axis as MOOS-IvP sees them: each run type's recorded trace, read without
//! changing it, becomes a [`RunLog`] (survey AUVs' truth `auvN` and estimate `auvN_est`, the CNA
//! `cna`, ranges and packets as pulses, planned legs), written into the run directory as
//! `run.alog` (mapping: `coopnav_moos::export`) with its interactive `replay.html`.

use crate::observe::metrics::RunResult as ClosedLoopResult;
use crate::output::record::PassRow;
use crate::output::{RunDir, WriteError};
use crate::scenario;
use coopnav_core::{CompassDeg, LatLon, LocalFrame, Vec3};
use coopnav_moos::{
    mission_files, replay, write_run_alog, Leg, MissionFiles, MissionSpec, Pulse, PulseKind, Role, RunLog, Sample,
    Vehicle, Waypoint, SIMULATED_LOG_START,
};
use coopnav_plan::predeploy::{Mission, RunResult as PlanResult};
use coopnav_plan::{CnaKind, CnaPose};

/// The alog every run directory with a time axis holds.
pub const ALOG_FILE: &str = "run.alog";

/// Writes `run` as `run.alog` and `replay.html` into `dir`.
pub fn write_moos_files(dir: &RunDir, run: &RunLog) -> Result<(), WriteError> {
    let alog = write_run_alog(run, ALOG_FILE, SIMULATED_LOG_START, Vec::new())?;
    let html = replay::from_alog_bytes(&alog)?;
    dir.write_bytes(ALOG_FILE, &alog)?;
    dir.write_text(replay::FILE, &html)?;
    Ok(())
}

fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

fn sample(t: f64, x: f64, y: f64, depth: f64) -> Sample {
    Sample { t, x, y, depth, sd: None, cov: None }
}

/// A closed-loop estimate with the filter's σ and horizontal covariance (drawn as ellipses).
fn estimate_sample(r: &crate::engine::TraceRow) -> Sample {
    Sample { sd: Some(r.est_sd), cov: Some([r.p_ee, r.p_en, r.p_nn]), ..sample(r.t, r.est_x, r.est_y, r.true_z) }
}

fn vehicle(name: String, role: Role, kind: &'static str, samples: Vec<Sample>) -> Vehicle {
    Vehicle { name, role, kind, samples }
}

/// Survey AUV `k` of a closed-loop or plan run, numbered from 0 as in the terminal, the report
/// and the CSVs.
pub fn auv_name(k: usize) -> String {
    format!("auv{k}")
}

/// A closed-loop mission (`simulate`): every AUV's truth and estimate (with the filter's 1σ)
/// every second, the CNA, CNA broadcasts as range pulses and AUV status packets as comms pulses.
/// Every CNA decision that steers for a point is a leg (VIEW_SEGLIST).
pub fn closed_loop_run(sc: &scenario::Scenario, result: &ClosedLoopResult) -> Result<RunLog, WriteError> {
    let trace = result.trace.as_ref().ok_or(WriteError::NotRecorded)?;
    let mut vehicles = Vec::new();
    for k in 0..sc.fleet.n_auvs {
        let rows = || trace.rows.iter().filter(move |r| r.auv == k);
        let truth = rows().map(|r| sample(r.t, r.true_x, r.true_y, r.true_z)).collect();
        let estimate = rows().map(estimate_sample).collect();
        vehicles.push(vehicle(auv_name(k), Role::Truth, "auv", truth));
        vehicles.push(vehicle(format!("{}_est", auv_name(k)), Role::Estimate, "auv", estimate));
    }
    // An AUV CNA's true depth (it dives and surfaces); a ship's transducer depth is not its DEP.
    let cna_kind = if sc.cna.auv.is_some() { "auv" } else { "ship" };
    let depth = |p: Vec3| if sc.cna.auv.is_some() { p.z } else { 0.0 };
    let cna = trace.cna.iter().map(|&(t, p)| sample(t, p.x, p.y, depth(p))).collect();
    vehicles.push(vehicle("cna".into(), Role::Cna, cna_kind, cna));
    let pulses = trace
        .comms
        .iter()
        .map(|e| {
            let (kind, from, to) = match e.direction {
                "down" => (PulseKind::Range, "cna".to_string(), auv_name(e.auv)),
                _ => (PulseKind::Comms, auv_name(e.auv), "cna".to_string()),
            };
            Pulse { t: e.t, kind, from, to, received: e.received }
        })
        .collect();
    let legs = trace
        .decisions
        .iter()
        .filter_map(|d| {
            let to = d.to?;
            Some(Leg { t: d.t, points: vec![[d.from.x, d.from.y, d.from.z], [to.x, to.y, to.z]] })
        })
        .collect();
    Ok(RunLog {
        scenario: format!(
            "closed loop, policy {}, {} survey AUVs, {} CNA, {} s, seed {}",
            result.policy,
            sc.fleet.n_auvs,
            if sc.cna.auv.is_some() { "AUV" } else { "ASC" },
            sc.duration_s,
            result.seed
        ),
        command: "simulate".into(),
        version: version(),
        origin: None,
        vehicles,
        pulses,
        legs,
    })
}

/// A pre-deployment plan (`plan`): the survey AUVs' planned tracks, the CNA's path (with depth)
/// and, at each decision, the leg it chose. The plan models errors but no filter, so there are no
/// estimates and no pulses.
pub fn plan_run(mission: &Mission, result: &PlanResult) -> RunLog {
    let steps = &result.steps;
    let mut vehicles: Vec<Vehicle> = (0..mission.names.len())
        .map(|k| {
            let samples = steps.iter().map(|s| sample(s.t, s.auv[k].x, s.auv[k].y, s.auv[k].z)).collect();
            vehicle(auv_name(k), Role::Truth, "auv", samples)
        })
        .collect();
    let cna_kind = if plans_an_auv(mission) { "auv" } else { "ship" };
    let cna = steps.iter().map(|s| sample(s.t, s.cna.pos.x, s.cna.pos.y, s.cna.pos.z)).collect();
    vehicles.push(vehicle("cna".into(), Role::Cna, cna_kind, cna));
    let legs = steps
        .windows(2)
        .map(|w| {
            let point = |s: &coopnav_plan::predeploy::StepRecord| [s.cna.pos.x, s.cna.pos.y, s.cna.pos.z];
            Leg { t: w[0].t, points: vec![point(&w[0]), point(&w[1])] }
        })
        .collect();
    RunLog {
        scenario: format!(
            "pre-deployment plan, survey AUVs {}, tau {} s",
            mission.names.join(" "),
            mission.planner.motion.tau
        ),
        command: "plan".into(),
        version: version(),
        origin: None,
        vehicles,
        pulses: Vec::new(),
        legs,
    }
}

/// A Gill (2013) pass (`hbl simulate`, one row a second): the AUV's truth and estimate (1σ =
/// √(σ_E² + σ_N²)), the ship (CNA) true and as the AUV estimates it, and the buoy when it is
/// scored; LAT/LON when the log has a geodetic origin. Depths are written as 0.
pub fn hbl_run(rows: &[PassRow], origin: Option<LocalFrame>) -> RunLog {
    let track = |f: &dyn Fn(&PassRow) -> Option<[f64; 2]>| -> Vec<Sample> {
        rows.iter().filter_map(|r| f(r).map(|p| sample(r.t, p[0], p[1], 0.0))).collect()
    };
    let estimate: Vec<Sample> = rows
        .iter()
        .map(|r| Sample { sd: Some(r.auv_sd[0].hypot(r.auv_sd[1])), ..sample(r.t, r.auv_est[0], r.auv_est[1], 0.0) })
        .collect();
    let mut vehicles = vec![
        vehicle(auv_name(0), Role::Truth, "auv", track(&|r| Some(r.auv_true))),
        vehicle(format!("{}_est", auv_name(0)), Role::Estimate, "auv", estimate),
        vehicle("cna".into(), Role::Cna, "ship", track(&|r| Some(r.ship_true))),
        vehicle("cna_est".into(), Role::Estimate, "ship", track(&|r| Some(r.ship_est))),
    ];
    let buoy = track(&|r| r.buoy_true);
    if !buoy.is_empty() {
        vehicles.push(vehicle("buoy".into(), Role::Beacon, "buoy", buoy));
    }
    RunLog {
        scenario: "hbl: an AUV passing under a ship (Gill 2013)".into(),
        command: "hbl simulate".into(),
        version: version(),
        origin,
        vehicles,
        pulses: Vec::new(),
        legs: Vec::new(),
    }
}

fn plans_an_auv(mission: &Mission) -> bool {
    matches!(mission.planner.motion.cna, CnaKind::Auv { .. })
}

/// The MOOS-IvP mission files (`cna.moos`, `cna.bhv`) that fly a plan's CNA path: its start, every
/// waypoint with its time, depth and leg heading, at the planned speed; `origin` anchors the local
/// frame.
pub fn plan_mission(mission: &Mission, result: &PlanResult, origin: LatLon) -> MissionFiles {
    let waypoint = |t: f64, cna: &CnaPose| Waypoint {
        t,
        x: cna.pos.x,
        y: cna.pos.y,
        depth: cna.pos.z,
        heading_compass_deg: CompassDeg::from(cna.heading).0,
    };
    let steps = &result.steps;
    mission_files(&MissionSpec {
        community: "cna".into(),
        server_port: 9000,
        origin,
        speed: mission.planner.motion.speed,
        auv: plans_an_auv(mission),
        start: waypoint(steps[0].t, &steps[0].cna),
        waypoints: steps[1..].iter().map(|s| waypoint(s.t, &s.cna)).collect(),
        capture_radius_m: 5.0,
    })
}
