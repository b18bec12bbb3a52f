//! The production search: depth-first branch-and-bound over the look-ahead tree with
//! preallocated per-level buffers, children visited cheapest first, and a parallel mode over the
//! top two levels. It returns exactly the brute-force decision and minimum path cost:
//! - a subtree is cut only when its lower bound (path so far + a bound on the levels below: the
//!   per-level floor, then the node's own bound) is strictly greater than the best complete
//!   path known times (1 + tie tolerance), so no path within the tie tolerance of the minimum is
//!   ever cut, and the minimum under every level-0 option that ties is found exactly;
//! - the decision is `tree::choose` of those per-option minima (lowest option index among the
//!   ties), the same rule as the brute force; workers' minima are merged per option, so the
//!   result does not depend on thread timing;
//! - a node is abandoned part-way through its AUVs once the partial sum is cut (`tree::Cut`).
//!
//! The parallel mode orders the (level-0, level-1) subtrees by their lower bound, searches the
//! most promising one first on the calling thread to get a tight bound, then lets every worker
//! pull the remaining subtrees in that order, skipping those the bound already excludes.
//! Only the node count varies with the thread count.

use crate::cost_model::CostModel;
use crate::tree::{choose, Cut, NodeRef, Tree};
use crate::SearchOutcome;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

/// Preallocated buffers for the children of one level.
struct Level<S> {
    state: Vec<S>,
    pose: Vec<crate::motion::FastPose>,
    cost: Vec<f64>,
    order: Vec<usize>,
}

fn levels<M: CostModel>(tree: &Tree<M>) -> Vec<Level<M::State>> {
    let (m, n) = (tree.n_options(), tree.n);
    let any_state = tree.root_state[0];
    (0..tree.depth)
        .map(|_| Level {
            state: vec![any_state; m * n],
            pose: vec![tree.root_pose; m],
            cost: vec![0.0; m],
            order: Vec::with_capacity(m),
        })
        .collect()
}

/// Shared between workers: the best complete path value (f64 bits; non-negative floats order like
/// their bits), the abort flag and the deadline.
pub(crate) struct Shared {
    best_bits: AtomicU64,
    pub abort: AtomicBool,
    deadline: Option<Instant>,
}

impl Shared {
    pub fn new(deadline: Option<Instant>) -> Self {
        Shared { best_bits: AtomicU64::new(f64::INFINITY.to_bits()), abort: AtomicBool::new(false), deadline }
    }
    fn bound(&self) -> f64 {
        f64::from_bits(self.best_bits.load(Ordering::Relaxed))
    }
    fn offer(&self, v: f64) {
        self.best_bits.fetch_min(v.to_bits(), Ordering::Relaxed);
    }
    /// Reads the clock: raises the abort flag once the deadline has passed; true when aborted.
    pub fn check_clock(&self) -> bool {
        if let Some(d) = self.deadline {
            if Instant::now() >= d {
                self.abort.store(true, Ordering::Relaxed);
            }
        }
        self.abort.load(Ordering::Relaxed)
    }
}

/// One worker's search state.
struct Ctx<'s> {
    shared: &'s Shared,
    /// The best complete path this worker has seen.
    best: f64,
    /// 1 + the tie tolerance: what the best path is inflated by before cutting.
    slack: f64,
    /// The best complete path seen under each level-0 option.
    root_min: Vec<f64>,
    /// The level-0 option of the subtree being searched.
    root: usize,
    nodes: u64,
    /// Searches entered since the clock was last read (starts at 255: each worker reads it first).
    since_clock: u32,
}

impl<'s> Ctx<'s> {
    fn new<M: CostModel>(shared: &'s Shared, tree: &Tree<M>) -> Self {
        Ctx {
            shared,
            best: f64::INFINITY,
            slack: 1.0 + tree.tie_tolerance,
            root_min: vec![f64::INFINITY; tree.n_options()],
            root: usize::MAX,
            nodes: 0,
            since_clock: 255,
        }
    }
    /// Anything whose lower bound is above this is cut.
    fn bound(&self) -> f64 {
        self.best.min(self.shared.bound()) * self.slack
    }
    fn leaf(&mut self, v: f64) {
        let m = &mut self.root_min[self.root];
        *m = m.min(v);
        if v < self.best {
            self.best = v;
            self.shared.offer(v);
        }
    }
    /// Reads the clock every 256 subtree entries; true when the search must stop.
    fn out_of_time(&mut self) -> bool {
        self.since_clock += 1;
        if self.since_clock >= 256 {
            self.since_clock = 0;
            return self.shared.check_clock();
        }
        self.shared.abort.load(Ordering::Relaxed)
    }
    /// Joins another worker's findings into this one's.
    fn merge(&mut self, other: Ctx) {
        self.nodes += other.nodes;
        self.best = self.best.min(other.best);
        for (m, o) in self.root_min.iter_mut().zip(other.root_min) {
            *m = m.min(o);
        }
    }
    fn outcome(&self, tree_tolerance: f64) -> SearchOutcome {
        let (root_option, value) = choose(&self.root_min, tree_tolerance).unwrap_or((usize::MAX, f64::INFINITY));
        SearchOutcome { root_option, value, nodes: self.nodes }
    }
}

/// Expands every child of `parent` into `lv` (level `level`), dropping those `cut` removes, and
/// sorts the rest cheapest first.
fn expand_all<M: CostModel>(
    tree: &Tree<M>,
    level: usize,
    parent: &NodeRef<M::State>,
    lv: &mut Level<M::State>,
    ctx: &mut Ctx,
    cut: &Cut,
) {
    let n = tree.n;
    lv.order.clear();
    let options = tree.level_options(level);
    for &o in options {
        if let Some((p, c)) = tree.expand_within(level, parent, o, &mut lv.state[o * n..(o + 1) * n], cut) {
            lv.pose[o] = p;
            lv.cost[o] = c;
            lv.order.push(o);
        }
    }
    ctx.nodes += options.len() as u64;
    let cost = &lv.cost;
    // Stable sort keeps index order among equal costs.
    lv.order.sort_by(|&a, &b| cost[a].total_cmp(&cost[b]));
}

/// A node at `level` with path cost `v`: a leaf on the last level, else searched below unless its
/// bound is beaten.
fn visit<M: CostModel>(
    tree: &Tree<M>,
    level: usize,
    node: &NodeRef<M::State>,
    v: f64,
    deeper: &mut [Level<M::State>],
    ctx: &mut Ctx,
) {
    if level + 1 == tree.depth {
        ctx.leaf(v);
    } else if v + tree.rest_bound(level, node, ctx.bound() - v) <= ctx.bound() {
        dfs(tree, level + 1, node, v, deeper, ctx);
    }
}

/// Searches below `parent` (at level − 1) with path cost `acc` so far.
fn dfs<M: CostModel>(
    tree: &Tree<M>,
    level: usize,
    parent: &NodeRef<M::State>,
    acc: f64,
    levels: &mut [Level<M::State>],
    ctx: &mut Ctx,
) {
    if ctx.out_of_time() {
        return;
    }
    let (lv, deeper) = levels.split_first_mut().expect("one buffer per level");
    let cut = Cut { acc, floor: tree.rest_floor[level], bound: ctx.bound() };
    expand_all(tree, level, parent, lv, ctx, &cut);
    let n = tree.n;
    for i in 0..lv.order.len() {
        let o = lv.order[i];
        if level == 0 {
            ctx.root = o;
        }
        let v = acc + lv.cost[o];
        if v + tree.rest_floor[level] > ctx.bound() {
            break; // children are sorted: every later one is cut too
        }
        let child = NodeRef { pose: lv.pose[o], state: &lv.state[o * n..(o + 1) * n] };
        visit(tree, level, &child, v, deeper, ctx);
    }
}

/// Runs the search at the tree's full depth. `None` when the deadline stopped it.
pub(crate) fn branch_and_bound<M: CostModel>(tree: &Tree<M>, parallel: bool, shared: &Shared) -> Option<SearchOutcome> {
    let out = if parallel && tree.depth >= 2 {
        parallel_search(tree, shared)
    } else {
        let mut ctx = Ctx::new(shared, tree);
        dfs(tree, 0, &tree.root(), 0.0, &mut levels(tree), &mut ctx);
        ctx.outcome(tree.tie_tolerance)
    };
    (!shared.abort.load(Ordering::Relaxed)).then_some(out)
}

/// A (level-0, level-1) subtree of the parallel search, with its path cost and lower bound.
struct Subtree {
    root: usize,
    child: usize,
    cost: f64,
    bound: f64,
}

/// The (level-0, level-1) subtrees, most promising (lowest bound) first.
fn subtrees<M: CostModel>(tree: &Tree<M>, top: &Level<M::State>) -> Vec<Subtree> {
    let n = tree.n;
    let mut all: Vec<Subtree> = tree
        .root_options
        .par_iter()
        .flat_map_iter(|&r| {
            let parent = NodeRef { pose: top.pose[r], state: &top.state[r * n..(r + 1) * n] };
            let mut out = vec![tree.root_state[0]; n];
            tree.all_options
                .iter()
                .map(|&c| {
                    let (pose, c1) = tree.expand(1, &parent, c, &mut out);
                    let cost = top.cost[r] + c1;
                    let below = if tree.depth > 2 {
                        tree.rest_bound(1, &NodeRef { pose, state: &out }, f64::INFINITY)
                    } else {
                        0.0
                    };
                    Subtree { root: r, child: c, cost, bound: cost + below }
                })
                .collect::<Vec<_>>()
        })
        .collect();
    all.sort_by(|a, b| a.bound.total_cmp(&b.bound).then(a.root.cmp(&b.root)).then(a.child.cmp(&b.child)));
    all
}

/// Searches one (level-0, level-1) subtree; `below_top` holds the buffers of levels 1, 2, ….
fn search_subtree<M: CostModel>(
    tree: &Tree<M>,
    top: &Level<M::State>,
    task: &Subtree,
    below_top: &mut [Level<M::State>],
    ctx: &mut Ctx,
) {
    if task.bound > ctx.bound() || ctx.out_of_time() {
        return;
    }
    let n = tree.n;
    ctx.root = task.root;
    let parent = NodeRef { pose: top.pose[task.root], state: &top.state[task.root * n..(task.root + 1) * n] };
    let (level1, deeper) = below_top.split_first_mut().expect("depth >= 2");
    let buf = &mut level1.state[..n];
    let (pose, _) = tree.expand(1, &parent, task.child, buf);
    visit(tree, 1, &NodeRef { pose, state: buf }, task.cost, deeper, ctx);
}

/// Subtrees ordered by bound; the first searched alone for a tight bound, the rest pulled in order
/// by one worker per rayon thread; the per-option minima merged.
fn parallel_search<M: CostModel>(tree: &Tree<M>, shared: &Shared) -> SearchOutcome {
    let mut first = Ctx::new(shared, tree);
    let mut lv = levels(tree);
    let (top_slot, rest) = lv.split_first_mut().expect("depth >= 2");
    expand_all(tree, 0, &tree.root(), top_slot, &mut first, &Cut::NEVER);
    let top = &*top_slot;
    let tasks = subtrees(tree, top);
    first.nodes += tasks.len() as u64;
    search_subtree(tree, top, &tasks[0], rest, &mut first);
    let next = AtomicUsize::new(1);
    let workers = rayon::current_num_threads().max(1);
    let results: Vec<Ctx> = (0..workers)
        .into_par_iter()
        .map(|_| {
            let mut ctx = Ctx::new(shared, tree);
            let mut lv = levels(tree);
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= tasks.len() || shared.abort.load(Ordering::Relaxed) {
                    break;
                }
                search_subtree(tree, top, &tasks[i], &mut lv[1..], &mut ctx);
            }
            ctx
        })
        .collect();
    for r in results {
        first.merge(r);
    }
    first.outcome(tree.tie_tolerance)
}
