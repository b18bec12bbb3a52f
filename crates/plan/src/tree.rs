//! One planning instance: the look-ahead tree's fixed data (options, predicted AUV positions per
//! level, penalties, the per-level cost floor) and the node expansion that both searches share,
//! so the brute-force reference and the production search evaluate every path bit-identically.
//!
//! Path costs are summed from the root down, ((c₀ + c₁) + c₂) + …, in both searches.

use crate::error_model::{tangential_update, ErrorModel};
use crate::motion::{FastOption, FastPose, MotionConfig};
use crate::penalty::{Penalty, PenaltyFn, PenaltyPair, Violation};
use crate::planner::DistanceLimits;

/// Most tree levels a search may have (L ≤ 63; validated in `PlannerConfig::validate`).
pub(crate) const MAX_LEVELS: usize = 64;

/// The data of one tree search.
pub(crate) struct Tree {
    pub motion: MotionConfig,
    pub model: ErrorModel,
    pub limits: DistanceLimits,
    pub penalties: PenaltyPair,
    pub options: Vec<FastOption>,
    /// Level-0 options left after removing those that break AUV-CNA limits (A5).
    pub root_options: Vec<usize>,
    /// Every option index, 0..A·B (the options of levels ≥ 1).
    pub all_options: Vec<usize>,
    /// Number of levels (L + 1, or fewer when the forecast ends: A11).
    pub depth: usize,
    pub n: usize,
    /// Predicted AUV positions, `auv[level * n + k]`, at t + (level + 1)·τ.
    pub auv: Vec<[f64; 3]>,
    pub sigma2: Vec<f64>,
    pub alpha_tau: f64,
    pub root_pose: FastPose,
    pub root_eps2: Vec<f64>,
    pub root_los: Vec<[f64; 3]>,
    /// `rest_floor[l]`: a lower bound on the summed costs of levels l+1 .. depth−1, valid for every
    /// node at level l (used by branch-and-bound).
    pub rest_floor: Vec<f64>,
    /// `reach[j * n + k]` (j ≥ 1): how far AUV k's line of sight can move between levels j−1 and j,
    /// |Δa| + s·τ (AUV displacement plus the CNA's step), metres.
    pub reach: Vec<f64>,
}

/// A node's state as the search sees it.
#[derive(Clone, Copy)]
pub(crate) struct NodeRef<'a> {
    pub pose: FastPose,
    pub eps2: &'a [f64],
    pub los: &'a [[f64; 3]],
}

impl Tree {
    pub fn root(&self) -> NodeRef<'_> {
        NodeRef { pose: self.root_pose, eps2: &self.root_eps2, los: &self.root_los }
    }

    pub fn n_options(&self) -> usize {
        self.options.len()
    }

    /// Options of `level` in index order.
    pub fn level_options(&self, level: usize) -> &[usize] {
        if level == 0 {
            &self.root_options
        } else {
            &self.all_options
        }
    }

    /// A lower bound on the summed costs of levels `level`+1 .. depth−1 below `node` (at `level`).
    /// - Bearing: the line of sight to AUV k can turn by at most asin(r/D) in a step when it moves
    ///   by r ≤ reach and is D ≥ |los| − (earlier reaches) long, so sin²Δθ ≤ S = (r/D)² (or 1), and
    ///   eq. (1a) gives ε'² ≥ σ²·S + ε²·(1 − S) + ατ when ε² > σ² (else ε² + ατ).
    /// - Distance: the 3-D CNA–AUV distance changes by at most the same reach per level, so when
    ///   some AUV is surely beyond the maximum (or within the minimum) distance at a level, a
    ///   doubling look-ahead penalty surely applies there. Other penalties count as ×1 (they never
    ///   lower a cost).
    ///
    /// A relative margin of 1e-9 absorbs rounding.
    pub fn rest_bound(&self, level: usize, node: &NodeRef) -> f64 {
        let mut per_level = [0.0f64; MAX_LEVELS];
        let mut violated = [false; MAX_LEVELS];
        let doubling = matches!(self.penalties.look_ahead, PenaltyFn::Doubling {});
        let auv = &self.auv[level * self.n..(level + 1) * self.n];
        let p = node.pose.p;
        let (lo, hi) = (self.limits.min, self.limits.max);
        for (k, a) in auv.iter().enumerate() {
            let s2 = self.sigma2[k];
            let mut x = node.eps2[k];
            let l = node.los[k];
            let mut dist = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
            let d3 = ((a[0] - p[0]).powi(2) + (a[1] - p[1]).powi(2) + (a[2] - p[2]).powi(2)).sqrt();
            let (mut near, mut far) = (d3, d3);
            for j in level + 1..self.depth {
                let r = self.reach[j * self.n + k];
                let smax = if dist > r { (r / dist) * (r / dist) } else { 1.0 };
                x = if s2 < x { s2 * smax + x * (1.0 - smax) + self.alpha_tau } else { x + self.alpha_tau };
                per_level[j] += self.model.cost_term(s2, x);
                dist -= r;
                near -= r;
                far += r;
                violated[j] |= near > hi * (1.0 + 1e-9) || far < lo * (1.0 - 1e-9);
            }
        }
        let total: f64 = (level + 1..self.depth)
            .map(|j| if doubling && violated[j] { 2.0 * per_level[j] } else { per_level[j] })
            .sum();
        total * (1.0 - 1e-9)
    }

    /// Expands `parent` (a node at level − 1, or the root) by option `opt` into a node at `level`:
    /// writes the child's ε² and lines of sight into `out_eps2`/`out_los` and returns its pose and
    /// penalised cost.
    #[inline(always)]
    pub fn expand(
        &self,
        level: usize,
        parent: &NodeRef,
        opt: usize,
        out_eps2: &mut [f64],
        out_los: &mut [[f64; 3]],
    ) -> (FastPose, f64) {
        let pose = self.motion.step(&parent.pose, &self.options[opt]);
        let auv = &self.auv[level * self.n..(level + 1) * self.n];
        let (mut raw, mut dmin2, mut dmax2) = (0.0, f64::INFINITY, 0.0f64);
        for k in 0..self.n {
            let a = auv[k];
            let d = [a[0] - pose.p[0], a[1] - pose.p[1], a[2] - pose.p[2]];
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            dmin2 = dmin2.min(d2);
            dmax2 = dmax2.max(d2);
            let los = self.model.los(pose.p, a);
            let (e2, l) = tangential_update(self.sigma2[k], parent.eps2[k], &parent.los[k], los, self.alpha_tau);
            out_eps2[k] = e2;
            out_los[k] = l;
            raw += self.model.cost_term(self.sigma2[k], e2);
        }
        (pose, self.penalise(level, &pose, raw, dmin2, dmax2))
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
        // Look-ahead AUV-CNA pitch/depth violations double the cost (Sec. 5.2, A5).
        if self.motion.limit_violation(pose) > 0.0 {
            2.0 * c
        } else {
            c
        }
    }
}

/// Per-level lower bounds on the cost, independent of the path: ε² at level j is at least m_j
/// with m₀ = min(σ², ε₀²) + ατ and m_{j+1} = min(σ², m_j) + ατ (eq. 1a is a convex combination of
/// σ² and ε² plus ατ), and every penalty keeps C' ≥ C. A relative margin of 1e-9 absorbs rounding.
pub(crate) fn rest_floors(model: &ErrorModel, sigma2: &[f64], eps2: &[f64], alpha_tau: f64, depth: usize) -> Vec<f64> {
    let mut m: Vec<f64> = eps2.to_vec();
    let mut level_floor = Vec::with_capacity(depth);
    for _ in 0..depth {
        let mut f = 0.0;
        for (mk, &s2) in m.iter_mut().zip(sigma2) {
            *mk = mk.min(s2) + alpha_tau;
            f += model.cost_term(s2, *mk);
        }
        level_floor.push(f);
    }
    (0..depth).map(|l| level_floor[l + 1..].iter().sum::<f64>() * (1.0 - 1e-9)).collect()
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
