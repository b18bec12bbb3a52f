//! Nams's experiment on the one engine: each (scenario, behaviour) cell of an
//! [`ExperimentConfig`] becomes an engine scenario — `scenarios/nams-1.toml` with the cell's
//! square, lanes, altitude, speed, ambient noise, shelf, success model, estimator mode, slot length
//! and rate policy set — which the batch runner runs with Nams's metrics as the observer.
//!
//! A mission lasts until both vehicles have flown their lawnmowers (the controller alone on its
//! plan, at the slot's resolution, as Nams's prepared mission), or `max_time`.

use crate::models::peer::StatusFormat;
use crate::models::schedule::{Schedule, SlotSpec};
use crate::models::tl_spec::TlModel;
use crate::scenario::nams::{Behaviour, ExperimentConfig, Scenario};
use crate::scenario::world::{Scenario as EngineScenario, ScenarioError};
use coopnav_acomms::selector::RatePolicyError;
use coopnav_acomms::SuccessModel;
use coopnav_core::{Bathymetry, DepthTarget, Heading, Iver2, Iver2State, Vec3, Waypoint};
use std::path::Path;

/// The engine file every cell starts from (Nams's scenario 1).
pub const TEMPLATE: &str = include_str!("../../../../scenarios/nams-1.toml");

/// Hard stop for a mission that never finishes (a waypoint the vehicle cannot capture), s.
const MAX_MISSION: f64 = 48.0 * 3600.0;

/// Slot length the behaviour forces on the network (15 s if it may use rate 5).
pub fn slot_length(cfg: &ExperimentConfig, behaviour: &Behaviour) -> Result<f64, RatePolicyError> {
    Ok(cfg.tdma.slot_length(behaviour.rates()?, cfg.ack))
}

/// The engine scenario of one cell; `slot_s` is [`slot_length`]'s; `tl`, when given, replaces the
/// template's analytic model (a BELLHOP grid is built here, by the validation).
pub fn engine_scenario(
    scenario: &Scenario,
    cfg: &ExperimentConfig,
    behaviour: &Behaviour,
    slot_s: f64,
    tl: Option<&TlModel>,
) -> Result<EngineScenario, ScenarioError> {
    let file = Path::new("scenarios/nams-1.toml");
    let mut sc = EngineScenario::parse(TEMPLATE, file)?;
    let (square, f) = (scenario.square, &mut sc.fleet);
    f.lane_length = square;
    f.lane_spacing = scenario.lane_spacing;
    f.lanes = (square / scenario.lane_spacing).round() as usize + 1;
    f.speed = scenario.speed;
    f.depth = DepthTarget::Altitude { altitude: scenario.altitude };
    f.shelf = Some(cfg.shelf.clone());
    f.vehicle = cfg.vehicle;
    if let Some(far) = f.lawnmowers.get_mut(1) {
        far.origin = (square, square);
    }
    // The experiment's vehicle step is the world's: truth, filters and link step together.
    sc.dt = cfg.vehicle.timestep;
    sc.cna.x = square / 2.0;
    let c = &mut sc.comms;
    c.tau = 2.0 * slot_s;
    c.status_format = StatusFormat::NamsFrame0 { estimator: cfg.estimator };
    let slot = |who: &str, start_s| SlotSpec {
        who: who.into(),
        start_s,
        length_s: slot_s,
        message: None,
        rate_policy: Some(behaviour.clone()),
    };
    c.schedule = Schedule::Tdma { slots: vec![slot("auv0", 0.0), slot("auv1", slot_s)] };
    // The square's diagonal, with room.
    c.max_range_m = 1.5 * square;
    c.success = SuccessModel { noise_db: scenario.noise_db, ..cfg.success.clone() };
    c.peer_receiver = scenario.receiver;
    if let Some(tl) = tl {
        c.tl = tl.clone();
    }
    sc.duration_s = mission_duration(&sc, slot_s).min(cfg.max_time.unwrap_or(MAX_MISSION));
    sc.validate(Path::new(&format!("{} ({}, {})", file.display(), scenario.name, behaviour.label())))?;
    Ok(sc)
}

/// When both survey AUVs' controllers, flying their plans from the plans' starts, have finished:
/// the first multiple of `slot_s` at which both are done.
fn mission_duration(sc: &EngineScenario, slot_s: f64) -> f64 {
    let bathy = sc.bathymetry();
    let mut vehicles: Vec<Iver2> = (0..sc.fleet.n_auvs).map(|k| flown(sc, k, &bathy)).collect();
    let mut k = 0u64;
    loop {
        let t = k as f64 * slot_s;
        vehicles.iter_mut().for_each(|v| v.advance_to(t, &bathy));
        if vehicles.iter().all(Iver2::is_complete) || t >= MAX_MISSION {
            return t;
        }
        k += 1;
    }
}

/// Survey AUV `k`'s controller at the start of its plan, at its altitude.
fn flown(sc: &EngineScenario, k: usize, bathy: &Bathymetry) -> Iver2 {
    let f = &sc.fleet;
    let plan: Vec<Waypoint> = sc
        .lawnmower(k)
        .waypoints()
        .into_iter()
        .map(|(x, y)| Waypoint { x, y, target: f.depth, speed: f.speed })
        .collect();
    let (a, b) = (plan[0], plan.get(1).copied().unwrap_or(plan[0]));
    let depth = f.depth.depth_over(bathy.depth_at(a.x, a.y)).max(0.0);
    let start = Iver2State::at_rest(Vec3::new(a.x, a.y, depth), Heading::from_radians((b.y - a.y).atan2(b.x - a.x)));
    Iver2::new(f.vehicle, start, plan)
}
