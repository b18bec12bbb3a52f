//! Preparation mode (thesis §4.4.4): vehicle paths and slot timing do not depend on any comms
//! decision, so each (scenario, slot length) is flown once — kinematics and transmission loss at
//! every slot — and every behaviour and repetition reuses it.

use super::scenario::{ExperimentConfig, Scenario};
use coopnav_acomms::{Tdma, TlError, TransmissionLoss};
use coopnav_core::geometry::horizontal_distance;
use coopnav_core::{Bathymetry, DepthTarget, Heading, Iver2, Iver2State, Lawnmower, Vec3, Waypoint};
use std::f64::consts::PI;

/// Hard stop for a mission that never finishes (a waypoint the vehicle cannot capture), s.
const MAX_MISSION: f64 = 48.0 * 3600.0;

/// One vehicle at one slot start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub pos: Vec3,
    pub heading: Heading,
    pub speed: f64,
    pub next_wp: usize,
}

/// A scenario flown once at one slot length.
#[derive(Debug, Clone)]
pub struct Prepared {
    pub slot_len: f64,
    pub plans: [Vec<Waypoint>; 2],
    pub starts: [Iver2State; 2],
    /// Per slot k (t = k·slot_len): both vehicles.
    pub samples: Vec<[Sample; 2]>,
    /// TL from slot k's owner to the other vehicle, dB.
    pub tl: Vec<f64>,
    pub mean_distance: f64,
    pub duration: f64,
}

/// The two lawnmowers: vehicle 0 from (0, 0) running east and stepping north, vehicle 1 from the
/// opposite corner running west and stepping south (nams digest §8 item 21).
pub fn plans(s: &Scenario) -> [Vec<Waypoint>; 2] {
    let lanes = (s.square / s.lane_spacing).round() as usize + 1;
    let mower = |origin, heading| Lawnmower {
        origin,
        lane_heading: Heading::from_radians(heading),
        lane_length: s.square,
        spacing: s.lane_spacing,
        lanes,
        speed: s.speed,
        depth: coopnav_core::DepthProfile::Constant { depth: 0.0 },
    };
    let wps = |m: Lawnmower| {
        m.waypoints()
            .into_iter()
            .map(|(x, y)| Waypoint { x, y, target: DepthTarget::Altitude { altitude: s.altitude }, speed: s.speed })
            .collect()
    };
    [wps(mower((0.0, 0.0), 0.0)), wps(mower((s.square, s.square), PI))]
}

fn start(plan: &[Waypoint], bathy: &Bathymetry, altitude: f64) -> Iver2State {
    let (a, b) = (plan[0], plan.get(1).copied().unwrap_or(plan[0]));
    let depth = (bathy.depth_at(a.x, a.y) - altitude).max(0.0);
    Iver2State::at_rest(Vec3::new(a.x, a.y, depth), Heading::from_radians((b.y - a.y).atan2(b.x - a.x)))
}

fn sample(v: &Iver2) -> Sample {
    Sample { pos: v.state.pos, heading: v.state.heading, speed: v.state.speed, next_wp: v.next_waypoint() }
}

/// Flies `scenario` with slots of `slot_len` s and computes the TL of every slot.
pub fn prepare(
    scenario: &Scenario,
    cfg: &ExperimentConfig,
    bathy: &Bathymetry,
    tl: &dyn TransmissionLoss,
    slot_len: f64,
) -> Result<Prepared, TlError> {
    let plans = plans(scenario);
    let starts = [start(&plans[0], bathy, scenario.altitude), start(&plans[1], bathy, scenario.altitude)];
    let mut v =
        [Iver2::new(cfg.vehicle, starts[0], plans[0].clone()), Iver2::new(cfg.vehicle, starts[1], plans[1].clone())];
    let limit = cfg.max_time.unwrap_or(MAX_MISSION).min(MAX_MISSION);
    let (mut samples, mut tls) = (Vec::new(), Vec::new());
    let mut k = 0u64;
    loop {
        let t = k as f64 * slot_len;
        for vi in &mut v {
            vi.advance_to(t, bathy);
        }
        if (v[0].is_complete() && v[1].is_complete()) || t >= limit {
            break;
        }
        let s = [sample(&v[0]), sample(&v[1])];
        let owner = Tdma::owner(k, 2);
        tls.push(tl.tl(&s[owner].pos, &s[1 - owner].pos)?);
        samples.push(s);
        k += 1;
    }
    let n = samples.len().max(1) as f64;
    let mean_distance = samples.iter().map(|s| horizontal_distance(&s[0].pos, &s[1].pos)).sum::<f64>() / n;
    Ok(Prepared { slot_len, plans, starts, duration: samples.len() as f64 * slot_len, samples, tl: tls, mean_distance })
}
