//! Work estimates of every runnable set-up (pre-deployment plan, closed loop, HBL simulate, Monte
//! Carlo, grid, tuning and post-processing), computed from the validated input alone, before any track, tree or
//! table is built, and checked with [`coopnav_core::limits`]. Kept apart from validation: a value
//! can be valid and still too large to run without `--allow-large`.
//!
//! The byte figures are rough upper bounds of what each command holds at once (per-row sizes
//! below), enough to tell a mission from a typo that asks for gigabytes.

use crate::batch::grid::GridSpec;
use crate::batch::tune::TuneSpec;
use crate::scenario;
use crate::scenario::plan;
use coopnav_core::limits::{
    Estimate, MAX_BYTES, MAX_PLANNER_LEAVES, MAX_PLANNER_UPDATES, MAX_POINTS, MAX_VEHICLE_STEPS,
};
use coopnav_nav::fieldlog::LogRow;
use coopnav_nav::post::{AuvModel, CompactHistory, PostConfig};
use coopnav_plan::CnaKind;

/// Bytes of one stored track sample (t, x, y, z).
const TRACK_SAMPLE_BYTES: f64 = 32.0;
/// Bytes of one recorded per-AUV row (planner step record, closed-loop time-series row).
const RECORD_ROW_BYTES: f64 = 200.0;

/// A lawnmower's duration (s) from its description: lanes plus the turns between them.
fn lawnmower_duration(lanes: usize, lane_length: f64, spacing: f64, speed: f64) -> f64 {
    lanes as f64 * (lane_length.abs() + spacing.abs()) / speed
}

/// The planner's tree per decision and its work over `decisions` with `n_auvs` survey AUVs.
/// One planner's tree: its field prefix, A heading options, B pitch options, L and the levels
/// that offer the pitch options (None: every level; deeper ones hold the pitch, A options).
struct TreeSize<'a> {
    prefix: &'a str,
    headings: usize,
    pitches: usize,
    look_ahead: usize,
    pitch_levels: Option<usize>,
}

impl TreeSize<'_> {
    fn leaves(&self) -> f64 {
        let pitched = self.pitch_levels.map_or(self.look_ahead, |p| p.min(self.look_ahead));
        let (a, b) = (self.headings as f64, self.pitches as f64);
        (a * b).powf(pitched as f64) * a.powf((self.look_ahead - pitched) as f64)
    }

    fn estimates(&self, decisions: f64, n_auvs: usize) -> [Estimate; 2] {
        let (prefix, leaves) = (self.prefix, self.leaves());
        let pitch = match self.pitch_levels {
            Some(_) => format!(" (x pitch_options for {prefix}pitch_levels levels)"),
            None => " (x pitch_options)".to_string(),
        };
        [
            Estimate::new(
                "planner leaves per decision",
                format!("{prefix}heading_options{pitch} ^ {prefix}look_ahead"),
                leaves,
                MAX_PLANNER_LEAVES,
            ),
            Estimate::new(
                "planner AUV-node updates",
                format!("decisions x leaves x survey AUVs ({prefix}look_ahead, tau, mission length, AUVs)"),
                decisions * leaves * n_auvs as f64,
                MAX_PLANNER_UPDATES,
            ),
        ]
    }
}

fn pitch_options(cna: &CnaKind) -> usize {
    match cna {
        CnaKind::Auv { pitch_options, .. } => *pitch_options,
        CnaKind::Asc {} => 1,
    }
}

/// A pre-deployment plan: track samples per lawnmower, decisions, tree size, memory.
pub fn predeploy(sc: &plan::Scenario) -> Vec<Estimate> {
    let mut out = Vec::new();
    let mut shortest = f64::INFINITY;
    let mut samples = 0.0;
    for (i, a) in sc.auv.iter().enumerate() {
        if let Some(m) = &a.lawnmower {
            let duration = lawnmower_duration(m.lanes, m.lane_length, m.spacing, m.speed);
            let n = duration / plan::LAWNMOWER_DT;
            out.push(Estimate::new(
                "track samples",
                format!("auv[{i}].lawnmower lanes, lane_length, spacing, speed"),
                n,
                MAX_POINTS,
            ));
            shortest = shortest.min(duration);
            samples += n;
        }
    }
    let start = sc.mission.start_time.unwrap_or(0.0);
    let span = sc.mission.end_time.map_or(shortest, |end| end - start);
    let cfg = sc.policy.planner.config(&sc.platform, &facts_for_size(sc), 0.0);
    let tree = TreeSize {
        prefix: "policy.planner.tree.",
        headings: cfg.motion.heading_options,
        pitches: pitch_options(&cfg.motion.cna),
        look_ahead: cfg.look_ahead,
        pitch_levels: None,
    };
    if span.is_infinite() && sc.mission.end_time.is_none() {
        // Only track files: the mission's length is known once they are read
        // ([`predeploy_mission`]); the tree's size is not.
        out.push(tree.estimates(0.0, sc.auv.len())[0].clone());
        return out;
    }
    out.extend(decision_estimates(span, &cfg.motion, &tree, sc.auv.len(), samples));
    out
}

/// The mission facts a pre-deployment planner's size is read with (Hudson's cost reads none).
fn facts_for_size(sc: &plan::Scenario) -> coopnav_plan::auto::MissionFacts {
    coopnav_plan::auto::MissionFacts {
        n_auvs: sc.auv.len(),
        cna: coopnav_plan::auto::CnaFact::Asc,
        adcp_current: [0.0, 0.0],
        filters_estimate_current: false,
    }
}

/// The decisions over a mission of `span` seconds, the tree's work over them and the memory.
fn decision_estimates(
    span: f64,
    motion: &coopnav_plan::MotionConfig,
    tree: &TreeSize,
    n_auvs: usize,
    samples: f64,
) -> Vec<Estimate> {
    let decisions = span / motion.tau;
    let mut out = vec![Estimate::new("planner decisions", "mission length / platform.tau", decisions, MAX_POINTS)];
    out.extend(tree.estimates(decisions, n_auvs));
    let bytes = samples * TRACK_SAMPLE_BYTES + decisions * n_auvs as f64 * RECORD_ROW_BYTES;
    out.push(Estimate::new("memory (bytes)", "number of [[auv]], track lengths, platform.tau", bytes, MAX_BYTES));
    out
}

/// A pre-deployment mission once its tracks are read: the decisions over the span they cover.
pub fn predeploy_mission(mission: &coopnav_plan::predeploy::Mission) -> Vec<Estimate> {
    let motion = &mission.planner.motion;
    let tree = TreeSize {
        prefix: "policy.planner.tree.",
        headings: motion.heading_options,
        pitches: pitch_options(&motion.cna),
        look_ahead: mission.planner.look_ahead,
        pitch_levels: None,
    };
    let samples: f64 = mission.tracks.iter().map(|t| t.samples().len() as f64).sum();
    decision_estimates(mission.end_time - mission.start_time, motion, &tree, mission.tracks.len(), samples)
}

/// What a recorded closed-loop run holds at its peak, while its run directory is written: per
/// second and survey AUV the trace row, its CSV and alog lines and its share of the plots and the
/// replay page; per second the CNA's track; and the program itself. Sized from measured peaks
/// (docs/evaluation.md), checked within 2x by `crates/cli/tests/bounded_work.rs`.
pub fn recorded_run_bytes(duration_s: f64, n_auvs: usize) -> f64 {
    const PER_AUV_SECOND: f64 = 1600.0;
    const PER_SECOND: f64 = 600.0;
    const PROGRAM: f64 = 16e6;
    PROGRAM + duration_s * (n_auvs as f64 * PER_AUV_SECOND + PER_SECOND)
}

/// A closed-loop set-up run `runs` times for each of `policies` policies (1 and 1: one run).
pub fn closed_loop(sc: &scenario::Scenario, runs: usize, policies: usize) -> Vec<Estimate> {
    let f = &sc.fleet;
    let vehicles = (f.n_auvs + 1) as f64;
    let runs_total = runs as f64 * policies as f64;
    let pitches = sc.cna.auv.as_ref().map_or(1, |a| a.pitch_options);
    // The largest of the planners' trees: each instance's own A, L and pitch levels.
    let tree = sc
        .planner_specs()
        .into_iter()
        .map(|(name, spec)| {
            // The survey's extent only chooses penalties, not the tree; left out, so that no
            // survey waypoint is computed before its size is checked.
            let cfg = spec.config(&sc.platform(), &sc.mission_facts(), 0.0);
            let pitch_levels = match cfg.motion.cna {
                coopnav_plan::CnaKind::Auv { pitch_levels, .. } => pitch_levels,
                coopnav_plan::CnaKind::Asc {} => None,
            };
            TreeSize {
                prefix: tree_prefix(name),
                headings: cfg.motion.heading_options,
                pitches,
                look_ahead: cfg.look_ahead,
                pitch_levels,
            }
        })
        .reduce(|best, t| if t.leaves() > best.leaves() { t } else { best })
        .expect("three planner instances");
    let decisions = sc.duration_s / sc.comms.tau;
    let mut out = vec![
        Estimate::new(
            "simulated vehicle-steps",
            "duration_s / dt x (fleet.n_auvs + 1) x --runs x policies",
            sc.duration_s / sc.dt * vehicles * runs_total,
            MAX_VEHICLE_STEPS,
        ),
        Estimate::new(
            "lawnmower waypoints",
            "fleet.lanes x fleet.n_auvs",
            2.0 * f.lanes as f64 * f.n_auvs as f64,
            MAX_POINTS,
        ),
        Estimate::new(
            "memory of one recorded run (bytes)",
            "duration_s x (fleet.n_auvs + 1) (the time series, its CSV, plots, alog and replay)",
            recorded_run_bytes(sc.duration_s, f.n_auvs),
            MAX_BYTES,
        ),
    ];
    out.extend(tree.estimates(decisions * runs_total, f.n_auvs));
    out.extend(shelf(f.shelf.as_ref(), "fleet.shelf"));
    out
}

/// Where a planner instance's tree keys sit in a scenario file.
fn tree_prefix(name: &str) -> &'static str {
    match name {
        "planner-estimator" => "policy.planner-estimator.tree.",
        "open-loop" => "policy.open-loop.tree.",
        _ => "policy.planner.tree.",
    }
}

/// A sloping shelf's grid: its nodes, from its extent and spacing (`field` names the table).
pub fn shelf(shelf: Option<&coopnav_core::Shelf>, field: &str) -> Option<Estimate> {
    let s = shelf?;
    let fields = format!("{field} x_min, x_max, y_min, y_max / spacing");
    Some(Estimate::new("bathymetry grid nodes", fields, s.nodes(), MAX_POINTS))
}

/// A Nams rate-selection experiment: every scenario × behaviour × run flies both
/// vehicles over the square's lawnmower at the vehicle's step (at most `max_time`), and the
/// shelf's grid is built once.
pub fn nams(cfg: &crate::scenario::nams::ExperimentConfig) -> Vec<Estimate> {
    let per_set = (cfg.behaviours.len() * cfg.runs) as f64;
    let steps: f64 = cfg
        .scenarios
        .iter()
        .map(|s| {
            let lanes = (s.square / s.lane_spacing).round() + 1.0;
            let flown = lawnmower_duration(lanes as usize, s.square, s.lane_spacing, s.speed);
            let duration = cfg.max_time.map_or(flown, |m| m.min(flown));
            // Two survey AUVs and the CNA's slot owner: three vehicles a step.
            duration / cfg.vehicle.timestep * 3.0
        })
        .sum();
    let mut out = vec![Estimate::new(
        "simulated vehicle-steps",
        "experiment.scenarios (square, lane_spacing, speed) / vehicle.timestep x behaviours x experiment.runs",
        steps * per_set,
        MAX_VEHICLE_STEPS,
    )];
    out.extend(shelf(Some(&cfg.shelf), "experiment.shelf"));
    out
}

/// `runs` runs of a Gill pass in engine scenario `sc` (`runs_fields` says where the count comes
/// from); `recorded`: one run keeps its post-processing log (a few rows per truth step).
pub fn hbl_runs(sc: &scenario::Scenario, runs: f64, runs_fields: &str, recorded: bool) -> Vec<Estimate> {
    let steps = sc.duration_s / sc.dt;
    let vehicles = (sc.fleet.n_auvs + 1 + sc.ships.len() + sc.buoys.len()) as f64;
    let mut out = vec![Estimate::new(
        "simulated vehicle-steps",
        format!("duration_s / dt x (fleet.n_auvs + 1 + ships + buoys) x {runs_fields}"),
        steps * vehicles * runs,
        MAX_VEHICLE_STEPS,
    )];
    out.extend(shelf(sc.fleet.shelf.as_ref(), "fleet.shelf"));
    if recorded {
        out.push(Estimate::new("memory of the log (bytes)", "duration_s / dt", steps * RECORD_ROW_BYTES, MAX_BYTES));
    }
    out
}

/// The buoy-location grid: its cells, and every cell's Monte Carlo.
pub fn hbl_grid(sc: &scenario::Scenario, spec: &GridSpec) -> Vec<Estimate> {
    let cells = spec.cell_count();
    let mut out = vec![Estimate::new("grid cells", "grid x, y, spacing", cells, MAX_POINTS)];
    out.extend(hbl_runs(sc, cells * spec.runs_per_cell as f64, "grid cells x runs_per_cell", false));
    out
}

/// Nelder–Mead tuning: at most `max_iters` iterations of up to n + 1 evaluations (a shrink), each a
/// Monte Carlo of `runs` runs.
pub fn hbl_tune(sc: &scenario::Scenario, spec: &TuneSpec) -> Vec<Estimate> {
    let evaluations = (spec.max_iters as f64 + 1.0) * (spec.coefficients.len() as f64 + 1.0);
    hbl_runs(sc, evaluations * spec.runs as f64, "tune runs x (max_iters + 1) x (coefficients + 1)", false)
}

/// Shortest row of a post-processing log, bytes (`0,speed,,1,,,` and its newline; an `.alog`
/// line is longer): bounds the rows a log file of a given size can hold.
const MIN_LOG_ROW_BYTES: f64 = 12.0;

/// The largest post-processing log file whose parsed rows fit the memory limit, bytes: what the
/// bounded reader reads of a log before refusing it.
pub fn max_postprocess_log_bytes() -> f64 {
    MAX_BYTES * MIN_LOG_ROW_BYTES / std::mem::size_of::<LogRow>() as f64
}

/// A post-processing log file of `bytes` bytes, before it is read: the memory its rows take once
/// parsed.
pub fn postprocess_log(path: &str, bytes: u64) -> Estimate {
    Estimate::new(
        "memory of the parsed log rows (bytes)",
        format!("the size of {path}"),
        bytes as f64 / MIN_LOG_ROW_BYTES * std::mem::size_of::<LogRow>() as f64,
        MAX_BYTES,
    )
}

/// Post-processing the parsed log `rows`: the filter steps they ask for (a silence up to
/// `max_gap_s` is predicted in `auv.step_s` pieces, a longer one in a single step) and the memory
/// of the history, smoothed states and samples kept for every step.
pub fn postprocess(rows: &[LogRow], cfg: &PostConfig) -> Vec<Estimate> {
    let mut times: Vec<f64> = rows.iter().map(|r| r.t).collect();
    times.sort_by(f64::total_cmp);
    // As the filter runs: rows at one time share a step, and a gap within 1 ns of a whole number
    // of steps takes that many (10 Hz times such as 0.3 − 0.2 are not exact multiples of 0.1 s).
    let predictions: f64 = times
        .windows(2)
        .map(|w| match w[1] - w[0] {
            gap if gap > cfg.max_gap_s => 1.0,
            gap => ((gap - 1e-9) / cfg.auv.step_s).ceil().max(0.0),
        })
        .sum();
    let steps = predictions + 1.0;
    let per_step = match cfg.model {
        AuvModel::Thesis => CompactHistory::<5>::STEP_BYTES,
        AuvModel::Current(_) => CompactHistory::<7>::STEP_BYTES,
    } as f64;
    let fields = "the log's time span (silences up to max_gap_s) / auv.step_s";
    vec![
        Estimate::new("post-processing filter steps", fields, steps, MAX_VEHICLE_STEPS),
        Estimate::new("memory of the filter history and smoothed track (bytes)", fields, steps * per_step, MAX_BYTES),
    ]
}

/// The filter steps of a `folds`-fold cross-validation of the log (one run per fold, each with
/// the history of one run: the memory is [`postprocess`]'s).
pub fn postprocess_folds(rows: &[LogRow], cfg: &PostConfig, folds: usize) -> Vec<Estimate> {
    let steps = postprocess(rows, cfg)[0].value * folds as f64;
    let fields = "--hold-out-every × the log's time span (silences up to max_gap_s) / auv.step_s";
    vec![Estimate::new("cross-validation filter steps", fields, steps, MAX_VEHICLE_STEPS)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::limits::check;
    use std::path::Path;

    #[test]
    fn postprocessing_is_bounded_by_the_logs_time_span_and_size() {
        use coopnav_nav::fieldlog::Observation;
        let cfg = PostConfig::default();
        let rows = |spacing: f64| -> Vec<LogRow> {
            (0..2000).map(|i| LogRow { t: i as f64 * spacing, obs: Observation::Speed(1.0), sigma: None }).collect()
        };
        // 2000 rows 1 s apart: 2·10⁴ steps of 0.1 s, far below the limits.
        assert!(check(postprocess(&rows(1.0), &cfg), false).is_ok());
        // 500 s apart (under max_gap_s): 10⁷ steps, gigabytes of history.
        let e = check(postprocess(&rows(500.0), &cfg), false).unwrap_err().to_string();
        assert!(e.contains("memory of the filter history") && e.contains("auv.step_s"), "{e}");
        // 1000 s apart (over max_gap_s): one step per silence, as the filter runs it.
        assert!(check(postprocess(&rows(1000.0), &cfg), false).is_ok());
        assert!(check([postprocess_log("log.csv", 10_000_000)], false).is_ok());
        // The step estimate is the filter's own count on a 10 Hz log with two rows per time.
        let init = Observation::Init { e: 0.0, n: 0.0, speed: 1.0, compass_deg: 0.0 };
        let mut ten_hz = vec![LogRow { t: 0.0, obs: init, sigma: None }];
        for i in 1..=2000 {
            let t = i as f64 * 0.1;
            ten_hz.push(LogRow { t, obs: Observation::Speed(1.0), sigma: None });
            ten_hz.push(LogRow { t, obs: Observation::Heading { compass_deg: 0.0 }, sigma: None });
        }
        let steps = coopnav_nav::post::postprocess_rows(&ten_hz, &cfg).unwrap().samples.len();
        assert_eq!((steps, postprocess(&ten_hz, &cfg)[0].value), (2001, 2001.0));
        let e = check([postprocess_log("log.csv", 1_000_000_000)], false).unwrap_err().to_string();
        assert!(e.contains("the size of log.csv"), "{e}");
    }

    /// An AUV CNA whose planner-estimator offers its pitch options at the first level only: the
    /// leaves counted are that tree's, A·B at level 1 and A below, not (A·B)^L.
    #[test]
    fn the_estimators_pitch_levels_shrink_its_tree() {
        let file = include_str!("../../../../scenarios/sloping-auv-cna.toml");
        let mut sc = scenario::Scenario::parse(file, Path::new("sloping-auv-cna.toml")).unwrap();
        let tree = &mut sc.policy.planner_estimator.tree;
        (tree.heading_options, tree.look_ahead, tree.pitch_levels) = (Some(9), Some(6), Some(1));
        let leaves = |sc: &scenario::Scenario| {
            closed_loop(sc, 1, 1).into_iter().find(|e| e.what == "planner leaves per decision").unwrap()
        };
        // (9·3)·9⁵ against Hudson's 15⁵ (A = 5, L = 5, three pitch options).
        let e = leaves(&sc);
        assert_eq!(e.value, 27.0 * 9f64.powi(5), "{}", e.fields);
        assert!(e.fields.contains("policy.planner-estimator.tree.pitch_levels"), "{}", e.fields);
        // Left out: the rule's, level 0 only with an AUV CNA.
        sc.policy.planner_estimator.tree.pitch_levels = None;
        assert_eq!(leaves(&sc).value, 27.0 * 9f64.powi(5));
        // Every level of L = 6.
        sc.policy.planner_estimator.tree.pitch_levels = Some(6);
        assert_eq!(leaves(&sc).value, 27f64.powi(6));
        sc.policy.planner_estimator.tree.heading_options = Some(3);
        let hudson = leaves(&sc);
        assert_eq!((hudson.value, hudson.fields.starts_with("policy.planner.tree.heading")), (15f64.powi(5), true));
    }

    #[test]
    fn embedded_scenarios_pass_and_typos_are_refused() {
        let plan = plan::Scenario::parse(plan::EXAMPLE, Path::new("example")).unwrap();
        assert!(check(predeploy(&plan), false).is_ok());
        let mut wide = plan.clone();
        wide.policy.planner.tree.heading_options = Some(1_000_000_000);
        let e = check(predeploy(&wide), false).unwrap_err().to_string();
        assert!(e.contains("policy.planner.tree.heading_options") && e.contains("--allow-large"), "{e}");

        let sim = scenario::Scenario::parse(scenario::EXAMPLE, Path::new("default")).unwrap();
        assert!(check(closed_loop(&sim, 100, 3), false).is_ok());
        let mut wide_estimator = sim.clone();
        wide_estimator.policy.planner_estimator.tree.heading_options = Some(1_000_000);
        let e = check(closed_loop(&wide_estimator, 1, 1), false).unwrap_err().to_string();
        assert!(e.contains("policy.planner-estimator.tree.heading_options") && e.contains("--allow-large"), "{e}");
        let long = scenario::Scenario { duration_s: 1e9, ..sim };
        assert!(check(closed_loop(&long, 1, 1), false).unwrap_err().to_string().contains("duration_s / dt"));

        let hbl = crate::scenario::hbl::table5_scenario(coopnav_nav::cycle::Configuration::HblTwo).unwrap();
        assert!(check(hbl_runs(&hbl, 250.0, "--runs", false), false).is_ok());
        assert!(check(hbl_grid(&hbl, &GridSpec::default()), false).is_ok());
        let fine = scenario::Scenario { dt: 1e-9, ..hbl.clone() };
        assert!(check(hbl_runs(&fine, 1.0, "1 run", true), false).unwrap_err().to_string().contains("duration_s / dt"));
    }
}
