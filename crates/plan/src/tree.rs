//! One planning instance: the look-ahead tree's fixed data (options, predicted AUV positions per
//! level, penalties, the per-level cost floor) and the node expansion that both searches share,
//! so the brute-force reference and the production search evaluate every path bit-identically.
//!
//! Path costs are summed from the root down, ((c₀ + c₁) + c₂) + …, in both searches. On the last
//! level each AUV's term is the model's `CostModel::leaf_term` (at least 1 + H times the term, H
//! the model's cost-to-go in levels, `CostModel::terminal_levels`), in both searches; the bounds
//! count the last level 1 + H times.

use crate::cost_model::{norm, Below, CostModel};
use crate::horizon::GoalTerm;
use crate::motion::{FastOption, FastPose, MotionConfig};
use crate::penalty::{Penalty, PenaltyFn, PenaltyPair, Violation};
use crate::planner::DistanceLimits;

/// Most tree levels a search may have (L ≤ 63; validated in `PlannerConfig::validate`).
pub(crate) const MAX_LEVELS: usize = 64;

/// The data of one tree search on cost model `M`.
pub(crate) struct Tree<M: CostModel> {
    pub motion: MotionConfig,
    pub model: M,
    pub limits: DistanceLimits,
    pub penalties: PenaltyPair,
    pub options: Vec<FastOption>,
    /// Level-0 options left after removing those that break AUV-CNA limits (docs/models.md#hudson-motion).
    pub root_options: Vec<usize>,
    /// Every option index, 0..A·B (the options of levels ≥ 1 that offer the pitch options).
    pub all_options: Vec<usize>,
    /// The options that hold the pitch (least |Δφ|: 0 with an odd number of pitch options), those
    /// of the levels from `pitch_levels` on.
    pub held_pitch_options: Vec<usize>,
    /// Levels below this one offer every option, deeper ones `held_pitch_options` only
    /// (`CnaKind::Auv::pitch_levels`; ≥ depth: every level).
    pub pitch_levels: usize,
    /// Number of levels (L + 1, or fewer when the forecast ends: docs/models.md#hudson-search).
    pub depth: usize,
    pub n: usize,
    /// Predicted AUV positions, `auv[level * n + k]`, at t + (level + 1)·τ.
    pub auv: Vec<[f64; 3]>,
    pub root_pose: FastPose,
    pub root_state: Vec<M::State>,
    /// `rest_floor[l]`: a lower bound on the summed costs of levels l+1 .. depth−1, valid for every
    /// node at level l (used by branch-and-bound).
    pub rest_floor: Vec<f64>,
    /// `reach[j * n + k]` (j ≥ 1): how far AUV k's line of sight can move between levels j−1 and j,
    /// |Δa| + s·τ (AUV displacement plus the CNA's step), metres.
    pub reach: Vec<f64>,
    /// The CNA's step s·τ (3-D, every option), metres.
    pub step: f64,
    /// `SearchConfig::tie_tolerance`: level-0 options within this relative margin of the minimum tie.
    pub tie_tolerance: f64,
    /// The mission-long horizon's pull (`horizon::GoalTerm`), added to every leaf's penalised
    /// cost; None: no horizon layer.
    pub goal: Option<GoalTerm>,
}

/// When a node being expanded is cut: its path cost so far `acc` plus the raw cost summed over
/// the AUVs processed so far plus the floor of the levels below already exceeds `bound`. Every
/// cost term is ≥ 0, `combine` never decreases and every penalty keeps C' ≥ C, so the full,
/// penalised cost would be cut by the same test (`(acc + c) + floor > bound`, evaluated in the
/// same order, and floating-point addition is monotone).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cut {
    pub acc: f64,
    pub floor: f64,
    pub bound: f64,
}

impl Cut {
    /// Never cuts (the brute force and the parallel set-up).
    pub const NEVER: Cut = Cut { acc: 0.0, floor: 0.0, bound: f64::INFINITY };

    #[inline(always)]
    fn cuts(&self, raw: f64) -> bool {
        (self.acc + raw) + self.floor > self.bound
    }
}

/// The decision among the level-0 options from the minimum path cost found under each
/// (`f64::INFINITY` where none was found): the overall minimum V, and the lowest option index whose
/// minimum is ≤ V·(1 + tolerance). `None` when no path was found.
pub(crate) fn choose(root_min: &[f64], tolerance: f64) -> Option<(usize, f64)> {
    let v = root_min.iter().copied().fold(f64::INFINITY, f64::min);
    let limit = v * (1.0 + tolerance);
    root_min.iter().position(|&m| m <= limit).map(|o| (o, v))
}

/// A node's state as the search sees it.
pub(crate) struct NodeRef<'a, S> {
    pub pose: FastPose,
    pub state: &'a [S],
}

impl<S> Clone for NodeRef<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<S> Copy for NodeRef<'_, S> {}

impl<M: CostModel> Tree<M> {
    pub fn root(&self) -> NodeRef<'_, M::State> {
        NodeRef { pose: self.root_pose, state: &self.root_state }
    }

    pub fn n_options(&self) -> usize {
        self.options.len()
    }

    /// Options of `level` in index order.
    pub fn level_options(&self, level: usize) -> &[usize] {
        if level == 0 {
            &self.root_options
        } else if level < self.pitch_levels {
            &self.all_options
        } else {
            &self.held_pitch_options
        }
    }

    /// How many nodes the top `levels` levels hold (every option expanded), saturating at
    /// `u64::MAX` (a deadline's fit check asks it of the full tree, whatever its size).
    pub fn nodes_above(&self, levels: usize) -> u64 {
        let mut width = 1u64;
        (0..levels)
            .map(|l| {
                width = width.saturating_mul(self.level_options(l).len() as u64);
                width
            })
            .fold(0, u64::saturating_add)
    }

    /// The factor of the last level's terms, 1 + H (`CostModel::terminal_levels`).
    #[inline(always)]
    pub fn leaf_weight(&self) -> f64 {
        1.0 + self.model.terminal_levels()
    }

    /// A lower bound on the summed costs of levels `level`+1 .. depth−1 below `node` (at `level`).
    /// - Cost: the model's own bound per AUV and level (`CostModel::bound_rest`).
    /// - Distance: j levels below, the CNA is within j·s·τ of its position at the node and the
    ///   AUV is where it is predicted, so when some AUV is surely beyond the maximum (or within the
    ///   minimum) distance at a level, a doubling look-ahead penalty surely applies there. Other
    ///   penalties count as ×1 (they never lower a cost).
    ///
    /// The AUVs are summed one by one, and the sum so far (a lower bound too: every term is ≥ 0)
    /// is returned as soon as it exceeds `budget`, so a node that is cut costs less. A relative
    /// margin of 1e-9 absorbs rounding.
    pub fn rest_bound(&self, level: usize, node: &NodeRef<M::State>, budget: f64) -> f64 {
        let (n, p, levels) = (self.n, node.pose.p, level + 1..self.depth);
        let below = |k: usize| {
            levels.clone().map(move |j| Below {
                auv: self.auv[j * n + k],
                spread: (j - level) as f64 * self.step,
                turn: self.reach[j * n + k],
            })
        };
        let mut weight = [1.0f64; MAX_LEVELS];
        if matches!(self.penalties.look_ahead, PenaltyFn::Doubling {}) {
            let (lo, hi) = (self.limits.min, self.limits.max);
            for k in 0..n {
                for (w, b) in weight[levels.clone()].iter_mut().zip(below(k)) {
                    if *w == 2.0 {
                        continue; // one AUV out of the limits is enough
                    }
                    let d = norm([b.auv[0] - p[0], b.auv[1] - p[1], b.auv[2] - p[2]]);
                    if d - b.spread > hi * (1.0 + 1e-9) || d + b.spread < lo * (1.0 - 1e-9) {
                        *w = 2.0;
                    }
                }
            }
        }
        // The last level's terms count 1 + H times (`leaf_weight`), the penalty's ×2 on top.
        weight[self.depth - 1] *= self.leaf_weight();
        let mut per_level = [0.0f64; MAX_LEVELS];
        let mut total = 0.0;
        for k in 0..n {
            let a = self.auv[level * n + k];
            self.model.bound_rest(k, &node.state[k], p, a, below(k), &mut per_level[levels.clone()]);
            total = levels.clone().map(|j| weight[j] * per_level[j]).sum::<f64>() * (1.0 - 1e-9);
            if total > budget {
                break;
            }
        }
        match &self.goal {
            Some(g) if level + 1 < self.depth => total + g.bound(self.depth - 1, p, self.depth - 1 - level, self.step),
            _ => total,
        }
    }

    /// Expands `parent` (a node at level − 1, or the root) by option `opt` into a node at `level`:
    /// writes the child's per-AUV states into `out` and returns its pose and penalised cost.
    #[inline(always)]
    pub fn expand(
        &self,
        level: usize,
        parent: &NodeRef<M::State>,
        opt: usize,
        out: &mut [M::State],
    ) -> (FastPose, f64) {
        self.expand_within(level, parent, opt, out, &Cut::NEVER).expect("never cut")
    }

    /// [`Tree::expand`], stopping early (`None`, `out` partly written) once `cut` applies to the
    /// raw cost summed so far.
    #[inline(always)]
    pub fn expand_within(
        &self,
        level: usize,
        parent: &NodeRef<M::State>,
        opt: usize,
        out: &mut [M::State],
        cut: &Cut,
    ) -> Option<(FastPose, f64)> {
        self.expand_into(level, parent, opt, Some(out), cut)
    }

    /// The cost of the leaf `parent` → `opt` on the last level as [`Tree::expand_within`] gives
    /// it, bit for bit; the leaf's states are not kept (no level reads them), which spares the
    /// search most of the last level's work.
    #[inline(always)]
    pub fn leaf_within(&self, level: usize, parent: &NodeRef<M::State>, opt: usize, cut: &Cut) -> Option<f64> {
        debug_assert_eq!(level + 1, self.depth, "only the last level's states are never read");
        self.expand_into(level, parent, opt, None, cut).map(|(_, c)| c)
    }

    #[inline(always)]
    fn expand_into(
        &self,
        level: usize,
        parent: &NodeRef<M::State>,
        opt: usize,
        mut out: Option<&mut [M::State]>,
        cut: &Cut,
    ) -> Option<(FastPose, f64)> {
        let pose = self.motion.step(&parent.pose, &self.options[opt]);
        let auv = &self.auv[level * self.n..(level + 1) * self.n];
        let (mut raw, mut dmin2, mut dmax2) = (0.0, f64::INFINITY, 0.0f64);
        let leaf = level + 1 == self.depth;
        for k in 0..self.n {
            let a = auv[k];
            let d = [a[0] - pose.p[0], a[1] - pose.p[1], a[2] - pose.p[2]];
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            dmin2 = dmin2.min(d2);
            dmax2 = dmax2.max(d2);
            let term = match out.as_deref_mut() {
                Some(out) => {
                    let (state, term) = self.model.update(k, &parent.state[k], pose.p, a);
                    out[k] = state;
                    if leaf {
                        self.model.leaf_term(k, &state, pose.p, a, term)
                    } else {
                        term
                    }
                }
                None => self.model.leaf_cost(k, &parent.state[k], pose.p, a),
            };
            raw = self.model.combine(raw, term);
            if cut.cuts(raw) {
                return None;
            }
        }
        let cost = self.penalise(level, &pose, raw, dmin2, dmax2);
        match &self.goal {
            Some(g) if leaf => Some((pose, cost + g.cost(level, pose.p))),
            _ => Some((pose, cost)),
        }
    }

    #[inline(always)]
    fn penalise(&self, level: usize, pose: &FastPose, raw: f64, dmin2: f64, dmax2: f64) -> f64 {
        let (lo, hi) = (self.limits.min, self.limits.max);
        let v = Violation {
            too_close: if dmin2 < lo * lo { lo - dmin2.sqrt() } else { 0.0 },
            too_far: if dmax2 > hi * hi { dmax2.sqrt() - hi } else { 0.0 },
        };
        if level == 0 {
            return self.penalties.primary.apply(raw, &v);
        }
        let c = if v.any() { self.penalties.look_ahead.apply(raw, &v) } else { raw };
        // Look-ahead AUV-CNA pitch/depth violations double the cost (Hudson 2012, Sec. 5.2).
        if self.motion.limit_violation(pose) > 0.0 {
            2.0 * c
        } else {
            c
        }
    }
}

/// `rest_floor` of [`Tree`] from the model's per-level floors: every penalty keeps C' ≥ C, so
/// the floor of levels l+1.. is the sum of their raw floors, the last one times `leaf_weight`
/// (`Tree::leaf_weight`). A relative margin of 1e-9 absorbs rounding.
pub(crate) fn rest_floors(level_floor: &[f64], leaf_weight: f64) -> Vec<f64> {
    let mut floor = level_floor.to_vec();
    if let Some(last) = floor.last_mut() {
        *last *= leaf_weight;
    }
    (0..floor.len()).map(|l| floor[l + 1..].iter().sum::<f64>() * (1.0 - 1e-9)).collect()
}

/// `reach` of [`Tree`]: per level j ≥ 1 and AUV k, |a_j − a_{j−1}| + s·τ (level 0 unused, 0).
pub(crate) fn reaches(auv: &[[f64; 3]], n: usize, step: f64) -> Vec<f64> {
    let depth = auv.len() / n.max(1);
    let mut r = vec![0.0; auv.len()];
    for j in 1..depth {
        for k in 0..n {
            let (a, b) = (auv[j * n + k], auv[(j - 1) * n + k]);
            r[j * n + k] = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt() + step;
        }
    }
    r
}
