//! The per-AUV cost models the tree search runs on, behind one small trait: how one survey AUV's
//! error state moves through one look-ahead level (a τ step ending with a ping from the CNA's new
//! pose), what that level costs, and a lower bound on the levels below a node (branch-and-bound).
//!
//! Two models: [`HudsonCost`], the isotropic tangential model of Hudson eq. (1) (`error_model`),
//! and `estimator::EstimatorCost`, the survey AUVs' own EKF covariances.

use crate::error_model::{tangential_update, ErrorModel};

/// One per-AUV cost model. Implementations must make `bound_rest` and `level_floors` true lower
/// bounds of what `update` produces along any path, keep every cost term ≥ 0 and `combine`
/// non-decreasing in both arguments (a partly summed level cost is then a lower bound of the
/// whole, `tree::Cut`), or branch-and-bound stops being exact.
pub(crate) trait CostModel: Sync {
    /// One AUV's error state at a node.
    type State: Copy + Send + Sync;

    /// AUV `k`'s state after one level ending with a ping from `cna` to the AUV at `auv`, and
    /// its cost term.
    fn update(&self, k: usize, parent: &Self::State, cna: [f64; 3], auv: [f64; 3]) -> (Self::State, f64);

    /// Cost-to-go beyond the horizon as H ≥ 0 further levels at each AUV's leaf term: on the last
    /// level every term counts 1 + H times. Being a fixed factor, it scales the last level's
    /// bounds and floor alike (sum and max commute with it), so they stay lower bounds
    /// (`Tree::leaf_weight`). Default: none (Hudson's model).
    #[inline(always)]
    fn terminal_levels(&self) -> f64 {
        0.0
    }

    /// AUV `k`'s term on the last level, with the cost-to-go: `term` and `state` are what
    /// `update` returned for the ping from `cna` to the AUV at `auv`. Must be ≥ (1 + H)·term
    /// (H = `terminal_levels`), what the bounds assume of it (up to their 1e-9 margin).
    #[inline(always)]
    fn leaf_term(&self, _k: usize, _state: &Self::State, _cna: [f64; 3], _auv: [f64; 3], term: f64) -> f64 {
        term * (1.0 + self.terminal_levels())
    }

    /// AUV `k`'s term on the last level when its state is not kept: `leaf_term` of what
    /// `update` gives, bit for bit (the searches' leaves use this, the brute force the pair, and
    /// the branch-and-bound proptest compares them). A model overrides it to share the work of
    /// the two.
    #[inline(always)]
    fn leaf_cost(&self, k: usize, parent: &Self::State, cna: [f64; 3], auv: [f64; 3]) -> f64 {
        let (state, term) = self.update(k, parent, cna, auv);
        self.leaf_term(k, &state, cna, auv, term)
    }

    /// Joins one AUV's term into a level's raw cost (sum, or max for worst-AUV).
    fn combine(&self, acc: f64, term: f64) -> f64;

    /// Lower bounds on AUV `k`'s cost terms at each level below a node, combined into `out`
    /// (`out[i]` is the i-th level below). The node has the CNA at `cna` and the AUV at `auv`;
    /// `below` yields what is known of each level below ([`Below`]).
    fn bound_rest(
        &self,
        k: usize,
        state: &Self::State,
        cna: [f64; 3],
        auv: [f64; 3],
        below: impl Iterator<Item = Below>,
        out: &mut [f64],
    );

    /// Path-independent lower bounds on the raw cost of each level 0..depth from the root states.
    fn level_floors(&self, root: &[Self::State], depth: usize) -> Vec<f64>;

    /// What `bound_rest` over every AUV costs per level below a node, in node expansions: the
    /// search skips the bound at the levels where its cuts saved fewer nodes than that
    /// (`search::BoundStats`; 0: always computed). Default: about one expansion (the
    /// estimator-aware bound's two chains cost a few covariance updates per AUV and level).
    const BOUND_COST: f64 = 1.0;
}

/// What a bound knows of one AUV at one level below a node: the AUV's path is predicted, the
/// CNA's is not, but it moves exactly s·τ per level.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Below {
    /// The AUV's predicted position at that level.
    pub auv: [f64; 3],
    /// How far the CNA can be from its position at the node by then: (levels below) · s·τ. So
    /// the line of sight at that level is within `spread` of `auv − cna`.
    pub spread: f64,
    /// How far the line of sight can move within that level: |Δa| + s·τ.
    pub turn: f64,
}

/// The 3-D length of a vector.
#[inline(always)]
pub(crate) fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Hudson's state of one AUV: tangential variance ε² and the line of sight of the last range.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tangential {
    pub eps2: f64,
    pub los: [f64; 3],
}

/// Hudson eq. (1) with the per-AUV radial variances σ² of this decision.
pub(crate) struct HudsonCost {
    pub model: ErrorModel,
    pub sigma2: Vec<f64>,
    pub alpha_tau: f64,
}

impl CostModel for HudsonCost {
    type State = Tangential;

    /// Always computed: a few operations per AUV and level, and skipping it where it seldom cut
    /// made Hudson's trees slower (`coopnav bench planner`).
    const BOUND_COST: f64 = 0.0;

    #[inline(always)]
    fn update(&self, k: usize, parent: &Tangential, cna: [f64; 3], auv: [f64; 3]) -> (Tangential, f64) {
        let los = self.model.los(cna, auv);
        let (eps2, los) = tangential_update(self.sigma2[k], parent.eps2, &parent.los, los, self.alpha_tau);
        (Tangential { eps2, los }, self.model.cost_term(self.sigma2[k], eps2))
    }

    #[inline(always)]
    fn combine(&self, acc: f64, term: f64) -> f64 {
        acc + term
    }

    /// The line of sight to AUV k can turn by at most asin(r/D) in a level when it moves by
    /// r ≤ turn and was D long before (D ≥ |a − c| − spread at the level above, the node's own
    /// line of sight at the first level below), so sin²Δθ ≤ S = (r/D)² (or 1), and eq. (1a) gives
    /// ε'² ≥ σ²·S + ε²·(1 − S) + ατ when ε² > σ² (else ε² + ατ).
    fn bound_rest(
        &self,
        k: usize,
        state: &Tangential,
        cna: [f64; 3],
        _auv: [f64; 3],
        below: impl Iterator<Item = Below>,
        out: &mut [f64],
    ) {
        let s2 = self.sigma2[k];
        let mut x = state.eps2;
        let mut dist = norm(state.los);
        for (slot, b) in out.iter_mut().zip(below) {
            let smax = if dist > b.turn { (b.turn / dist) * (b.turn / dist) } else { 1.0 };
            x = if s2 < x { s2 * smax + x * (1.0 - smax) + self.alpha_tau } else { x + self.alpha_tau };
            *slot += self.model.cost_term(s2, x);
            dist = norm(self.model.los(cna, b.auv)) - b.spread;
        }
    }

    /// ε² at level j is at least m_j with m₀ = min(σ², ε₀²) + ατ and m_{j+1} = min(σ², m_j) + ατ
    /// (eq. 1a is a convex combination of σ² and ε² plus ατ).
    fn level_floors(&self, root: &[Tangential], depth: usize) -> Vec<f64> {
        let mut m: Vec<f64> = root.iter().map(|s| s.eps2).collect();
        (0..depth)
            .map(|_| {
                let mut f = 0.0;
                for (mk, &s2) in m.iter_mut().zip(&self.sigma2) {
                    *mk = mk.min(s2) + self.alpha_tau;
                    f += self.model.cost_term(s2, *mk);
                }
                f
            })
            .collect()
    }
}
