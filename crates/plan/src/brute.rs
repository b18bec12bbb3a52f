//! The plain reference search: enumerates every option sequence of the tree, recomputes each
//! path from the root, and keeps the minimum path sum (ties: lowest level-0 option index).
//! It is deliberately simple: it is what the production search is tested against.

use crate::cost_model::CostModel;
use crate::tree::{NodeRef, Tree};
use crate::SearchOutcome;

pub(crate) fn brute_force<M: CostModel>(tree: &Tree<M>) -> SearchOutcome {
    let (n, depth) = (tree.n, tree.depth);
    let mut state: Vec<M::State> = tree.root_state.iter().cycle().take(n * depth).copied().collect();
    let mut idx = vec![0usize; depth];
    let (mut best, mut best_root) = (f64::INFINITY, usize::MAX);
    let mut nodes = 0u64;
    loop {
        let mut acc = 0.0;
        let mut pose = tree.root_pose;
        for (l, &i) in idx.iter().enumerate() {
            let opt = tree.level_options(l)[i];
            let (above, here) = state.split_at_mut(l * n);
            let parent = if l == 0 { tree.root() } else { NodeRef { pose, state: &above[(l - 1) * n..] } };
            let (p, c) = tree.expand(l, &parent, opt, &mut here[..n]);
            pose = p;
            acc += c;
            nodes += 1;
        }
        let root = tree.root_options[idx[0]];
        if acc < best || (acc == best && root < best_root) {
            best = acc;
            best_root = root;
        }
        if !advance(&mut idx, tree) {
            break;
        }
    }
    SearchOutcome { root_option: best_root, value: best, nodes }
}

/// Odometer over option sequences, the deepest level turning fastest. False when exhausted.
fn advance<M: CostModel>(idx: &mut [usize], tree: &Tree<M>) -> bool {
    for l in (0..idx.len()).rev() {
        idx[l] += 1;
        if idx[l] < tree.level_options(l).len() {
            return true;
        }
        idx[l] = 0;
    }
    false
}
