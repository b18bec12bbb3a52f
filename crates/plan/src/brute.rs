//! The plain reference search: enumerates every option sequence of the tree, recomputes each
//! path from the root, keeps the minimum path sum under each level-0 option and decides by
//! `tree::choose` (ties within the tolerance: lowest level-0 option index). It is deliberately
//! simple: it is what the production search is tested against. It reads the clock every 4096
//! paths, so a deadline stops it too.

use crate::cost_model::CostModel;
use crate::search::Shared;
use crate::tree::{choose, NodeRef, Tree};
use crate::SearchOutcome;

/// `None` when the deadline stopped it.
pub(crate) fn brute_force<M: CostModel>(tree: &Tree<M>, shared: &Shared) -> Option<SearchOutcome> {
    let (n, depth) = (tree.n, tree.depth);
    let mut state: Vec<M::State> = tree.root_state.iter().cycle().take(n * depth).copied().collect();
    let mut idx = vec![0usize; depth];
    let mut root_min = vec![f64::INFINITY; tree.n_options()];
    let mut nodes = 0u64;
    for path in 0u64.. {
        if path % 4096 == 0 && shared.check_clock() {
            return None;
        }
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
        let m = &mut root_min[tree.root_options[idx[0]]];
        *m = m.min(acc);
        if !advance(&mut idx, tree) {
            break;
        }
    }
    let (root_option, value) = choose(&root_min, tree.tie_tolerance).unwrap_or((usize::MAX, f64::INFINITY));
    Some(SearchOutcome { root_option, value, nodes })
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
