//! Headroom of the CNA's path (for the evaluation's tied cells): a clairvoyant rollout policy, a measuring
//! tool, not a planner. At every CNA decision it forks the TRUE mission once per motion option of
//! the planner's level 0 (headings, and pitch for an AUV CNA, those within the pitch and depth
//! limits), commits that option for one period, then lets the base policy steer for HORIZON_S
//! seconds, and takes the option whose fork has the lowest mean true error of all survey AUVs over
//! [t, t + HORIZON_S] (every AUV's once-a-second sample; ties by option order). That is one step
//! of policy improvement over the base with the truth known.
//! - REDRAWS = 0: the forks use the run's own future random draws (clairvoyant: an upper bound on
//!   what any causal policy could gain over the base this way);
//! - REDRAWS = K > 0: each option is scored over K forks with fresh future draws (a perfect model
//!   and the true state, the future noise unknown).
//!
//! The rollout and POLICIES run on the same TUNING-seed runs (base seed 1000, paired by run); the
//! rollout is the reference of the printed comparison. Then, per policy: where its CNA sat (mean
//! CNA–AUV distance, time inside / beyond the distance limits, distance from the AUVs' centroid,
//! depth); for the rollout its time per run and how often it took the base's own first move.
//!
//! `cargo run --release -p coopnav-sim --example closed_loop_headroom -- RUNS SCENARIO N POLICIES
//! [DURATION_S|-] [HORIZON_S] [REDRAWS] [BASE]`
//! - SCENARIO: `current`, `sloping-auv-cna` (the evaluation's settings for N AUVs), or a scenario
//!   file (N `-`: its own fleet);
//! - HORIZON_S default 300, REDRAWS default 0, BASE default `planner-estimator` (or `planner`,
//!   `centroid`, `centroid-standoff`: a baseline base must be stateless, it is rebuilt per fork).
//!
//! e.g. `... -- 20 sloping-auv-cna 2 planner-estimator,centroid-standoff,trail,zigzag,racetrack,centroid - 300`.

use coopnav_core::{run_seed, Vec3};
use coopnav_plan::{MotionConfig, MotionOption};
use coopnav_sim::batch::mc::{compare, comparison_table};
use coopnav_sim::engine::{Faults, Observer, TraceRow};
use coopnav_sim::experiments::closed_loop::{setup, TUNING_SEED};
use coopnav_sim::experiments::{ReproOptions, Size};
use coopnav_sim::observe::metrics::{run, RunResult, ScoredMission as Mission};
use coopnav_sim::policy::{CnaCommand, CnaPolicy, PolicyContext};
use coopnav_sim::policy::{Policy, PolicySpec};
use coopnav_sim::scenario::Scenario;
use rayon::prelude::*;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Instant;

type Error = Box<dyn std::error::Error + Send + Sync>;

/// Stateless baselines a fork may rebuild instead of copying.
const STATELESS: [&str; 2] = ["centroid", "centroid-standoff"];

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [runs, scenario, n, policies, rest @ ..] = args.as_slice() else {
        return Err(
            "usage: closed_loop_headroom RUNS SCENARIO N POLICIES [DURATION_S|-] [HORIZON_S] [REDRAWS] [BASE]".into()
        );
    };
    let runs: usize = runs.parse()?;
    let arg = |i: usize| rest.get(i).map(String::as_str).filter(|a| *a != "-");
    let duration = arg(0).map(str::parse::<f64>).transpose()?;
    let horizon: f64 = arg(1).map_or(Ok(300.0), str::parse)?;
    let redraws: usize = arg(2).map_or(Ok(0), str::parse)?;
    let base_name = arg(3).unwrap_or("planner-estimator");
    let sc = scenario_for(scenario, n, duration)?;
    let base = PolicySpec::new(base_name, &sc)?;
    if !matches!(base.build(&sc)?, Policy::Planner(_)) && !STATELESS.contains(&base_name) {
        return Err(format!("base {base_name}: a fork cannot copy its state").into());
    }
    let policies: Vec<String> = policies.split(',').map(str::to_string).collect();
    let specs = policies.iter().map(|p| PolicySpec::new(p, &sc)).collect::<Result<Vec<_>, _>>()?;
    let rollout = Rollout { sc: &sc, base: &base, horizon, redraws };
    let start = Instant::now();
    // One job per (policy, run), the rollout's first; each run on its own, results in job order.
    let jobs: Vec<(Option<&PolicySpec>, usize)> =
        [None].into_iter().chain(specs.iter().map(Some)).flat_map(|p| (0..runs).map(move |r| (p, r))).collect();
    let done: Vec<(RunResult, Geometry, Option<RolloutStats>)> = jobs
        .par_iter()
        .map(|&(spec, r)| {
            let seed = run_seed(sc.seed, r as u64);
            match spec {
                None => rollout.run(seed),
                Some(spec) => {
                    let mut geometry = Geometry::new(&sc);
                    let r = run(&sc, &mut spec.build(&sc)?, seed, &Faults::default(), &mut geometry);
                    Ok((r, geometry, None))
                }
            }
        })
        .collect::<Result<_, Error>>()?;
    let names: Vec<String> = [format!("rollout({base_name})")].into_iter().chain(policies).collect();
    let results: Vec<RunResult> = done.iter().map(|(r, _, _)| r.clone()).collect();
    let c = compare(&sc, &names, runs, &results);
    println!(
        "{} N = {}, tau = {} s, {} s missions; rollout horizon {horizon} s, {}",
        scenario,
        sc.fleet.n_auvs,
        sc.comms.tau,
        sc.duration_s,
        if redraws == 0 {
            "clairvoyant (the run's own future draws)".to_string()
        } else {
            format!("{redraws} fresh draws per option")
        }
    );
    print!("{}", comparison_table(&c));
    println!(
        "policy: CNA-AUV distance mean (m), time closer than {} m / farther than {} m (%), CNA to the AUVs' centroid (m), \
         CNA depth (m)",
        sc.policy.planner.limits.min, sc.policy.planner.limits.max
    );
    for (name, runs_of) in names.iter().zip(done.chunks(runs)) {
        let g = runs_of.iter().fold(Geometry::new(&sc), |acc, (_, g, _)| acc.merged(g));
        let n = g.samples.max(1) as f64;
        let pct = |c: usize| 100.0 * c as f64 / n;
        println!(
            "  {name:<28} {:7.0} {:6.1} {:6.1} {:7.0} {:6.1}",
            g.distance / n,
            pct(g.closer),
            pct(g.farther),
            g.to_centroid / g.instants.max(1) as f64,
            g.depth / g.instants.max(1) as f64
        );
    }
    let stats: Vec<&RolloutStats> = done.iter().filter_map(|(_, _, s)| s.as_ref()).collect();
    let decisions: usize = stats.iter().map(|s| s.decisions).sum();
    let same: usize = stats.iter().map(|s| s.base_move_taken).sum();
    let known: usize = stats.iter().map(|s| s.base_move_known).sum();
    let cpu: f64 = stats.iter().map(|s| s.cpu_s).sum();
    println!(
        "rollout: {decisions} decisions, {:.1} options per decision, the base's own first move taken at {same} of the \
         {known} where the base moved by an option ({:.0} %); {:.1} s per run (in-thread wall time)",
        stats.iter().map(|s| s.options).sum::<usize>() as f64 / decisions.max(1) as f64,
        100.0 * same as f64 / known.max(1) as f64,
        cpu / runs.max(1) as f64
    );
    let per_known = |f: fn(&RolloutStats) -> f64| stats.iter().map(|s| f(s)).sum::<f64>() / known.max(1) as f64;
    println!(
        "rollout scores (mean error over the horizon, per decision): worst option minus best {:.3} m, the base's move \
         minus best {:.3} m",
        per_known(|s| s.spread),
        per_known(|s| s.base_regret)
    );
    println!("wall time {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// The tuning-seed mission `name` (a setting of `closed-loop-vs-baselines`, or a scenario file).
fn scenario_for(name: &str, n: &str, duration: Option<f64>) -> Result<Scenario, Error> {
    let mut sc = if name.ends_with(".toml") {
        let sc = Scenario::load(Path::new(name))?;
        if n == "-" {
            sc
        } else {
            sc.with_auvs(n.parse()?)
        }
    } else {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, TUNING_SEED + 1))?;
        let setting = settings.iter().find(|s| s.name == name).ok_or_else(|| format!("no scenario {name}"))?;
        setting.scenario(n.parse()?, TUNING_SEED, None)?
    };
    sc.seed = TUNING_SEED;
    if let Some(d) = duration {
        sc.duration_s = d;
    }
    Ok(sc)
}

/// The rollout's settings for one cell.
struct Rollout<'a> {
    sc: &'a Scenario,
    base: &'a PolicySpec,
    horizon: f64,
    redraws: usize,
}

/// What the rollout did in one run.
struct RolloutStats {
    decisions: usize,
    /// Options scored per decision, summed.
    options: usize,
    /// Decisions where the base's own command was one of the options, and where the rollout took it.
    base_move_known: usize,
    base_move_taken: usize,
    /// Over those decisions, summed: the worst option's score minus the best's, and the base's
    /// move's score minus the best's, m.
    spread: f64,
    base_regret: f64,
    cpu_s: f64,
}

impl Rollout<'_> {
    fn run(&self, seed: u64) -> Result<(RunResult, Geometry, Option<RolloutStats>), Error> {
        let start = Instant::now();
        let sc = self.sc;
        let motion = sc.planner_config().motion;
        let options = motion.options();
        let faults = Faults::default();
        let steered = Arc::new(Mutex::new(Steered::new(self.base.build(sc)?, motion)));
        let mut policy = Policy::Baseline(Box::new(Handle(Arc::clone(&steered))));
        let mut geometry = Geometry::new(sc);
        let mut mission = Mission::new(sc, &mut policy, seed, &faults, &mut geometry);
        let horizon_steps = (self.horizon / sc.dt).round() as u64;
        let mut stats = RolloutStats {
            decisions: 0,
            options: 0,
            base_move_known: 0,
            base_move_taken: 0,
            spread: 0.0,
            base_regret: 0.0,
            cpu_s: 0.0,
        };
        while !mission.done() {
            if mission.decides_next() {
                let before = steered.lock().expect("one thread per run").copy(self)?;
                let draws: Vec<Option<u64>> = match self.redraws {
                    0 => vec![None],
                    k => (0..k).map(|j| Some(run_seed(seed, (stats.decisions * k + j + 1) as u64))).collect(),
                };
                // Each option's score (None: off limits), in option order.
                let mut scores: Vec<Option<f64>> = Vec::with_capacity(options.len());
                for i in 0..options.len() {
                    let mut total = Some(0.0);
                    for &draw in &draws {
                        total = match (total, self.score(&mission, &before, i, draw, horizon_steps)?) {
                            (Some(t), Some(s)) => Some(t + s),
                            _ => None,
                        };
                    }
                    scores.push(total.map(|t| t / draws.len() as f64));
                }
                let valid = || scores.iter().enumerate().filter_map(|(i, s)| s.map(|s| (s, i)));
                // The first lowest score: ties by option order.
                let best = valid().fold(None, |b: Option<(f64, usize)>, (s, i)| match b {
                    Some((bs, _)) if bs <= s => b,
                    _ => Some((s, i)),
                });
                stats.options += valid().count();
                let chosen = best.map(|(_, i)| i);
                steered.lock().expect("one thread per run").option = chosen;
                stats.decisions += 1;
                mission.step(&mut geometry);
                let s = steered.lock().expect("one thread per run");
                if let (Some(base_move), Some((low, i))) = (s.base_move, best) {
                    stats.base_move_known += 1;
                    stats.base_move_taken += usize::from(base_move == i);
                    let high = valid().map(|(s, _)| s).fold(low, f64::max);
                    stats.spread += high - low;
                    stats.base_regret += scores[base_move].map_or(0.0, |s| s - low);
                }
            } else {
                mission.step(&mut geometry);
            }
        }
        let mut result = mission.finish();
        result.policy = "rollout".into();
        stats.cpu_s = start.elapsed().as_secs_f64();
        Ok((result, geometry, Some(stats)))
    }

    /// Mean true error over the horizon of `mission` forked with option `i` first, then the base
    /// (`before`: the base as it stood before this decision); None when the option breaks the
    /// CNA's pitch or depth limits.
    fn score(
        &self,
        mission: &Mission,
        before: &Steered,
        i: usize,
        draw: Option<u64>,
        steps: u64,
    ) -> Result<Option<f64>, Error> {
        let mut forced = before.copy(self)?;
        forced.option = Some(i);
        let steered = Arc::new(Mutex::new(forced));
        let mut policy = Policy::Baseline(Box::new(Handle(Arc::clone(&steered))));
        let mut fork = mission.fork(&mut policy, draw);
        let mut score = MeanError::default();
        for step in 0..steps {
            if fork.done() {
                break;
            }
            fork.step(&mut score);
            if step == 0 && steered.lock().expect("one thread per run").off_limits {
                return Ok(None);
            }
        }
        Ok(Some(score.sum / score.n.max(1) as f64))
    }
}

/// The base policy, with one decision's option forced on it.
struct Steered {
    base: Policy,
    motion: MotionConfig,
    options: Vec<MotionOption>,
    /// The option the next decision takes instead of the base's command (taken once).
    option: Option<usize>,
    /// The option the base itself chose at the last forced decision (None: a hold, or no option's).
    base_move: Option<usize>,
    /// The forced option broke the pitch or depth limits.
    off_limits: bool,
}

impl Steered {
    fn new(base: Policy, motion: MotionConfig) -> Self {
        Steered { base, motion, options: motion.options(), option: None, base_move: None, off_limits: false }
    }

    /// A copy with the base's state (a planner's trackers), for a fork.
    fn copy(&self, r: &Rollout) -> Result<Self, Error> {
        let base = match &self.base {
            Policy::Planner(p) => Policy::Planner(p.clone()),
            Policy::Baseline(_) => r.base.build(r.sc)?,
        };
        Ok(Steered::new(base, self.motion))
    }
}

impl CnaPolicy for Steered {
    fn name(&self) -> &'static str {
        "rollout"
    }

    /// The base always decides (its models step with every broadcast); a forced option overrides
    /// its command.
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let next = |o: &MotionOption| self.motion.next(&ctx.cna, o);
        let forced = self.option.take().map(|i| next(&self.options[i]));
        if let Some((_, false)) = forced {
            // The fork ends here: the base's search would be wasted.
            self.off_limits = true;
            return CnaCommand::Hold;
        }
        let command = self.base.as_policy().decide(ctx);
        let Some((pose, _)) = forced else { return command };
        self.base_move = match command {
            CnaCommand::GoTo(p) => self.options.iter().position(|o| same(next(o).0.pos, p)),
            CnaCommand::Hold => None,
        };
        CnaCommand::GoTo(pose.pos)
    }
}

fn same(a: Vec3, b: Vec3) -> bool {
    (a - b).norm() < 1e-6
}

/// A [`Steered`] the caller keeps a hand on while the mission holds it.
struct Handle(Arc<Mutex<Steered>>);

impl CnaPolicy for Handle {
    fn name(&self) -> &'static str {
        "rollout"
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        self.0.lock().expect("one thread per run").decide(ctx)
    }
}

/// The mean of every survey AUV's true error sample.
#[derive(Default)]
struct MeanError {
    sum: f64,
    n: usize,
}

impl Observer for MeanError {
    fn on_sample(&mut self, _t: f64, _cna: Vec3, rows: &[TraceRow]) {
        self.sum += rows.iter().map(|r| r.error).sum::<f64>();
        self.n += rows.len();
    }
}

/// Where the CNA sat relative to the survey AUVs, summed over a run's once-a-second samples.
#[derive(Clone, Copy)]
struct Geometry {
    min: f64,
    max: f64,
    /// Per AUV sample: the sum of distances, and the samples closer than `min` and farther than `max`.
    samples: usize,
    distance: f64,
    closer: usize,
    farther: usize,
    /// Per instant: the CNA's horizontal distance from the AUVs' true centroid, and its depth.
    instants: usize,
    to_centroid: f64,
    depth: f64,
}

impl Geometry {
    fn new(sc: &Scenario) -> Self {
        let (min, max) = (sc.policy.planner.limits.min, sc.policy.planner.limits.max);
        Geometry {
            min,
            max,
            samples: 0,
            distance: 0.0,
            closer: 0,
            farther: 0,
            instants: 0,
            to_centroid: 0.0,
            depth: 0.0,
        }
    }

    fn merged(self, o: &Geometry) -> Self {
        Geometry {
            samples: self.samples + o.samples,
            distance: self.distance + o.distance,
            closer: self.closer + o.closer,
            farther: self.farther + o.farther,
            instants: self.instants + o.instants,
            to_centroid: self.to_centroid + o.to_centroid,
            depth: self.depth + o.depth,
            ..self
        }
    }
}

impl Observer for Geometry {
    fn on_sample(&mut self, _t: f64, cna: Vec3, rows: &[TraceRow]) {
        for r in rows {
            self.samples += 1;
            self.distance += r.distance;
            self.closer += usize::from(r.distance < self.min);
            self.farther += usize::from(r.distance > self.max);
        }
        let n = rows.len().max(1) as f64;
        let (cx, cy) = (rows.iter().map(|r| r.true_x).sum::<f64>() / n, rows.iter().map(|r| r.true_y).sum::<f64>() / n);
        self.instants += 1;
        self.to_centroid += (cna.x - cx).hypot(cna.y - cy);
        self.depth += cna.z;
    }
}
