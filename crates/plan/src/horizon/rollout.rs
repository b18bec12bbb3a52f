//! The horizon layer's rollouts: the CNA's macro-action per service segment (fly at the served
//! AUV, then circle it) and the exhaustive search over visiting orders, each valued by stepping
//! the tree's own cost model level by level (module `horizon` says why).

use crate::cost_model::CostModel;

/// What a rollout knows of the mission: the AUVs' forecast positions per level, the CNA's start
/// and speed, and the orders' shape.
pub(crate) struct World {
    /// `auv[j * n + k]`: AUV k at t + (j + 1)·τ, j over the whole horizon (S·D/τ levels).
    pub auv: Vec<[f64; 3]>,
    pub n: usize,
    /// Levels per segment (≥ 1) and segments per order.
    pub levels_per_segment: usize,
    pub segments: usize,
    pub cna: [f64; 3],
    /// The CNA's step s·τ, m.
    pub step: f64,
    pub standoff: f64,
}

impl World {
    fn levels(&self) -> usize {
        self.levels_per_segment * self.segments
    }

    fn auv(&self, level: usize, k: usize) -> [f64; 3] {
        self.auv[level * self.n + k]
    }
}

/// The best visiting order and the price of delaying it by one level.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Order {
    /// Fleet index served in each segment.
    pub targets: Vec<usize>,
    /// Its rolled-out cost.
    pub value: f64,
    /// Its cost after the CNA first holds one level, minus `value` (≥ 0).
    pub delay: f64,
}

/// One level of the macro-action serving an AUV at `target`: straight at it while farther than
/// the standoff radius plus a step, else around it on that circle (counter-clockwise, radius
/// eased towards the standoff by at most one step), depth held.
#[inline(always)]
fn fly(cna: [f64; 3], target: [f64; 3], step: f64, standoff: f64) -> [f64; 3] {
    let (dx, dy) = (cna[0] - target[0], cna[1] - target[1]);
    let dist = (dx * dx + dy * dy).sqrt();
    if dist > standoff + step {
        let f = step / dist;
        return [cna[0] - dx * f, cna[1] - dy * f, cna[2]];
    }
    let angle = if dist > 1e-9 { dy.atan2(dx) } else { 0.0 } + step / standoff;
    let radius = dist + (standoff - dist).clamp(-step, step);
    [target[0] + radius * angle.cos(), target[1] + radius * angle.sin(), cna[2]]
}

/// Levels `from..to` of a rollout serving `target` from `cna` with `states`, the last level of the
/// horizon with the model's cost-to-go (`CostModel::leaf_term`), as the tree's leaves; `hold`:
/// the CNA stays where it is on level 0. Returns the CNA's end position and the levels' cost.
fn run<M: CostModel>(
    model: &M,
    world: &World,
    (from, to): (usize, usize),
    (target, hold): (usize, bool),
    mut cna: [f64; 3],
    states: &mut [M::State],
) -> ([f64; 3], f64) {
    let mut cost = 0.0;
    let last = world.levels() - 1;
    for j in from..to {
        if !(hold && j == 0) {
            cna = fly(cna, world.auv(j, target), world.step, world.standoff);
        }
        let mut level = 0.0;
        for (k, s) in states.iter_mut().enumerate() {
            let a = world.auv(j, k);
            let (next, term) = model.update(k, s, cna, a);
            let term = if j == last { model.leaf_term(k, &next, cna, a, term) } else { term };
            *s = next;
            level = model.combine(level, term);
        }
        cost += level;
    }
    (cna, cost)
}

/// The cost of the order `targets` rolled out from the root (`hold`: after one level held).
fn value<M: CostModel>(model: &M, world: &World, root: &[M::State], targets: &[usize], hold: bool) -> f64 {
    let mut states = root.to_vec();
    let (mut cna, mut cost) = (world.cna, 0.0);
    for (seg, &target) in targets.iter().enumerate() {
        let span = (seg * world.levels_per_segment, (seg + 1) * world.levels_per_segment);
        let (end, c) = run(model, world, span, (target, hold), cna, &mut states);
        cna = end;
        cost += c;
    }
    cost
}

/// Depth-first over every order, sharing each prefix's rollout; an order whose prefix already
/// costs at least the best complete one is cut (every term is ≥ 0). Ties keep the first found,
/// the lexicographically smallest order.
fn search<M: CostModel>(
    model: &M,
    world: &World,
    (seg, cna, acc): (usize, [f64; 3], f64),
    states: &[M::State],
    prefix: &mut Vec<usize>,
    best: &mut (f64, Vec<usize>),
) {
    let span = (seg * world.levels_per_segment, (seg + 1) * world.levels_per_segment);
    for target in 0..world.n {
        let mut next = states.to_vec();
        let (end, c) = run(model, world, span, (target, false), cna, &mut next);
        let total = acc + c;
        if total >= best.0 {
            continue;
        }
        prefix.push(target);
        if seg + 1 == world.segments {
            *best = (total, prefix.clone());
        } else {
            search(model, world, (seg + 1, end, total), &next, prefix, best);
        }
        prefix.pop();
    }
}

/// The best visiting order under `model` from the states `root` (fleet order), or None for an
/// empty fleet or a world with no levels.
pub(crate) fn best_order<M: CostModel>(model: &M, world: &World, root: &[M::State]) -> Option<Order> {
    if world.n == 0 || world.levels() == 0 || root.len() != world.n {
        return None;
    }
    let mut best = (f64::INFINITY, Vec::new());
    search(model, world, (0, world.cna, 0.0), root, &mut Vec::with_capacity(world.segments), &mut best);
    if best.1.is_empty() {
        return None;
    }
    let targets = best.1;
    let now = value(model, world, root, &targets, false);
    let held = value(model, world, root, &targets, true);
    Some(Order { value: now, delay: (held - now).max(0.0), targets })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_macro_action_flies_straight_at_a_far_auv_and_circles_a_near_one() {
        let far = fly([0.0, 0.0, 0.0], [1000.0, 0.0, 20.0], 60.0, 300.0);
        assert_eq!(far, [60.0, 0.0, 0.0]);
        // On the circle: the radius is kept and the bearing turns by step / radius.
        let on = fly([300.0, 0.0, 0.0], [0.0, 0.0, 20.0], 60.0, 300.0);
        assert!(((on[0].hypot(on[1])) - 300.0).abs() < 1e-9, "{on:?}");
        assert!((on[1].atan2(on[0]) - 0.2).abs() < 1e-12, "{on:?}");
        // Inside the circle the radius grows by at most one step.
        let inside = fly([10.0, 0.0, 0.0], [0.0, 0.0, 20.0], 60.0, 300.0);
        assert!((inside[0].hypot(inside[1]) - 70.0).abs() < 1e-9, "{inside:?}");
    }
}
