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
//! - a node is abandoned part-way through its AUVs once the partial sum is cut (`tree::Cut`);
//! - the bound below a node is computed only at the levels where its cuts have paid for it so
//!   far (`BoundStats`); a bound not computed cuts nothing, so this changes only node counts.
//!
//! The parallel mode starts as the one-thread search on the calling thread; a tree that needs
//! more than `SearchConfig::parallel_after_nodes` nodes and `parallel_after_us` µs is then split: the top two or three levels
//! become tasks ordered by their lower bound, and every worker pulls them in that order, sharing
//! the best path found (an atomic, seeded by the start) and skipping the tasks the start finished
//! or the best path excludes. Small trees never wake the threads (rayon's overhead made them
//! slower than one thread). Only the node count varies with the thread count and the hand-over.

use crate::cost_model::CostModel;
use crate::tree::{choose, Cut, NodeRef, Tree};
use crate::{SearchConfig, SearchOutcome};
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

/// What the bound below a node ([`Tree::rest_bound`]) bought at one level: how often it cut
/// the node's subtree, and how many nodes the subtrees it did not cut held. The estimator-aware
/// bound costs about an expansion per level below (`CostModel::BOUND_COST`), and far above the
/// leaves, where the last level's weight (1 + H) dominates every path and the CNA may yet move
/// anywhere, it seldom cuts (N = 5, L = 5, the sloping scenario: none of the nodes of levels 0–2
/// and 4 % of level 3's, against 74 % one level above the leaves). So a level where the nodes its
/// cuts saved fall short of its cost is searched without it, but for one node in
/// [`BoundStats::SAMPLE`] that keeps the count current. A bound not computed cuts nothing, so only
/// the node count depends on this, never the decision or its cost.
#[derive(Debug, Clone, Copy, Default)]
struct BoundStats {
    tried: u64,
    cut: u64,
    skipped: u64,
    /// Subtrees searched below this level, and their nodes.
    searched: u64,
    below: u64,
}

impl BoundStats {
    /// Tries at a level before the counts decide.
    const WARM_UP: u64 = 16;
    /// A level searched without the bound still tries it at one node in this many.
    const SAMPLE: u64 = 16;

    /// Whether to compute the bound at the next node of this level, where it costs as much as
    /// expanding `cost` nodes (0: always).
    #[inline(always)]
    fn worth_trying(&mut self, cost: f64) -> bool {
        // Until a subtree below was searched, what a cut saves is unknown.
        if self.tried < Self::WARM_UP || self.searched == 0 {
            return true;
        }
        // cut/tried · below/searched ≥ cost, without the divisions.
        let saved = self.cut as f64 * self.below as f64;
        if saved >= cost * self.tried as f64 * self.searched as f64 {
            return true;
        }
        self.skipped += 1;
        self.skipped % Self::SAMPLE == 0
    }

    #[inline(always)]
    fn record(&mut self, cut: bool) {
        self.tried += 1;
        self.cut += u64::from(cut);
    }

    #[inline(always)]
    fn searched(&mut self, nodes: u64) {
        self.searched += 1;
        self.below += nodes;
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
    /// The parallel mode's one-thread start (`None`: search to the end).
    start: Option<Start>,
    /// Per level: how often its bound cut.
    bounds: Vec<BoundStats>,
}

/// The one-thread start of the parallel mode (`SearchConfig::parallel_after_nodes`).
struct Start {
    /// Nodes it may expand before the rest of the tree is shared.
    budget: u64,
    /// Nor is it shared before this instant (`SearchConfig::parallel_after_us`; None: no floor).
    not_before: Option<Instant>,
    /// The levels the tasks span (`split_levels`), and the path to the node being searched there.
    split: usize,
    path: [usize; MAX_SPLIT],
    /// The task paths whose subtrees it searched to the end.
    finished: Vec<[usize; MAX_SPLIT]>,
    /// The budget ran out: the search stopped part-way.
    spent: bool,
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
            start: None,
            bounds: vec![BoundStats::default(); tree.depth],
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
    /// Reads the clock every 256 subtree entries (and on each entry once the start's node budget
    /// is spent and its time floor not yet passed); true when the search must stop (the deadline
    /// passed or the start's budget is spent).
    fn out_of_time(&mut self) -> bool {
        if let Some(start) = &mut self.start {
            if self.nodes >= start.budget && start.not_before.is_none_or(|t| Instant::now() >= t) {
                start.spent = true;
                return true;
            }
        }
        self.since_clock += 1;
        if self.since_clock >= 256 {
            self.since_clock = 0;
            return self.shared.check_clock();
        }
        self.shared.abort.load(Ordering::Relaxed)
    }
    /// True once the search has stopped part-way (deadline or spent budget).
    fn stopped(&self) -> bool {
        self.start.as_ref().is_some_and(|s| s.spent) || self.shared.abort.load(Ordering::Relaxed)
    }
    /// Option `o` is searched at `level`.
    fn enter(&mut self, level: usize, o: usize) {
        if level == 0 {
            self.root = o;
        }
        if let Some(start) = &mut self.start {
            if level < start.split {
                start.path[level] = o;
            }
        }
    }
    /// Whether the options of `level` need no bookkeeping ([`Ctx::enter`], [`Ctx::finished`]):
    /// below level 0 and below the parallel start's task levels.
    fn leaves_unrecorded(&self, level: usize) -> bool {
        level > 0 && self.start.as_ref().is_none_or(|s| level >= s.split)
    }
    /// The subtree entered at `level` was searched to the end: the start records a task's.
    fn finished(&mut self, level: usize) {
        if let Some(start) = &mut self.start {
            if level + 1 == start.split {
                start.finished.push(start.path);
            }
        }
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
    sort_by_cost(&mut lv.order, &lv.cost);
}

/// Sorts the children `order` cheapest first by `cost`, equal costs kept in index order (a
/// stable sort). A node has few children (A·B), where an insertion sort beats the library's.
pub(crate) fn sort_by_cost(order: &mut [usize], cost: &[f64]) {
    if order.len() > 32 {
        order.sort_by(|&a, &b| cost[a].total_cmp(&cost[b]));
        return;
    }
    for i in 1..order.len() {
        let o = order[i];
        let mut j = i;
        while j > 0 && cost[order[j - 1]].total_cmp(&cost[o]).is_gt() {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = o;
    }
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
        return;
    }
    // A bound that costs nothing (Hudson's, `BOUND_COST` 0) is always worth trying: its level's
    // statistics would never be read, and keeping them costs its search time.
    let adaptive = M::BOUND_COST > 0.0;
    if !adaptive || ctx.bounds[level].worth_trying(M::BOUND_COST * (tree.depth - 1 - level) as f64) {
        let cut = v + tree.rest_bound(level, node, ctx.bound() - v) > ctx.bound();
        if adaptive {
            ctx.bounds[level].record(cut);
        }
        if cut {
            return;
        }
    }
    let before = ctx.nodes;
    dfs(tree, level + 1, node, v, deeper, ctx);
    if adaptive {
        ctx.bounds[level].searched(ctx.nodes - before);
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
    if level + 1 == tree.depth && ctx.leaves_unrecorded(level) {
        leaves(tree, level, parent, acc, ctx);
        return;
    }
    let cut = Cut { acc, floor: tree.rest_floor[level], bound: ctx.bound() };
    expand_all(tree, level, parent, lv, ctx, &cut);
    let n = tree.n;
    for i in 0..lv.order.len() {
        let o = lv.order[i];
        ctx.enter(level, o);
        let v = acc + lv.cost[o];
        if v + tree.rest_floor[level] > ctx.bound() {
            break; // children are sorted: every later one is cut too
        }
        let child = NodeRef { pose: lv.pose[o], state: &lv.state[o * n..(o + 1) * n] };
        visit(tree, level, &child, v, deeper, ctx);
        if ctx.stopped() {
            return;
        }
        ctx.finished(level);
    }
}

/// The children of `parent` on the last level (leaves), in option order, each cut against the
/// best path as it stands (so one cheap leaf cuts its later siblings part-way). What it records
/// is what [`dfs`] records, node for node: the sorted visit there stops at the first leaf above
/// the bound, and a leaf above the cheapest sibling changes neither the option's minimum nor the
/// best path; here the cheapest sibling is never cut (its partial sums are at most its cost,
/// which is at most the best path whenever the sorted visit records it) and every leaf that is
/// recorded is at least it. The last level has no level below (`rest_floor` 0).
fn leaves<M: CostModel>(tree: &Tree<M>, level: usize, parent: &NodeRef<M::State>, acc: f64, ctx: &mut Ctx) {
    let floor = tree.rest_floor[level];
    let options = tree.level_options(level);
    for &o in options {
        let cut = Cut { acc, floor, bound: ctx.bound() };
        if let Some(c) = tree.leaf_within(level, parent, o, &cut) {
            let v = acc + c;
            if v + floor <= ctx.bound() {
                ctx.leaf(v);
            }
        }
    }
    ctx.nodes += options.len() as u64;
}

/// Runs the search at the tree's full depth (`search.parallel`: the parallel mode, its start on
/// this thread). `None` when the deadline stopped it.
pub(crate) fn branch_and_bound<M: CostModel>(
    tree: &Tree<M>,
    search: &SearchConfig,
    shared: &Shared,
) -> Option<SearchOutcome> {
    let mut ctx = Ctx::new(shared, tree);
    if search.parallel && tree.depth >= 2 {
        let split = split_levels(tree.depth).min(tree.depth);
        let budget = search.parallel_after_nodes;
        let floor = std::time::Duration::from_micros(search.parallel_after_us);
        let not_before = (search.parallel_after_us > 0).then(|| Instant::now() + floor);
        ctx.start = Some(Start { budget, not_before, split, path: [0; MAX_SPLIT], finished: Vec::new(), spent: false });
    }
    dfs(tree, 0, &tree.root(), 0.0, &mut levels(tree), &mut ctx);
    let out = match ctx.start.take() {
        Some(start) if start.spent && !shared.abort.load(Ordering::Relaxed) => parallel_search(tree, ctx, start),
        _ => ctx.outcome(tree.tie_tolerance),
    };
    (!shared.abort.load(Ordering::Relaxed)).then_some(out)
}

/// How many top levels the parallel search splits into tasks: 2, or 3 for trees of 5 levels or
/// more (7³ = 343 tasks for A = 7: small enough to balance two workers when one subtree holds
/// most of the work, as the best one does).
fn split_levels(depth: usize) -> usize {
    if depth >= 5 {
        3
    } else {
        2
    }
}

/// The most levels a task's path names.
const MAX_SPLIT: usize = 3;

/// One task of the parallel search: the subtree below the node that `path` (options from the
/// root, `split` of them) leads to, with that node's path cost and lower bound.
struct Task {
    path: [usize; MAX_SPLIT],
    cost: f64,
    bound: f64,
}

/// Every task of the top `split` levels, most promising (lowest bound) first; ties in option
/// order. The level-0 options are enumerated in parallel.
fn tasks<M: CostModel>(tree: &Tree<M>, split: usize) -> Vec<Task> {
    let mut all: Vec<Task> = tree
        .root_options
        .par_iter()
        .flat_map_iter(|&r| {
            let mut out = Vec::new();
            let mut buf = vec![tree.root_state[0]; tree.n * split];
            let mut path = [0; MAX_SPLIT];
            path[0] = r;
            enumerate(tree, 0, &tree.root(), 0.0, &mut path, split, &mut buf, &mut out);
            out
        })
        .collect();
    all.sort_by(|a, b| a.bound.total_cmp(&b.bound).then(a.path.cmp(&b.path)));
    all
}

/// Expands `path[level]` below `parent`, then every option of the levels down to `split`,
/// pushing one task per node at level `split − 1`; `buf` holds one node's states per level.
#[allow(clippy::too_many_arguments)]
fn enumerate<M: CostModel>(
    tree: &Tree<M>,
    level: usize,
    parent: &NodeRef<M::State>,
    acc: f64,
    path: &mut [usize; MAX_SPLIT],
    split: usize,
    buf: &mut [M::State],
    out: &mut Vec<Task>,
) {
    let (here, deeper) = buf.split_at_mut(tree.n);
    let (pose, c) = tree.expand(level, parent, path[level], here);
    let (node, cost) = (NodeRef { pose, state: &*here }, acc + c);
    if level + 1 == split {
        let below = if split < tree.depth {
            tree.rest_floor[level].max(tree.rest_bound(level, &node, f64::INFINITY))
        } else {
            0.0
        };
        out.push(Task { path: *path, cost, bound: cost + below });
        return;
    }
    for &o in tree.level_options(level + 1) {
        path[level + 1] = o;
        enumerate(tree, level + 1, &node, cost, path, split, deeper, out);
    }
}

/// Searches one task's subtree unless its bound is beaten: re-expands its path into `prefix`
/// (one node's states per level), then searches below with the buffers of the deeper levels.
fn search_task<M: CostModel>(
    tree: &Tree<M>,
    task: &Task,
    split: usize,
    prefix: &mut [M::State],
    deeper: &mut [Level<M::State>],
    ctx: &mut Ctx,
) {
    if task.bound > ctx.bound() || ctx.out_of_time() {
        return;
    }
    let n = tree.n;
    ctx.root = task.path[0];
    ctx.nodes += split as u64;
    let mut pose = tree.root_pose;
    for level in 0..split {
        let (above, here) = prefix.split_at_mut(level * n);
        let parent = if level == 0 { tree.root() } else { NodeRef { pose, state: &above[(level - 1) * n..] } };
        pose = tree.expand(level, &parent, task.path[level], &mut here[..n]).0;
    }
    let node = NodeRef { pose, state: &prefix[(split - 1) * n..split * n] };
    visit(tree, split - 1, &node, task.cost, deeper, ctx);
}

/// The rest of the tree after the one-thread start `first` (its `start` spent): the tasks of the
/// top levels ordered by bound, one worker per rayon thread pulling them in order, skipping those
/// the start finished (their minima are in `first`) and those the best path already excludes;
/// the per-option minima are merged. A subtree the start left part-way is searched again whole.
fn parallel_search<M: CostModel>(tree: &Tree<M>, mut first: Ctx, start: Start) -> SearchOutcome {
    let (shared, split) = (first.shared, start.split);
    let tasks = tasks(tree, split);
    let mut finished = start.finished;
    finished.sort_unstable();
    let worker = || (Ctx::new(shared, tree), vec![tree.root_state[0]; tree.n * split], levels(tree));
    // The enumeration expanded every node of the top `split` levels.
    first.nodes += tree.nodes_above(split);
    let next = AtomicUsize::new(0);
    let threads = rayon::current_num_threads().max(1);
    let results: Vec<Ctx> = (0..threads)
        .into_par_iter()
        .map(|_| {
            let (mut ctx, mut prefix, mut lv) = worker();
            loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= tasks.len() || shared.abort.load(Ordering::Relaxed) {
                    break;
                }
                if finished.binary_search(&tasks[i].path).is_ok() {
                    continue;
                }
                search_task(tree, &tasks[i], split, &mut prefix, &mut lv[split..], &mut ctx);
            }
            ctx
        })
        .collect();
    for r in results {
        first.merge(r);
    }
    first.outcome(tree.tie_tolerance)
}

#[cfg(test)]
mod tests {
    use super::BoundStats;

    /// Feeds `nodes` tries at a level `levels_below` above the leaves, where the bound cuts one
    /// node in `cut_every` and an uncut subtree holds `below` nodes; returns how many it computed.
    fn computed(levels_below: usize, cut_every: u64, below: u64, nodes: u64) -> u64 {
        let mut stats = BoundStats::default();
        let mut computed = 0;
        for i in 0..nodes {
            let cut = (i + 1) % cut_every == 0;
            if stats.worth_trying(levels_below as f64) {
                computed += 1;
                stats.record(cut);
                if cut {
                    continue;
                }
            }
            stats.searched(below);
        }
        computed
    }

    #[test]
    fn a_bound_is_computed_where_its_cuts_save_more_than_it_costs() {
        // Cuts every node one level above 5 leaves: always worth it.
        assert_eq!(computed(1, 1, 5, 1000), 1000);
        // Cuts one node in 10, whose subtree holds 1,000 nodes, four levels up: worth it.
        assert_eq!(computed(4, 10, 1000, 1000), 1000);
        // Never cuts: the warm-up, then one node in SAMPLE.
        let (warm, sample) = (BoundStats::WARM_UP, BoundStats::SAMPLE);
        assert_eq!(computed(3, u64::MAX, 100, 1000), warm + (1000 - warm) / sample);
        // Cuts one node in 25 above 12-node subtrees, two levels up (the sloping N = 5 tree's level
        // 3: it saves 0.5 node per try against its cost of 2): skipped after the warm-up.
        assert!(computed(2, 25, 12, 1000) < warm + 1000 / sample + 1);
        // A cost of 0 (Hudson's bound): always computed, whatever it saves.
        let mut stats = BoundStats::default();
        for _ in 0..1000 {
            assert!(stats.worth_trying(0.0));
            stats.record(false);
            stats.searched(1);
        }
    }
}

/// The state the workers share: the best path is the least value offered, and the clock check
/// raises the abort flag exactly once the deadline has passed.
#[cfg(test)]
mod shared_tests {
    use super::Shared;
    use std::sync::atomic::Ordering;
    use std::time::{Duration, Instant};

    #[test]
    fn the_shared_best_is_the_least_value_offered() {
        let s = Shared::new(None);
        assert_eq!(s.bound(), f64::INFINITY);
        s.offer(5.0);
        assert_eq!(s.bound(), 5.0);
        s.offer(7.5);
        assert_eq!(s.bound(), 5.0);
        s.offer(0.25);
        assert_eq!(s.bound(), 0.25);
    }

    #[test]
    fn the_clock_aborts_only_after_the_deadline() {
        let none = Shared::new(None);
        assert!(!none.check_clock());
        let later = Shared::new(Some(Instant::now() + Duration::from_secs(3600)));
        assert!(!later.check_clock());
        assert!(!later.abort.load(Ordering::Relaxed));
        let passed = Shared::new(Some(Instant::now()));
        assert!(passed.check_clock());
        assert!(passed.abort.load(Ordering::Relaxed));
        // An abort raised elsewhere is reported without a deadline.
        none.abort.store(true, Ordering::Relaxed);
        assert!(none.check_clock());
    }
}
