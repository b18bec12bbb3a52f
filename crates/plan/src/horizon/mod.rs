//! The mission-long horizon above the look-ahead tree (invented, docs/models.md#mission-horizon):
//! which survey AUV the CNA serves next, and so when it leaves one block for another, valued over
//! tens of minutes; the exact tree then plans the next L + 1 levels within that choice.
//!
//! Why a visiting order of fixed-length service segments, valued by rollouts of the tree's own
//! cost model:
//! - The decision the tree cannot see is a transit: between survey blocks a kilometre or more
//!   apart it takes ten or more minutes, far beyond L·τ, and the tree's cost-to-go prices each AUV
//!   alone (`estimator` steps 6 and 7), so no leaf is ever worth a commute. What must be compared
//!   is whole schedules of service: "serve AUV 2, then 0, then 1" against "stay with 0". A visiting
//!   order over S segments of D seconds each (`HorizonSpec`) is the smallest form that says it; it
//!   is searched exhaustively (N^S orders, prefixes shared), so the layer's choice is the best
//!   under its own model, deterministic, with no tuning of a sampling scheme.
//! - Each order is valued by rolling the tree's own per-AUV cost model (`CostModel::update`: the
//!   filters' covariance or the true-error moments, the link's success, the range bias, the same
//!   aggregate) level by level over the AUVs' forecast tracks, with the CNA flying a fixed
//!   macro-action per segment: straight at the AUV it serves until within `standoff_m`, then
//!   circling it at that radius, so the line of sight turns through every direction (the geometry
//!   that removes error along any axis, a current's drift included). Its costs are therefore in
//!   the tree's units, per level.
//! - The tree stays exact: the layer only adds a non-negative terminal term to every leaf, the
//!   price of the leaf's distance from the goal the best order serves first ([`GoalTerm`]):
//!   Δ per level of transit still to fly, where Δ is what the rollout says one level of delay
//!   costs (the best order's value after holding one level, minus its value now). The search
//!   still minimises its (now larger) path cost exactly, and its bounds add a lower bound of the
//!   term (the leaf is within the remaining levels' s·τ of any node), so branch-and-bound and the
//!   brute force agree bit for bit.
//!
//! The rollout is a model, not a plan the CNA flies: the tree is re-searched every τ and the
//! order is recomputed from that decision's states, so a served AUV's collapsed error moves the
//! goal on by itself.

mod rollout;

pub(crate) use rollout::{best_order, World};

use crate::planner::DistanceLimits;
use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// The horizon layer's settings. Every default is invented (docs/models.md#mission-horizon).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HorizonSpec {
    /// Whether the layer runs (true by default: `planner-estimator` a user flies has it).
    #[serde(default = "enabled")]
    pub enabled: bool,
    /// D: length of one service segment, s (> 0; whole τ steps are used, at least one).
    #[serde(default = "segment_s")]
    pub segment_s: f64,
    /// S: segments in a visiting order (1..=4); the horizon is S·D.
    #[serde(default = "segments")]
    pub segments: usize,
    /// Radius the rollout's CNA circles a served AUV at, and within which the goal term is 0, m (> 0).
    #[serde(default = "standoff_m")]
    pub standoff_m: f64,
    /// Factor on the delay price Δ of the goal term (≥ 0; 0 leaves the tree's decision as without
    /// the layer).
    #[serde(default = "weight")]
    pub weight: f64,
}

fn enabled() -> bool {
    true
}
fn segment_s() -> f64 {
    600.0
}
fn segments() -> usize {
    3
}
fn standoff_m() -> f64 {
    300.0
}
fn weight() -> f64 {
    1.0
}

impl Default for HorizonSpec {
    fn default() -> Self {
        HorizonSpec {
            enabled: enabled(),
            segment_s: segment_s(),
            segments: segments(),
            standoff_m: standoff_m(),
            weight: weight(),
        }
    }
}

impl HorizonSpec {
    /// Whether the layer takes over from Hudson's distance penalties (Table 5.2; the tree then
    /// has none, case "2"): when the survey spans more than twice the maximum CNA–AUV distance
    /// (`survey_extent_m`, the diagonal of the box around every AUV's plan), no CNA position keeps
    /// every AUV within it, so the look-ahead penalty doubles the cost of nearly every node alike
    /// and, in practice, holds the CNA between the blocks, far from all of them. Choosing which
    /// AUV to be near is then this layer's decision; the estimator-aware cost prices a far ping
    /// itself (the link's success, the range noise and bias).
    pub fn replaces_distance_penalties(&self, survey_extent_m: f64, limits: &DistanceLimits) -> bool {
        self.enabled && survey_extent_m > 2.0 * limits.max
    }
}

/// Most segments in an order: N^S rollouts, 4096 at N = 8.
pub const MAX_SEGMENTS: usize = 4;

impl CheckFields for HorizonSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.positive(&format!("{prefix}segment_s"), self.segment_s);
        p.check(
            &format!("{prefix}segments"),
            self.segments as f64,
            |s| (1.0..=MAX_SEGMENTS as f64).contains(&s),
            "1 <= segments <= 4",
        );
        p.positive(&format!("{prefix}standoff_m"), self.standoff_m);
        p.non_negative(&format!("{prefix}weight"), self.weight);
    }
}

/// What the layer hands the tree: the leaf term Δ'·max(0, |leaf − goal| − standoff) (horizontal),
/// with the goal the served AUV's forecast position at each tree level.
#[derive(Debug, Clone, PartialEq)]
pub struct GoalTerm {
    /// Fleet index of the AUV the best order serves first.
    pub target: usize,
    /// Δ·weight / (s·τ): the delay price per metre of transit left, cost units per m (≥ 0).
    pub per_metre: f64,
    pub standoff_m: f64,
    /// The target's forecast position at t + (l + 1)·τ, l = 0.. (the tree's levels).
    pub goal: Vec<[f64; 2]>,
}

impl GoalTerm {
    /// The term at a leaf on `level` with the CNA at `cna`.
    #[inline(always)]
    pub fn cost(&self, level: usize, cna: [f64; 3]) -> f64 {
        let g = self.goal[level.min(self.goal.len() - 1)];
        let d = ((cna[0] - g[0]).powi(2) + (cna[1] - g[1]).powi(2)).sqrt();
        self.per_metre * (d - self.standoff_m).max(0.0)
    }

    /// A lower bound of the term on the leaf (level `leaf`) of any path through a node with the
    /// CNA at `cna`, `levels` levels above the leaf: the CNA moves at most `step` per level.
    #[inline(always)]
    pub fn bound(&self, leaf: usize, cna: [f64; 3], levels: usize, step: f64) -> f64 {
        let g = self.goal[leaf.min(self.goal.len() - 1)];
        let d = ((cna[0] - g[0]).powi(2) + (cna[1] - g[1]).powi(2)).sqrt();
        self.per_metre * (d - self.standoff_m - levels as f64 * step).max(0.0) * (1.0 - 1e-9)
    }
}
