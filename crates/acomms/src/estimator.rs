//! Position estimator (Nams 2014, §5.1): a "shadow simulation" of each collaborator
//! with the same IVER2 kinematics. Each received status resets the shadow to the report; between
//! reports the shadow keeps flying — through the collaborator's known mission plan (pre-planned
//! mode), or only to the last reported next waypoint, where it stops (dynamic mode: straight-line
//! extrapolation "leads to runaway estimations").

use crate::status::{LocalOrigin, NextWaypoint, StatusMessage};
use coopnav_core::{Bathymetry, DepthTarget, Iver2, Iver2Params, Iver2State, Vec3, Waypoint};

/// What the estimator knows of the collaborator's mission.
#[derive(Debug, Clone, PartialEq)]
pub enum Knowledge {
    /// The full waypoint list (status messages carry a 1-byte waypoint id).
    PrePlanned { plan: Vec<Waypoint> },
    /// Nothing but the reports (status messages carry the next waypoint's lat/lon); the shadow
    /// flies to it with this depth reference and speed.
    Dynamic { target: DepthTarget, speed: f64, origin: LocalOrigin },
}

/// One collaborator's shadow.
#[derive(Debug, Clone)]
pub struct ShadowEstimator {
    knowledge: Knowledge,
    params: Iver2Params,
    shadow: Option<Iver2>,
}

impl ShadowEstimator {
    /// `initial`: the collaborator's state at t = 0 if known (e.g. the start of a known plan).
    pub fn new(knowledge: Knowledge, params: Iver2Params, initial: Option<Iver2State>) -> Self {
        let shadow = initial.map(|s| {
            let plan = match &knowledge {
                Knowledge::PrePlanned { plan } => plan.clone(),
                Knowledge::Dynamic { .. } => Vec::new(),
            };
            Iver2::new(params, s, plan)
        });
        ShadowEstimator { knowledge, params, shadow }
    }

    fn waypoints_after(&self, next: NextWaypoint) -> (Vec<Waypoint>, usize) {
        match (&self.knowledge, next) {
            (Knowledge::PrePlanned { plan }, NextWaypoint::Id(id)) => (plan.clone(), id as usize),
            (Knowledge::PrePlanned { plan }, NextWaypoint::LatLon { .. }) => (plan.clone(), plan.len()),
            (Knowledge::Dynamic { target, speed, origin }, NextWaypoint::LatLon { lat, lon }) => {
                let (x, y) = origin.to_local(lat, lon);
                (vec![Waypoint { x, y, target: *target, speed: *speed }], 0)
            }
            // An id without the plan it indexes says nothing: stop at the reported position.
            (Knowledge::Dynamic { .. }, NextWaypoint::Id(_)) => (Vec::new(), 0),
        }
    }

    /// Resets the shadow to a status report made at time `t_report`.
    pub fn on_status(&mut self, msg: &StatusMessage, t_report: f64) {
        let (wps, next) = self.waypoints_after(msg.next);
        let state = Iver2State { speed: msg.speed, t: t_report, ..Iver2State::at_rest(msg.pos, msg.heading) };
        let mut v = Iver2::new(self.params, state, wps);
        v.reset(state, next);
        self.shadow = Some(v);
    }

    /// Estimated position at time `t` (None until anything is known). Time only moves forward:
    /// asking for an earlier time returns the latest estimate.
    pub fn estimate(&mut self, t: f64, bathy: &Bathymetry) -> Option<Vec3> {
        let v = self.shadow.as_mut()?;
        v.advance_to(t, bathy);
        Some(v.state.pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::{Heading, Shelf};

    fn bathy() -> Bathymetry {
        Bathymetry::shelf(&Shelf::default()).unwrap()
    }

    fn plan() -> Vec<Waypoint> {
        let t = DepthTarget::Altitude { altitude: 5.0 };
        [(500.0, 0.0), (500.0, 50.0), (0.0, 50.0)]
            .iter()
            .map(|&(x, y)| Waypoint { x, y, target: t, speed: 1.543 })
            .collect()
    }

    fn truth(b: &Bathymetry) -> Vec<Iver2State> {
        let mut v = Iver2::new(
            Iver2Params::default(),
            Iver2State::at_rest(Vec3::new(0.0, 0.0, 15.0), Heading::from_radians(0.0)),
            plan(),
        );
        (0..8000)
            .map(|_| {
                v.step(b);
                v.state
            })
            .collect()
    }

    fn report(s: &Iver2State, next: NextWaypoint) -> StatusMessage {
        StatusMessage { pos: s.pos, heading: s.heading, speed: s.speed, next }
    }

    #[test]
    fn preplanned_shadow_tracks_through_a_long_drought() {
        let b = bathy();
        let tr = truth(&b);
        let mut est = ShadowEstimator::new(Knowledge::PrePlanned { plan: plan() }, Iver2Params::default(), None);
        assert_eq!(est.estimate(10.0, &b), None);
        // One report at t = 100 s (waypoint 0 next), then silence until t = 500 s (after two turns).
        let s = tr[999];
        // The report carries position, heading and speed; the rest of the state it leaves out
        // (pitch, rates, acceleration) is that of a steady straight cruise at this moment, so the
        // shadow, the same kinematics from the same state, must follow the truth through both
        // turns to rounding: a centimetre over 400 s. A shadow that started from rest, or
        // turned late, would be metres off.
        assert!(s.yaw_rate.abs() < 1e-9 && s.lin_accel.abs() < 1e-9 && s.speed > 1.0, "{s:?}");
        est.on_status(&report(&s, NextWaypoint::Id(0)), s.t);
        let turned = (tr[4999].heading.radians() - s.heading.radians()).abs();
        assert!(turned > 0.5, "the truth turns between the report and the estimate: {turned} rad");
        let e = est.estimate(tr[4999].t, &b).unwrap();
        assert!((e - tr[4999].pos).xy().norm() < 0.01, "error {}", (e - tr[4999].pos).xy().norm());
    }

    #[test]
    fn dynamic_shadow_stops_at_the_last_known_waypoint() {
        let b = bathy();
        let tr = truth(&b);
        let o = LocalOrigin::default();
        let (lat, lon) = o.to_latlon(500.0, 0.0);
        let mut est = ShadowEstimator::new(
            Knowledge::Dynamic { target: DepthTarget::Altitude { altitude: 5.0 }, speed: 1.543, origin: o },
            Iver2Params::default(),
            None,
        );
        est.on_status(&report(&tr[999], NextWaypoint::LatLon { lat, lon }), tr[999].t);
        let e = est.estimate(2000.0, &b).unwrap();
        assert!((e.x - 500.0).abs() < 6.0 && e.y.abs() < 6.0, "parked near the waypoint: {e:?}");
        // A new report resets the shadow.
        est.on_status(&report(&tr[5999], NextWaypoint::LatLon { lat, lon }), tr[5999].t);
        let e2 = est.estimate(tr[5999].t, &b).unwrap();
        // Asked at the report's own time: the reported position itself.
        assert!((e2 - tr[5999].pos).norm() < 1e-9, "{e2:?} vs {:?}", tr[5999].pos);
    }

    #[test]
    fn known_start_gives_an_estimate_before_any_report() {
        let b = bathy();
        let init = Iver2State::at_rest(Vec3::new(0.0, 0.0, 15.0), Heading::from_radians(0.0));
        let mut est = ShadowEstimator::new(Knowledge::PrePlanned { plan: plan() }, Iver2Params::default(), Some(init));
        let tr = truth(&b);
        let e = est.estimate(tr[2999].t, &b).unwrap();
        assert!((e - tr[2999].pos).norm() < 1e-9, "same kinematics, same start: identical");
    }
}
