//! A scenario's `[policy]` table: what the CNA knows of the fleet under every policy (when it
//! starts planning for an AUV, what it knows before then, the link model it plans with, how it
//! predicts an AUV from its reports), and one table per policy instance, as MOOS-IvP mission
//! files name behaviour instances: `[policy.planner]` and `[policy.planner-estimator]` (each a
//! `coopnav_plan::PlannerSpec`), `[policy.open-loop]` (the pre-deployment planner's spec),
//! `[policy.zigzag]`, `[policy.racetrack]`, `[policy.centroid-standoff]`, `[policy.trail]`,
//! `[policy.relay]`, `[policy.greedy-fisher]`. Every table and key is optional; each default is
//! written once, here or in the planner's spec, and the baselines' defaults are the values they
//! were flown with before they were data (all invented, docs/models.md#baselines).

use coopnav_core::validation::Problems;
use coopnav_plan::predict::PredictorConfig;
use coopnav_plan::PlannerSpec;
use serde::{Deserialize, Serialize};

/// The `[policy]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Policies {
    /// Reports needed from an AUV before the CNA plans for it, under every policy (Hudson 2012,
    /// Sec. 4.2: two; default one).
    #[serde(default = "one")]
    pub start_after_reports: usize,
    /// What the CNA plans with for an AUV it has fewer than `start_after_reports` reports of.
    /// Written only when not the thesis's default.
    #[serde(default, skip_serializing_if = "BeforeFirstReport::is_ignore")]
    pub before_first_report: BeforeFirstReport,
    /// Which channel the policies' link model (the planners' lost pings and link table,
    /// greedy-fisher's information) is built on. Written only when not the default.
    #[serde(default, skip_serializing_if = "PlannerLink::is_assumed")]
    pub link: PlannerLink,
    /// How the CNA predicts each AUV from its status reports (Hudson 2012, Sec. 4.2).
    #[serde(default)]
    pub predictor: PredictorConfig,
    /// Hudson's planner (default: Hudson's cost with every default).
    #[serde(default = "PlannerSpec::hudson")]
    pub planner: PlannerSpec,
    /// The estimator-aware planner (default: the estimator cost, every setting from the rule).
    #[serde(rename = "planner-estimator", default = "PlannerSpec::estimator")]
    pub planner_estimator: PlannerSpec,
    /// The pre-deployment plan flown by time: the planner that plans it on the nominal survey
    /// tracks (Hudson's cost; planned offline, so its `deadline` is not used).
    #[serde(rename = "open-loop", default = "PlannerSpec::hudson")]
    pub open_loop: PlannerSpec,
    #[serde(default)]
    pub racetrack: Racetrack,
    #[serde(default)]
    pub zigzag: Zigzag,
    #[serde(rename = "centroid-standoff", default)]
    pub centroid_standoff: CentroidStandoff,
    #[serde(default)]
    pub trail: Trail,
    #[serde(default)]
    pub relay: Relay,
    #[serde(rename = "greedy-fisher", default)]
    pub greedy_fisher: GreedyFisher,
    /// `none` and `centroid` take no parameters; their tables may be given empty.
    #[serde(default, skip_serializing)]
    pub none: NoParameters,
    #[serde(default, skip_serializing)]
    pub centroid: NoParameters,
}

impl Default for Policies {
    fn default() -> Self {
        toml::from_str("").expect("an empty [policy] table reads with every default")
    }
}

fn one() -> usize {
    1
}

/// What the CNA knows of a survey AUV before its reports meet the planning start rule (Hudson 2012, Sec. 4.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BeforeFirstReport {
    /// Nothing: the planner and every baseline ignore the AUV until then (the thesis's rule).
    /// An AUV whose statuses never reach the CNA is never looked for.
    #[default]
    Ignore,
    /// Its mission plan as the operator knew it before launch (launch point, planned lawnmower
    /// waypoints and speed), followed from t = 0 until the reports take over. An invention, not
    /// in the thesis: a field team knows its AUVs' plans.
    MissionPlan,
}

impl BeforeFirstReport {
    fn is_ignore(&self) -> bool {
        *self == BeforeFirstReport::Ignore
    }
}

/// The transmission loss behind the policies' ping success likelihood (`policy.link`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerLink {
    /// The analytic model the CNA is configured with (`comms.tl.assumed()`: the default Thorp
    /// model under the BELLHOP kinds), apart from the sea it plays in.
    #[default]
    Assumed,
    /// The scenario's own `comms.tl` provider, averaged over bearings from the survey blocks'
    /// centres (policies `channel_likelihood`). Invented: a team that has modelled
    /// its site's acoustics gives the planner that model. Needs `analytic` or `bellhop_grid`.
    ScenarioChannel,
}

impl PlannerLink {
    fn is_assumed(&self) -> bool {
        *self == PlannerLink::Assumed
    }
}

/// An empty table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoParameters {}

/// Radius within which a fixed pattern's waypoint counts as reached, m. Invented.
fn capture_radius_m() -> f64 {
    20.0
}

/// The survey area's perimeter flown round and round, `inset_m` inside it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Racetrack {
    /// Inset from the survey area's edge, m (≥ 0). Invented: 100 m.
    #[serde(default = "racetrack_inset_m")]
    pub inset_m: f64,
    #[serde(default = "capture_radius_m")]
    pub capture_radius_m: f64,
}

fn racetrack_inset_m() -> f64 {
    100.0
}

impl Default for Racetrack {
    fn default() -> Self {
        Racetrack { inset_m: racetrack_inset_m(), capture_radius_m: capture_radius_m() }
    }
}

/// Legs zig-zagging along the survey area's longer side, there and back.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zigzag {
    /// Legs one way (≥ 1). Invented: 4.
    #[serde(default = "zigzag_legs")]
    pub legs: usize,
    #[serde(default = "capture_radius_m")]
    pub capture_radius_m: f64,
}

fn zigzag_legs() -> usize {
    4
}

impl Default for Zigzag {
    fn default() -> Self {
        Zigzag { legs: zigzag_legs(), capture_radius_m: capture_radius_m() }
    }
}

/// A loiter circle around the fleet's predicted centroid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentroidStandoff {
    /// The circle's radius, m (≥ 0). Invented: 150 m, the trail baseline's stand-off.
    #[serde(default = "standoff_radius_m")]
    pub radius_m: f64,
}

fn standoff_radius_m() -> f64 {
    150.0
}

impl Default for CentroidStandoff {
    fn default() -> Self {
        CentroidStandoff { radius_m: standoff_radius_m() }
    }
}

/// Following one AUV at a fixed range and angle from its course (BHV_Trail-style).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trail {
    /// The AUV followed (absent: the middle one, N / 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auv: Option<usize>,
    /// Range behind it, m (≥ 0). Invented: 150 m.
    #[serde(default = "trail_range_m")]
    pub range_m: f64,
    /// Angle from its course, counter-clockwise, degrees (180 = directly behind).
    #[serde(default = "trail_angle_deg")]
    pub angle_deg: f64,
}

fn trail_range_m() -> f64 {
    150.0
}
fn trail_angle_deg() -> f64 {
    180.0
}

impl Default for Trail {
    fn default() -> Self {
        Trail { auv: None, range_m: trail_range_m(), angle_deg: trail_angle_deg() }
    }
}

/// Holding the midpoint between the CNA's start (the operator's base) and one AUV.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Relay {
    /// The AUV relayed (absent: the middle one, N / 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auv: Option<usize>,
}

/// One-step Fisher-information placement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GreedyFisher {
    /// Reachable points tried per decision, evenly spread in heading (≥ 1). Invented: 16.
    #[serde(default = "greedy_candidates")]
    pub candidates: usize,
    /// The prior that keeps a rank-one information matrix invertible, m (> 0). Invented: 100 m.
    #[serde(default = "greedy_sigma_prior_m")]
    pub sigma_prior_m: f64,
}

fn greedy_candidates() -> usize {
    16
}
fn greedy_sigma_prior_m() -> f64 {
    100.0
}

impl Default for GreedyFisher {
    fn default() -> Self {
        GreedyFisher { candidates: greedy_candidates(), sigma_prior_m: greedy_sigma_prior_m() }
    }
}

impl Policies {
    /// The baselines' own fields (the planners' are checked with the mission, `Scenario::validate`).
    pub fn check_baselines(&self, n_auvs: usize, p: &mut Problems) {
        if self.start_after_reports == 0 {
            p.push("policy.start_after_reports", "0", ">= 1");
        }
        p.non_negative("policy.racetrack.inset_m", self.racetrack.inset_m);
        p.non_negative("policy.racetrack.capture_radius_m", self.racetrack.capture_radius_m);
        if self.zigzag.legs == 0 {
            p.push("policy.zigzag.legs", "0", ">= 1");
        }
        p.non_negative("policy.zigzag.capture_radius_m", self.zigzag.capture_radius_m);
        p.non_negative("policy.centroid-standoff.radius_m", self.centroid_standoff.radius_m);
        p.non_negative("policy.trail.range_m", self.trail.range_m);
        p.finite("policy.trail.angle_deg", self.trail.angle_deg);
        for (field, auv) in [("policy.trail.auv", self.trail.auv), ("policy.relay.auv", self.relay.auv)] {
            if let Some(k) = auv.filter(|&k| k >= n_auvs) {
                p.push(field, k.to_string(), format!("0..{n_auvs} (a survey AUV's index)"));
            }
        }
        if self.greedy_fisher.candidates == 0 {
            p.push("policy.greedy-fisher.candidates", "0", ">= 1");
        }
        p.positive("policy.greedy-fisher.sigma_prior_m", self.greedy_fisher.sigma_prior_m);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every baseline's default is the value it was flown with as a constant.
    #[test]
    fn the_baselines_defaults_are_their_former_constants() {
        let p = Policies::default();
        assert_eq!((p.racetrack.inset_m, p.racetrack.capture_radius_m), (100.0, 20.0));
        assert_eq!((p.zigzag.legs, p.zigzag.capture_radius_m), (4, 20.0));
        assert_eq!(p.centroid_standoff.radius_m, 150.0);
        assert_eq!((p.trail.auv, p.trail.range_m, p.trail.angle_deg), (None, 150.0, 180.0));
        assert_eq!(p.relay.auv, None);
        assert_eq!((p.greedy_fisher.candidates, p.greedy_fisher.sigma_prior_m), (16, 100.0));
        assert_eq!(p.planner, PlannerSpec::hudson());
        assert_eq!(p.planner_estimator, PlannerSpec::estimator());
        assert_eq!(p.open_loop, PlannerSpec::hudson());
        assert_eq!(
            (p.start_after_reports, p.before_first_report, p.link),
            (1, BeforeFirstReport::Ignore, PlannerLink::Assumed)
        );
    }

    /// A table sets only what it names; an unknown policy or key is refused naming it.
    #[test]
    fn a_policy_table_sets_only_what_it_names() {
        let p: Policies = toml::from_str("[zigzag]\nlegs = 6\n[trail]\nauv = 0\n[none]\n").unwrap();
        assert_eq!((p.zigzag.legs, p.zigzag.capture_radius_m, p.trail.auv), (6, 20.0, Some(0)));
        let e = toml::from_str::<Policies>("[zig-zag]\nlegs = 6\n").unwrap_err().to_string();
        assert!(e.contains("zig-zag") && e.contains("zigzag") && e.contains("planner-estimator"), "{e}");
        let e = toml::from_str::<Policies>("[racetrack]\ninset = 6.0\n").unwrap_err().to_string();
        assert!(e.contains("inset") && e.contains("inset_m"), "{e}");
        let mut found = Problems::new();
        let bad: Policies = toml::from_str("start_after_reports = 0\n[zigzag]\nlegs = 0\n[relay]\nauv = 3\n").unwrap();
        bad.check_baselines(3, &mut found);
        let e = found.finish().unwrap_err().to_string();
        for field in ["policy.start_after_reports = 0", "policy.zigzag.legs = 0", "policy.relay.auv = 3"] {
            assert!(e.contains(field), "{field}: {e}");
        }
    }
}
