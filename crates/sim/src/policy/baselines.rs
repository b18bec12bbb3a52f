//! The baselines the planner is judged against: no CNA at all, fixed patterns over the survey
//! area, loitering at the fleet's centroid (on top of it, or on a stand-off circle around it),
//! trailing one AUV, relaying between a base and an AUV, and a pre-deployment plan flown
//! open-loop. Each is deliberately simple and stateless except for where it is along its own
//! pattern.

use super::{CnaCommand, CnaPolicy, PolicyContext};
use coopnav_core::{Heading, Rect, Vec3};

/// No CNA: the survey AUVs navigate on dead reckoning alone.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoCna;

impl CnaPolicy for NoCna {
    fn name(&self) -> &'static str {
        "none"
    }
    fn transmits(&self) -> bool {
        false
    }
    fn decide(&mut self, _: &PolicyContext) -> CnaCommand {
        CnaCommand::Hold
    }
}

/// A fixed closed pattern of waypoints flown round and round, whatever the AUVs do.
#[derive(Debug, Clone)]
pub struct FixedPattern {
    name: &'static str,
    waypoints: Vec<(f64, f64)>,
    capture_radius: f64,
    next: usize,
}

impl FixedPattern {
    /// The perimeter of the survey area, `inset` metres inside it.
    pub fn racetrack(area: Rect, inset: f64, capture_radius: f64) -> Self {
        let r = area.inset(inset);
        let waypoints = vec![r.min, (r.max.0, r.min.1), r.max, (r.min.0, r.max.1)];
        FixedPattern { name: "racetrack", waypoints, capture_radius, next: 0 }
    }

    /// `legs` legs zig-zagging along the area's longer side, there and back.
    pub fn zigzag(area: Rect, legs: usize, capture_radius: f64) -> Self {
        let legs = legs.max(1);
        let (w, h) = (area.max.0 - area.min.0, area.max.1 - area.min.1);
        let along_x = w >= h;
        let point = |i: usize| {
            let f = i as f64 / legs as f64;
            let side = i % 2 == 1;
            if along_x {
                (area.min.0 + f * w, if side { area.max.1 } else { area.min.1 })
            } else {
                (if side { area.max.0 } else { area.min.0 }, area.min.1 + f * h)
            }
        };
        let out: Vec<_> = (0..=legs).map(point).collect();
        let back = out.iter().rev().skip(1).take(legs.saturating_sub(1)).copied();
        let waypoints = out.iter().copied().chain(back).collect();
        FixedPattern { name: "zigzag", waypoints, capture_radius, next: 0 }
    }

    pub fn waypoints(&self) -> &[(f64, f64)] {
        &self.waypoints
    }
}

impl CnaPolicy for FixedPattern {
    fn name(&self) -> &'static str {
        self.name
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let here = (ctx.cna.pos.x, ctx.cna.pos.y);
        let reached = |w: (f64, f64)| (w.0 - here.0).hypot(w.1 - here.1) <= self.capture_radius;
        // Skip every waypoint already within reach, but at most one lap.
        for _ in 0..self.waypoints.len() {
            if !reached(self.waypoints[self.next]) {
                break;
            }
            self.next = (self.next + 1) % self.waypoints.len();
        }
        let (x, y) = self.waypoints[self.next];
        CnaCommand::GoTo(Vec3::new(x, y, ctx.cna.pos.z))
    }
}

/// The centroid of the AUVs' predicted positions half a period ahead (None: none known).
fn predicted_centroid(ctx: &PolicyContext) -> Option<Vec3> {
    let ahead = ctx.predicted_all(ctx.t + ctx.tau / 2.0);
    (!ahead.is_empty()).then(|| ahead.iter().sum::<Vec3>() / ahead.len() as f64)
}

/// Loiter at the centroid of the AUVs' predicted positions half a period ahead.
#[derive(Debug, Clone, Copy, Default)]
pub struct Centroid;

impl CnaPolicy for Centroid {
    fn name(&self) -> &'static str {
        "centroid"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        match predicted_centroid(ctx) {
            Some(c) => CnaCommand::GoTo(Vec3::new(c.x, c.y, ctx.cna.pos.z)),
            None => CnaCommand::Hold,
        }
    }
}

/// Loiter on a circle of radius `radius` around the centroid of the AUVs' predicted positions
/// half a period ahead, counter-clockwise: what a field team does with a CNA it does not plan for
/// (a range from right above an AUV tells it nothing horizontally, so the circle keeps a stand-off).
#[derive(Debug, Clone, Copy)]
pub struct CentroidStandoff {
    pub radius: f64,
}

impl CnaPolicy for CentroidStandoff {
    fn name(&self) -> &'static str {
        "centroid-standoff"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let Some(c) = predicted_centroid(ctx) else { return CnaCommand::Hold };
        let (dx, dy) = (ctx.cna.pos.x - c.x, ctx.cna.pos.y - c.y);
        // From the CNA's bearing about the centroid (its heading's side when it sits on it), one
        // period's travel further along the circle; from off the circle, the bearing's point on it.
        let distance = dx.hypot(dy);
        let bearing = if distance > 1e-9 { dy.atan2(dx) } else { ctx.cna.heading.radians() };
        let on_circle = (distance - self.radius).abs() <= ctx.speed * ctx.tau;
        let advance = if on_circle && self.radius > 0.0 { ctx.speed * ctx.tau / self.radius } else { 0.0 };
        let angle = bearing + advance;
        let target = (c.x + self.radius * angle.cos(), c.y + self.radius * angle.sin());
        CnaCommand::GoTo(Vec3::new(target.0, target.1, ctx.cna.pos.z))
    }
}

/// Follow one AUV at a fixed range and angle relative to its direction of travel, as MOOS-IvP's
/// BHV_Trail does (angle 180° = directly behind, 90° = abeam to port).
#[derive(Debug, Clone, Copy)]
pub struct Trail {
    pub auv: usize,
    pub range: f64,
    /// Relative to the AUV's predicted course, counter-clockwise, radians.
    pub angle: f64,
}

impl CnaPolicy for Trail {
    fn name(&self) -> &'static str {
        "trail"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let t1 = ctx.t + ctx.tau;
        let (Some(now), Some(next)) = (ctx.fleet.position(self.auv, ctx.t), ctx.fleet.position(self.auv, t1)) else {
            return CnaCommand::Hold;
        };
        let moving = (next.x - now.x).hypot(next.y - now.y) > 1e-6;
        let course = if moving { (next.y - now.y).atan2(next.x - now.x) } else { ctx.cna.heading.radians() };
        let (ux, uy) = Heading::from_radians(course + self.angle).unit();
        CnaCommand::GoTo(Vec3::new(next.x + self.range * ux, next.y + self.range * uy, ctx.cna.pos.z))
    }
}

/// Hold the midpoint between a fixed base (the operator's ship or shore station) and one AUV,
/// like DUNE's CommsRelay manoeuvre: the CNA bridges the two.
#[derive(Debug, Clone, Copy)]
pub struct MidpointRelay {
    pub base: (f64, f64),
    pub auv: usize,
}

impl CnaPolicy for MidpointRelay {
    fn name(&self) -> &'static str {
        "relay"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        match ctx.fleet.position(self.auv, ctx.t + ctx.tau) {
            Some(p) => CnaCommand::GoTo(Vec3::new((p.x + self.base.0) / 2.0, (p.y + self.base.1) / 2.0, ctx.cna.pos.z)),
            None => CnaCommand::Hold,
        }
    }
}

/// Waypoints planned before the mission (one per τ, from the pre-deployment planner on the
/// survey plan) flown open-loop by time, whatever the AUVs actually do.
#[derive(Debug, Clone)]
pub struct TimedWaypoints {
    /// (time the waypoint is due, position).
    pub waypoints: Vec<(f64, Vec3)>,
}

impl CnaPolicy for TimedWaypoints {
    fn name(&self) -> &'static str {
        "open-loop"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let due = ctx.t + ctx.tau;
        let i = self.waypoints.partition_point(|w| w.0 < due);
        match self.waypoints.get(i).or(self.waypoints.last()) {
            Some(&(_, p)) => CnaCommand::GoTo(p),
            None => CnaCommand::Hold,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_plan::{AuvForecast, CnaPose};

    /// AUVs moving east at 1 m/s from given starting points.
    struct Eastbound(Vec<(f64, f64)>);

    impl AuvForecast for Eastbound {
        fn n_auvs(&self) -> usize {
            self.0.len()
        }
        fn position(&self, k: usize, t: f64) -> Option<Vec3> {
            self.0.get(k).map(|&(x, y)| Vec3::new(x + t, y, 10.0))
        }
    }

    fn ctx<'a>(t: f64, pos: (f64, f64), fleet: &'a dyn AuvForecast) -> PolicyContext<'a> {
        PolicyContext {
            t,
            tau: 30.0,
            cna: CnaPose { pos: Vec3::new(pos.0, pos.1, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 },
            speed: 2.0,
            fleet,
            reported: &[],
            cna_variance: 1.0,
        }
    }

    fn target(c: CnaCommand) -> (f64, f64) {
        match c {
            CnaCommand::GoTo(p) => (p.x, p.y),
            CnaCommand::Hold => panic!("expected a target"),
        }
    }

    #[test]
    fn racetrack_advances_only_when_a_corner_is_reached() {
        let area = Rect { min: (0.0, 0.0), max: (1000.0, 400.0) };
        let mut p = FixedPattern::racetrack(area, 50.0, 20.0);
        let fleet = Eastbound(vec![]);
        assert_eq!(target(p.decide(&ctx(0.0, (500.0, 200.0), &fleet))), (50.0, 50.0));
        assert_eq!(target(p.decide(&ctx(0.0, (55.0, 45.0), &fleet))), (950.0, 50.0));
        assert_eq!(target(p.decide(&ctx(0.0, (500.0, 50.0), &fleet))), (950.0, 50.0));
    }

    #[test]
    fn zigzag_goes_out_and_back_along_the_long_side() {
        let area = Rect { min: (0.0, 0.0), max: (900.0, 300.0) };
        let p = FixedPattern::zigzag(area, 3, 20.0);
        let w = p.waypoints();
        assert_eq!(w, &[(0.0, 0.0), (300.0, 300.0), (600.0, 0.0), (900.0, 300.0), (600.0, 0.0), (300.0, 300.0)]);
    }

    #[test]
    fn centroid_trail_and_relay_use_predictions() {
        let fleet = Eastbound(vec![(0.0, 0.0), (0.0, 100.0)]);
        assert_eq!(target(Centroid.decide(&ctx(0.0, (0.0, 0.0), &fleet))), (15.0, 50.0));
        let mut trail = Trail { auv: 1, range: 50.0, angle: std::f64::consts::PI };
        let (x, y) = target(trail.decide(&ctx(0.0, (0.0, 0.0), &fleet)));
        assert!((x - (30.0 - 50.0)).abs() < 1e-9 && (y - 100.0).abs() < 1e-9);
        let mut relay = MidpointRelay { base: (-100.0, 0.0), auv: 0 };
        assert_eq!(target(relay.decide(&ctx(70.0, (0.0, 0.0), &fleet))), (0.0, 0.0));
    }

    #[test]
    fn centroid_standoff_circles_the_predicted_centroid_at_its_radius() {
        let fleet = Eastbound(vec![(0.0, 0.0), (0.0, 100.0)]);
        // The centroid half a period ahead is (15, 50); the CNA sits 100 m east of it, on the circle.
        let mut p = CentroidStandoff { radius: 100.0 };
        let (x, y) = target(p.decide(&ctx(0.0, (115.0, 50.0), &fleet)));
        assert!(((x - 15.0).hypot(y - 50.0) - 100.0).abs() < 1e-9, "({x}, {y})");
        // One period at 2 m/s is 60 m of arc: 0.6 rad counter-clockwise.
        assert!((x - (15.0 + 100.0 * 0.6f64.cos())).abs() < 1e-9 && (y - (50.0 + 100.0 * 0.6f64.sin())).abs() < 1e-9);
        // Far off the circle (500 m east): it heads for the circle's nearest point first.
        assert_eq!(target(p.decide(&ctx(0.0, (515.0, 50.0), &fleet))), (115.0, 50.0));
        // Never onto the centroid itself, unlike `Centroid`.
        let (x, y) = target(p.decide(&ctx(0.0, (15.0, 50.0), &fleet)));
        assert!(((x - 15.0).hypot(y - 50.0) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn policies_hold_when_nothing_is_known() {
        let fleet = Eastbound(vec![]);
        let c = ctx(0.0, (0.0, 0.0), &fleet);
        assert_eq!(Centroid.decide(&c), CnaCommand::Hold);
        assert_eq!(CentroidStandoff { radius: 100.0 }.decide(&c), CnaCommand::Hold);
        assert_eq!(Trail { auv: 0, range: 10.0, angle: 0.0 }.decide(&c), CnaCommand::Hold);
        assert_eq!(MidpointRelay { base: (0.0, 0.0), auv: 0 }.decide(&c), CnaCommand::Hold);
        assert_eq!(TimedWaypoints { waypoints: vec![] }.decide(&c), CnaCommand::Hold);
        assert!(!NoCna.transmits());
    }

    #[test]
    fn open_loop_waypoints_follow_the_clock() {
        let w = |t: f64, x: f64| (t, Vec3::new(x, 0.0, 0.0));
        let mut p = TimedWaypoints { waypoints: vec![w(30.0, 1.0), w(60.0, 2.0), w(90.0, 3.0)] };
        let fleet = Eastbound(vec![]);
        assert_eq!(target(p.decide(&ctx(0.0, (0.0, 0.0), &fleet))), (1.0, 0.0));
        assert_eq!(target(p.decide(&ctx(31.0, (0.0, 0.0), &fleet))), (3.0, 0.0));
        assert_eq!(target(p.decide(&ctx(500.0, (0.0, 0.0), &fleet))), (3.0, 0.0));
    }
}
