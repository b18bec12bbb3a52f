//! Underway-mode survey-track prediction (Hudson 2012, Sec. 4.2; docs/models.md#hudson-prediction).
//!
//! In underway mode the CNA knows nothing a priori about the survey AUVs' paths; it learns them
//! from acoustic status messages (position, depth, speed, heading and the next few waypoints).
//! [`UnderwayPredictor`] turns the reports of one AUV into a position at any future time:
//! along the reported waypoints at the last reported speed (so waypoint ETAs are recomputed with
//! every new report), then in a straight line, with depth held at the last reported value.
//! Optionally it holds the AUV's mission plan as known before launch, a stand-in forecast until
//! the reports take over ([`UnderwayPredictor::with_plan`]; not in the thesis).

use crate::AuvForecast;
use coopnav_core::{Heading, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// One status report as the CNA decoded it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusReport {
    /// Time the AUV sent the report (message header timestamp), s.
    pub t: f64,
    /// Reported position; z is the reported depth.
    pub pos: Vec3,
    /// Reported speed over ground, m/s.
    pub speed: f64,
    pub heading: Heading,
    /// The AUV's next waypoints (x, y), nearest first. Waypoints carry no depth.
    pub waypoints: Vec<(f64, f64)>,
}

/// How many of the reported waypoints the prediction follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WaypointUse {
    /// Every received waypoint (the default; recommended for future work in Hudson 2012, Ch. 7).
    All,
    /// At most this many. The thesis used min(L, 3), and one waypoint when L = 0 (Hudson 2012,
    /// Sec. 4.2); use [`WaypointUse::thesis`] for that.
    AtMost(usize),
}

impl WaypointUse {
    /// The thesis's behaviour for look-ahead depth `l`.
    pub fn thesis(l: usize) -> Self {
        WaypointUse::AtMost(l.clamp(1, 3))
    }
    fn limit(self, available: usize) -> usize {
        match self {
            WaypointUse::All => available,
            WaypointUse::AtMost(n) => n.min(available),
        }
    }
}

/// Direction of travel assumed once the AUV is predicted past its last known waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BeyondWaypoints {
    /// Stop at the last reported waypoint (the default). Past it the CNA knows nothing of the
    /// AUV's plan, and a straight-line guess grows without bound while the AUV stays unheard:
    /// on the mission engine a silenced AUV's extrapolation drew the CNA hundreds of metres off.
    /// Holding the last known point bounds the prediction by the plan the AUV sent.
    /// With no waypoint reported, the AUV is held at its reported position.
    Stop,
    /// Keep going along the last leg into the last waypoint (an interpretation: an AUV that reached a waypoint
    /// rarely keeps the heading it reported on the way to the first one).
    LastLeg,
    /// The last reported heading, as the thesis's text reads (Hudson 2012, Sec. 4.2).
    ReportedHeading,
}

/// Settings of the predictor. Defaults: docs/models.md#hudson-prediction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PredictorConfig {
    pub waypoints: WaypointUse,
    pub beyond: BeyondWaypoints,
    /// Reported speeds at or below this (m/s) mean the AUV has stopped (Hudson 2012, Sec. 4.2).
    pub stopped_speed: f64,
    /// Reports older than the newest by more than this (s) are dropped from the history; the thesis
    /// capped its report vector without giving the size (Hudson 2012, Sec. 4.2).
    pub max_report_age: f64,
}

impl Default for PredictorConfig {
    fn default() -> Self {
        PredictorConfig {
            waypoints: WaypointUse::All,
            beyond: BeyondWaypoints::Stop,
            stopped_speed: 0.05,
            max_report_age: 600.0,
        }
    }
}

/// The reports of one survey AUV and the prediction made from them.
#[derive(Debug, Clone)]
pub struct UnderwayPredictor {
    config: PredictorConfig,
    history: VecDeque<StatusReport>,
    received: usize,
    /// The mission plan as the operator knew it before launch, written as a report from the
    /// launch point; never counted as received.
    plan: Option<StatusReport>,
}

impl UnderwayPredictor {
    pub fn new(config: PredictorConfig) -> Self {
        UnderwayPredictor { config, history: VecDeque::new(), received: 0, plan: None }
    }

    /// The same predictor knowing the AUV's mission `plan` (launch time and point, planned speed,
    /// every planned waypoint): [`Self::planning_position`] forecasts from it until enough real
    /// reports arrive. An invention (not in the thesis, whose underway CNA knows nothing a priori):
    /// a field team knows its AUVs' plans, and an AUV whose first status is lost is otherwise
    /// never planned for.
    pub fn with_plan(self, plan: StatusReport) -> Self {
        UnderwayPredictor { plan: Some(plan), ..self }
    }

    /// Takes in a report. A report older than the newest one held (delayed or out of order)
    /// counts as received but does not replace the newer one.
    pub fn receive(&mut self, report: StatusReport) {
        self.received += 1;
        let newest = self.history.back().map_or(f64::NEG_INFINITY, |r| r.t);
        if report.t < newest {
            return;
        }
        self.history.push_back(report);
        let t_new = self.history.back().map_or(0.0, |r| r.t);
        while self.history.front().is_some_and(|r| t_new - r.t > self.config.max_report_age) {
            self.history.pop_front();
        }
    }

    /// Number of reports received so far (the planning start rule of Hudson 2012, Sec. 4.2, counts these).
    pub fn reports_received(&self) -> usize {
        self.received
    }

    /// Reports currently held, oldest first.
    pub fn history(&self) -> impl Iterator<Item = &StatusReport> {
        self.history.iter()
    }

    pub fn latest(&self) -> Option<&StatusReport> {
        self.history.back()
    }

    /// Predicted position at time `t`, or `None` before any report. Times before the latest
    /// report return the reported position: the CNA never predicts backwards.
    pub fn position_at(&self, t: f64) -> Option<Vec3> {
        self.latest().map(|r| self.predicted_from(r, t))
    }

    /// The position the CNA plans with at `t`: from the reports once `min_reports` of them
    /// arrived (the planning start rule, Hudson 2012, Sec. 4.2); before that from the mission plan if one is
    /// known, else none.
    pub fn planning_position(&self, t: f64, min_reports: usize) -> Option<Vec3> {
        if self.received >= min_reports {
            return self.position_at(t);
        }
        self.plan.as_ref().map(|plan| self.predicted_from(plan, t))
    }

    fn predicted_from(&self, r: &StatusReport, t: f64) -> Vec3 {
        let (x, y) = self.horizontal_at(r, t);
        Vec3::new(x, y, r.pos.z)
    }

    fn horizontal_at(&self, r: &StatusReport, t: f64) -> (f64, f64) {
        let start = (r.pos.x, r.pos.y);
        if r.speed <= self.config.stopped_speed || t <= r.t {
            return start;
        }
        let mut remaining = r.speed * (t - r.t);
        let used = &r.waypoints[..self.config.waypoints.limit(r.waypoints.len())];
        let mut from = start;
        for &to in used {
            let leg = (to.0 - from.0).hypot(to.1 - from.1);
            if remaining <= leg {
                return step(from, to, remaining);
            }
            remaining -= leg;
            from = to;
        }
        if self.config.beyond == BeyondWaypoints::Stop {
            return from;
        }
        let direction = match (self.config.beyond, used) {
            (BeyondWaypoints::LastLeg, [.., a, b]) => (b.1 - a.1).atan2(b.0 - a.0),
            (BeyondWaypoints::LastLeg, [only]) if (only.0, only.1) != start => {
                (only.1 - start.1).atan2(only.0 - start.0)
            }
            _ => r.heading.radians(),
        };
        (from.0 + remaining * direction.cos(), from.1 + remaining * direction.sin())
    }
}

/// A fleet of predictors is the planner's forecast in underway mode.
impl AuvForecast for [UnderwayPredictor] {
    fn n_auvs(&self) -> usize {
        self.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        self.get(k)?.position_at(t)
    }
}

/// The point `dist` metres from `a` towards `b`.
fn step(a: (f64, f64), b: (f64, f64), dist: f64) -> (f64, f64) {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    if len == 0.0 {
        return a;
    }
    let f = dist / len;
    (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(t: f64, speed: f64, waypoints: Vec<(f64, f64)>) -> StatusReport {
        StatusReport { t, pos: Vec3::new(0.0, 0.0, 12.0), speed, heading: Heading::from_radians(0.0), waypoints }
    }

    fn close(a: Vec3, x: f64, y: f64, z: f64) -> bool {
        (a.x - x).abs() < 1e-9 && (a.y - y).abs() < 1e-9 && (a.z - z).abs() < 1e-9
    }

    #[test]
    fn nothing_before_the_first_report() {
        assert!(UnderwayPredictor::new(PredictorConfig::default()).position_at(10.0).is_none());
    }

    #[test]
    fn follows_waypoints_at_reported_speed_then_straight_on() {
        let mut p = UnderwayPredictor::new(PredictorConfig { beyond: BeyondWaypoints::LastLeg, ..Default::default() });
        p.receive(report(100.0, 2.0, vec![(100.0, 0.0), (100.0, 50.0)]));
        assert!(close(p.position_at(150.0).unwrap(), 100.0, 0.0, 12.0));
        assert!(close(p.position_at(160.0).unwrap(), 100.0, 20.0, 12.0));
        // Past the last waypoint: along the last leg (north), depth held.
        assert!(close(p.position_at(200.0).unwrap(), 100.0, 100.0, 12.0));
        // Never backwards in time.
        assert!(close(p.position_at(50.0).unwrap(), 0.0, 0.0, 12.0));
    }

    #[test]
    fn thesis_waypoint_limit_and_reported_heading() {
        let cfg = PredictorConfig {
            waypoints: WaypointUse::thesis(0),
            beyond: BeyondWaypoints::ReportedHeading,
            ..Default::default()
        };
        let mut p = UnderwayPredictor::new(cfg);
        let mut r = report(0.0, 1.0, vec![(0.0, 10.0), (50.0, 10.0)]);
        r.heading = Heading::from_radians(std::f64::consts::PI);
        p.receive(r);
        // Only wp1 is used; beyond it the AUV keeps its reported heading (west): not wp2's leg
        // (which gives (20, 10)) nor the last leg (north, (0, 30)).
        assert!(close(p.position_at(30.0).unwrap(), -20.0, 10.0, 12.0));
    }

    #[test]
    fn no_waypoints_extrapolates_along_heading_and_stopped_stays() {
        let mut p = UnderwayPredictor::new(PredictorConfig { beyond: BeyondWaypoints::LastLeg, ..Default::default() });
        p.receive(report(0.0, 1.5, vec![]));
        assert!(close(p.position_at(10.0).unwrap(), 15.0, 0.0, 12.0));
        p.receive(report(20.0, 0.0, vec![(500.0, 0.0)]));
        assert!(close(p.position_at(100.0).unwrap(), 0.0, 0.0, 12.0));
    }

    #[test]
    fn by_default_the_prediction_stops_at_the_last_reported_waypoint() {
        let mut p = UnderwayPredictor::new(PredictorConfig::default());
        p.receive(report(100.0, 2.0, vec![(100.0, 0.0), (100.0, 50.0)]));
        assert!(close(p.position_at(160.0).unwrap(), 100.0, 20.0, 12.0));
        // An hour unheard: still at the last waypoint, not 7 km further north.
        for t in [200.0, 3700.0] {
            assert!(close(p.position_at(t).unwrap(), 100.0, 50.0, 12.0));
        }
        p.receive(report(200.0, 1.5, vec![]));
        assert!(close(p.position_at(900.0).unwrap(), 0.0, 0.0, 12.0));
    }

    #[test]
    fn the_mission_plan_stands_in_until_the_start_rule_is_met() {
        let plain = UnderwayPredictor::new(PredictorConfig::default());
        assert!(plain.planning_position(10.0, 1).is_none(), "no plan, no report: nothing to plan with");
        let plan = StatusReport { pos: Vec3::new(0.0, 0.0, 20.0), ..report(0.0, 1.0, vec![(0.0, 0.0), (100.0, 0.0)]) };
        let mut p = plain.with_plan(plan);
        assert!(close(p.planning_position(40.0, 2).unwrap(), 40.0, 0.0, 20.0));
        assert!(p.position_at(40.0).is_none(), "the plan is not a report");
        assert_eq!(p.reports_received(), 0);
        p.receive(report(50.0, 0.0, vec![]));
        // One report of two required: still the plan; with one required, the report.
        assert!(close(p.planning_position(60.0, 2).unwrap(), 60.0, 0.0, 20.0));
        assert!(close(p.planning_position(60.0, 1).unwrap(), 0.0, 0.0, 12.0));
    }

    #[test]
    fn newer_reports_win_and_old_ones_age_out() {
        let cfg = PredictorConfig { max_report_age: 100.0, ..Default::default() };
        let mut p = UnderwayPredictor::new(cfg);
        for t in [0.0, 60.0, 120.0, 180.0] {
            p.receive(report(t, 1.0, vec![]));
        }
        p.receive(report(30.0, 9.0, vec![]));
        assert_eq!(p.reports_received(), 5);
        assert_eq!(p.latest().unwrap().t, 180.0);
        let held: Vec<f64> = p.history().map(|r| r.t).collect();
        assert_eq!(held, vec![120.0, 180.0]);
    }
}
