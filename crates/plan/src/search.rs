//! The production search: depth-first branch-and-bound over the look-ahead tree with
//! preallocated per-level buffers, children visited cheapest first, and rayon over the top two
//! levels. It returns exactly the brute-force decision and minimum path cost:
//! - a subtree is cut only when its lower bound (path so far + a bound on the levels below: the
//!   per-level floor, then the node's geometric bound) is strictly greater than the best complete
//!   path known, so no minimum-cost path is ever cut;
//! - ties between equal minima go to the lowest level-0 option index, and parallel tasks are
//!   merged in index order, so the result does not depend on thread timing.
//!
//! Only the node count varies with the thread count.

use crate::tree::{NodeRef, Tree};
use crate::SearchOutcome;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Preallocated buffers for the children of one level.
struct Level {
    eps2: Vec<f64>,
    los: Vec<[f64; 3]>,
    pose: Vec<crate::motion::FastPose>,
    cost: Vec<f64>,
    order: Vec<usize>,
}

fn levels(tree: &Tree) -> Vec<Level> {
    let (m, n) = (tree.n_options(), tree.n);
    (0..tree.depth)
        .map(|_| Level {
            eps2: vec![0.0; m * n],
            los: vec![[0.0; 3]; m * n],
            pose: vec![tree.root_pose; m],
            cost: vec![0.0; m],
            order: Vec::with_capacity(m),
        })
        .collect()
}

/// Shared between tasks: the best complete path value (f64 bits; non-negative floats order like
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
}

/// One task's search state.
struct Ctx<'s> {
    shared: &'s Shared,
    best: f64,
    best_root: usize,
    root: usize,
    nodes: u64,
    /// Searches entered since the clock was last read (starts at 255: each task reads it first).
    since_clock: u32,
}

impl Ctx<'_> {
    fn bound(&self) -> f64 {
        self.best.min(self.shared.bound())
    }
    fn leaf(&mut self, v: f64) {
        if v < self.best || (v == self.best && self.root < self.best_root) {
            self.best = v;
            self.best_root = self.root;
            self.shared.offer(v);
        }
    }
    /// Reads the clock every 256 subtree entries; true when the search must stop.
    fn out_of_time(&mut self) -> bool {
        self.since_clock += 1;
        if self.since_clock >= 256 {
            self.since_clock = 0;
            if let Some(d) = self.shared.deadline {
                if Instant::now() >= d {
                    self.shared.abort.store(true, Ordering::Relaxed);
                }
            }
        }
        self.shared.abort.load(Ordering::Relaxed)
    }
}

/// Expands every child of `parent` into `lv` (level `level`) and sorts them cheapest first.
fn expand_all(tree: &Tree, level: usize, parent: &NodeRef, lv: &mut Level, ctx: &mut Ctx) {
    let n = tree.n;
    lv.order.clear();
    for &o in tree.level_options(level) {
        let (p, c) = tree.expand(level, parent, o, &mut lv.eps2[o * n..(o + 1) * n], &mut lv.los[o * n..(o + 1) * n]);
        lv.pose[o] = p;
        lv.cost[o] = c;
        lv.order.push(o);
    }
    ctx.nodes += lv.order.len() as u64;
    let cost = &lv.cost;
    // Stable sort keeps index order among equal costs.
    lv.order.sort_by(|&a, &b| cost[a].total_cmp(&cost[b]));
}

/// Searches below `parent` (at level − 1) with path cost `acc` so far.
fn dfs(tree: &Tree, level: usize, parent: &NodeRef, acc: f64, levels: &mut [Level], ctx: &mut Ctx) {
    if ctx.out_of_time() {
        return;
    }
    let (lv, deeper) = levels.split_first_mut().expect("one buffer per level");
    expand_all(tree, level, parent, lv, ctx);
    let last = level + 1 == tree.depth;
    let n = tree.n;
    for i in 0..lv.order.len() {
        let o = lv.order[i];
        let v = acc + lv.cost[o];
        if v + tree.rest_floor[level] > ctx.bound() {
            break; // children are sorted: every later one is cut too
        }
        if last {
            ctx.leaf(v);
        } else {
            let child =
                NodeRef { pose: lv.pose[o], eps2: &lv.eps2[o * n..(o + 1) * n], los: &lv.los[o * n..(o + 1) * n] };
            if v + tree.rest_bound(level, &child) <= ctx.bound() {
                dfs(tree, level + 1, &child, v, deeper, ctx);
            }
        }
    }
}

/// Runs the search at the tree's full depth. `None` when the deadline stopped it.
pub(crate) fn branch_and_bound(tree: &Tree, parallel: bool, shared: &Shared) -> Option<SearchOutcome> {
    let out = if parallel && tree.depth >= 2 { parallel_search(tree, shared) } else { sequential(tree, shared) };
    (!shared.abort.load(Ordering::Relaxed)).then_some(out)
}

fn sequential(tree: &Tree, shared: &Shared) -> SearchOutcome {
    let mut lv = levels(tree);
    let mut ctx =
        Ctx { shared, best: f64::INFINITY, best_root: usize::MAX, root: usize::MAX, nodes: 0, since_clock: 255 };
    let (top, deeper) = lv.split_first_mut().expect("depth >= 1");
    expand_all(tree, 0, &tree.root(), top, &mut ctx);
    let n = tree.n;
    for i in 0..top.order.len() {
        let o = top.order[i];
        ctx.root = o;
        let v = top.cost[o];
        if v + tree.rest_floor[0] > ctx.bound() {
            break;
        }
        if tree.depth == 1 {
            ctx.leaf(v);
        } else {
            let child =
                NodeRef { pose: top.pose[o], eps2: &top.eps2[o * n..(o + 1) * n], los: &top.los[o * n..(o + 1) * n] };
            if v + tree.rest_bound(0, &child) <= ctx.bound() {
                dfs(tree, 1, &child, v, deeper, &mut ctx);
            }
        }
    }
    SearchOutcome { root_option: ctx.best_root, value: ctx.best, nodes: ctx.nodes }
}

/// Rayon over (level-0, level-1) pairs; each task owns its buffers; results merged in index order.
fn parallel_search(tree: &Tree, shared: &Shared) -> SearchOutcome {
    let n = tree.n;
    let mut root_eps2 = vec![0.0; tree.n_options() * n];
    let mut root_los = vec![[0.0; 3]; tree.n_options() * n];
    let mut roots = Vec::new();
    for &o in &tree.root_options {
        let (p, c) =
            tree.expand(0, &tree.root(), o, &mut root_eps2[o * n..(o + 1) * n], &mut root_los[o * n..(o + 1) * n]);
        roots.push((o, p, c));
    }
    let tasks: Vec<(usize, usize)> =
        (0..roots.len()).flat_map(|r| tree.all_options.iter().map(move |&c| (r, c))).collect();
    let results: Vec<(f64, usize, u64)> = tasks
        .par_iter()
        .map_init(
            || (levels(tree), vec![0.0; n], vec![[0.0; 3]; n]),
            |(lv, e2, los), &(r, c)| {
                let (o, pose, c0) = roots[r];
                let mut ctx =
                    Ctx { shared, best: f64::INFINITY, best_root: usize::MAX, root: o, nodes: 1, since_clock: 255 };
                let parent = NodeRef { pose, eps2: &root_eps2[o * n..(o + 1) * n], los: &root_los[o * n..(o + 1) * n] };
                let (p1, c1) = tree.expand(1, &parent, c, e2, los);
                let v = c0 + c1;
                if tree.depth == 2 {
                    ctx.leaf(v);
                } else {
                    let child = NodeRef { pose: p1, eps2: e2, los };
                    if v + tree.rest_bound(1, &child) <= ctx.bound() {
                        dfs(tree, 2, &child, v, &mut lv[2..], &mut ctx);
                    }
                }
                (ctx.best, ctx.best_root, ctx.nodes)
            },
        )
        .collect();
    let mut out = SearchOutcome { root_option: usize::MAX, value: f64::INFINITY, nodes: roots.len() as u64 };
    for (v, root, nodes) in results {
        out.nodes += nodes;
        if v < out.value || (v == out.value && root < out.root_option) {
            out.value = v;
            out.root_option = root;
        }
    }
    out
}
