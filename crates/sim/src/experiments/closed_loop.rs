//! `closed-loop-vs-baselines` (docs/evaluation.md, study 1): the estimator-aware planner
//! (`planner-estimator`) against every baseline CNA policy and against Hudson's planner, in the
//! closed loop with the engine's realism on, judged on the survey AUVs' TRUE mean navigation
//! error, paired by run (common random numbers). Two scenarios: the default mission with a water
//! current, and `scenarios/sloping-auv-cna.toml` (sloping seafloor, no current, AUV CNA); N = 1,
//! 2, 3, 5 and 8 survey AUVs. A cell is won when the paired 95 % CI of (planner − baseline) lies
//! entirely below zero; every other cell is printed with its measured cause.
//!
//! The cells are data: `scenarios/experiments/closed-loop-vs-baselines.toml`, a sweep file
//! (docs/sweeps.md) expanded by the sweep expansion, names each scenario file, the fleet sizes it
//! is flown with, the overlays laid over it from a fleet size on (from 6
//! AUVs on every policy flies a schedule sized for the fleet: rate 0's 1 km slots lost the last
//! slot's AUV for every policy) and the reduced form. Nothing is set per cell here: each cell flies
//! what `coopnav simulate` flies for its file, `planner-estimator` with the settings of the
//! planner's rule for the mission (coopnav_plan `auto`) where the file sets none.
//!
//! Seeds: the rule's settings (the aggregate `sigma_sum`, the range bias, the cost-to-go, the
//! level-0 penalty and the reach cost-to-go from 5 AUVs on, L and the pitch levels with the AUV
//! CNA, the fine headings from 6 AUVs on) were picked on base seed [`TUNING_SEED`] (runs
//! `run_seed(1000, 0..R)`, R = 6 to 40); the evaluation uses the base seed of `--seed` (default 1,
//! runs `run_seed(1, 0..runs)`) and refuses that base seed. The baselines run exactly as
//! configured elsewhere (nothing is tuned for or against them).

use super::{Check, Experiment, ExperimentError, ReproOptions, ReproReport, Size};
use crate::batch::mc::{comparison_table, monte_carlo_grid};
use crate::batch::mc::{paired_per_auv, Ci, Comparison, PolicySummary};
use crate::batch::sweep::expand::{expand_with, Form, Rules};
use crate::batch::sweep::file::SweepFile;
use crate::models::cna_navigation::CnaNavigation;
use crate::output::plot::PlotError;
use crate::output::plot::{intervals_svg, Interval};
use crate::policy::registry::POLICY_NAMES;
use crate::scenario::Scenario;
use coopnav_plan::auto::{self, ASC_TRUTH, BIAS_PER_KM, DEPTH_AWARE_BIAS_PER_KM, REACH_SUCCESS, SPREAD_FLEET_MIN_AUVS};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

const ID: &str = "closed-loop-vs-baselines";

/// The policy judged: the reference of every paired difference.
const JUDGED: &str = "planner-estimator";

/// The policy judged, first, then every other policy it must beat (all of them, by name).
pub fn policies() -> Vec<String> {
    let others = POLICY_NAMES.iter().filter(|&&name| name != JUDGED);
    std::iter::once(JUDGED).chain(others.copied()).map(str::to_string).collect()
}

/// Base seed of the runs that chose the planner's aggregate; never an evaluation seed.
pub const TUNING_SEED: u64 = 1000;

/// The second scenario's file, embedded.
const SLOPING: &str = include_str!("../../../../scenarios/sloping-auv-cna.toml");

pub fn experiments() -> Vec<Experiment> {
    vec![Experiment {
        id: ID,
        about: "Closed loop: estimator-aware planner vs Hudson's planner and every baseline, true survey-AUV error, N = 1, 2, 3, 5, 8, two scenarios",
        run: closed_loop_vs_baselines,
    }]
}

/// The experiment's cells, embedded: a sweep file (docs/sweeps.md) of the scenario files, N per
/// scenario, the fleet-size overlay and the reduced form, expanded by the sweep expansion
/// ([`crate::batch::sweep::expand`]) as `coopnav sweep plan` expands it.
const CELLS: &str = include_str!("../../../../scenarios/experiments/closed-loop-vs-baselines.toml");

/// Where [`CELLS`] lives, for messages.
const CELLS_FILE: &str = "scenarios/experiments/closed-loop-vs-baselines.toml";

/// The scenario files [`CELLS`] may name, embedded, by the name it gives them (relative to its
/// folder; "default" is the embedded default mission, as in every sweep file).
const FILES: [(&str, &str); 2] = [("default", crate::scenario::world::EXAMPLE), ("../sloping-auv-cna.toml", SLOPING)];

/// The one axis of [`CELLS`]: the fleet size.
const AXIS: (&str, &str) = ("N", "fleet.n_auvs");

/// One evaluation scenario: its name, the fleet sizes it is flown with, its mission file and how
/// the sweep expansion makes a cell of it ([`CELLS`]).
#[derive(Debug, Clone)]
pub struct Setting {
    pub name: String,
    pub n: Vec<usize>,
    pub base: Scenario,
    /// The sweep file's rules: the N axis, the overlays from a fleet size on, the form's overlay.
    pub rules: Rules,
}

impl Setting {
    /// The mission for `n` AUVs: the cell of the file with `N = n` as the sweep expansion
    /// makes it (`fleet.n_auvs = n`, every conditional overlay that applies, the reduced form's
    /// overlay), with the evaluation's seed and, if given, the duration. The planners' settings
    /// are the file's and, for `planner-estimator`, the rule's for that mission.
    pub fn scenario(&self, n: usize, seed: u64, duration: Option<f64>) -> Result<Scenario, ExperimentError> {
        let value = toml::Value::Integer(i64::try_from(n).map_err(|e| fail(e.to_string()))?);
        let mut sc = self.rules.scenario(&self.base, &[value]).map_err(|e| fail(format!("{CELLS_FILE}: {e}")))?;
        sc.seed = seed;
        if let Some(d) = duration {
            sc.duration_s = d;
        }
        Ok(sc)
    }
}

/// The experiment's size: (settings, runs per policy and cell), read from [`CELLS`] in the form
/// of `opts` (the reduced form's shorter missions are its overlay, in every cell).
pub fn setup(opts: &ReproOptions) -> Result<(Vec<Setting>, usize), ExperimentError> {
    setup_from(CELLS, opts)
}

/// [`setup`] from the cells file's text.
fn setup_from(text: &str, opts: &ReproOptions) -> Result<(Vec<Setting>, usize), ExperimentError> {
    let file = Path::new(CELLS_FILE);
    let sweep = SweepFile::parse(text, file).map_err(|e| fail(e.to_string()))?;
    if sweep.policies != policies() {
        return Err(fail(format!(
            "{CELLS_FILE}: policies = {:?}: the reproduction compares {JUDGED}, first, with every other policy, in \
             this order: {:?}",
            sweep.policies,
            policies()
        )));
    }
    let axes: Vec<(Option<&str>, Option<&str>)> =
        sweep.axes.iter().map(|a| (a.name.as_deref(), a.path.as_deref())).collect();
    if axes != [(Some(AXIS.0), Some(AXIS.1))] {
        return Err(fail(format!(
            "{CELLS_FILE}: the reproduction's cells have one axis, name = \"{}\", path = \"{}\"",
            AXIS.0, AXIS.1
        )));
    }
    let load = |name: &str| {
        let known: Vec<&str> = FILES.iter().map(|(name, _)| *name).collect();
        let (_, text) = FILES
            .iter()
            .find(|(own, _)| *own == name)
            .ok_or_else(|| format!("not one of {} (the files the reproduction embeds)", known.join(", ")))?;
        Scenario::parse(text, Path::new(name)).map_err(|e| e.to_string())
    };
    let form = match opts.size {
        Size::Full => Form::Full,
        Size::Reduced => Form::Reduced,
    };
    let e = expand_with(&sweep, file, form, false, &load).map_err(|e| fail(e.to_string()))?;
    let mut settings = Vec::new();
    for b in &e.bases {
        let n = b.values[0]
            .iter()
            .map(|v| v.as_integer().and_then(|n| usize::try_from(n).ok()))
            .collect::<Option<Vec<usize>>>()
            .ok_or_else(|| fail(format!("{CELLS_FILE}: scenario {}: N must be whole numbers", b.name)))?;
        settings.push(Setting { name: b.name.clone(), n, base: b.scenario.clone(), rules: e.rules.clone() });
    }
    // Every cell is checked before any run, with the evaluation's seed.
    for s in &settings {
        for &n in &s.n {
            s.scenario(n, opts.seed, None)?.validate(file).map_err(|e| fail(e.to_string()))?;
        }
    }
    Ok((settings, e.runs))
}

fn fail(message: String) -> ExperimentError {
    ExperimentError::Failed { id: ID.into(), message }
}

fn closed_loop_vs_baselines(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    run_with_progress(opts, opts.progress)
}

/// One cell's paired difference (planner-estimator − baseline), m.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Cell {
    pub scenario: String,
    pub n: usize,
    pub baseline: String,
    pub mean: f64,
    pub low: f64,
    pub high: f64,
    pub won: bool,
}

/// Runs the experiment; `progress(done)` counts the finished runs of the whole grid.
pub fn run_with_progress(opts: &ReproOptions, progress: &(dyn Fn(u64) + Sync)) -> Result<ReproReport, ExperimentError> {
    let (settings, runs) = setup(opts)?;
    evaluate(&settings, runs, None, opts.seed, &policies(), progress)
}

/// Every cell of `settings` with `runs` runs per policy (`policies`, `JUDGED` first; [`policies`]
/// is every one) from base seed `seed` (never [`TUNING_SEED`]); `duration` overrides the missions'
/// length.
pub fn evaluate(
    settings: &[Setting],
    runs: usize,
    duration: Option<f64>,
    seed: u64,
    policies: &[String],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ReproReport, ExperimentError> {
    check_inputs(seed, policies)?;
    // Every cell's runs go through one pool (no cell waits for the previous cell's slowest run).
    let names: Vec<&str> = settings.iter().flat_map(|s| s.n.iter().map(move |_| s.name.as_str())).collect();
    let scenarios: Vec<Scenario> = settings
        .iter()
        .flat_map(|s| s.n.iter().map(move |&n| s.scenario(n, seed, duration)))
        .collect::<Result<_, _>>()?;
    let comparisons = monte_carlo_grid(&scenarios, policies, runs, progress).map_err(|e| fail(e.to_string()))?;
    let named: Vec<(&str, &Scenario)> = names.iter().copied().zip(&scenarios).collect();
    report(&named, comparisons, runs, seed)
}

/// The seed and policies an evaluation may use (refused before any run).
fn check_inputs(seed: u64, policies: &[String]) -> Result<(), ExperimentError> {
    if seed == TUNING_SEED {
        return Err(fail(format!(
            "seed {TUNING_SEED} chose the planner's settings; evaluate on another base seed (--seed)"
        )));
    }
    if policies.first().map(String::as_str) != Some(JUDGED) {
        return Err(fail(format!("the first policy must be {JUDGED}, the one judged")));
    }
    Ok(())
}

/// The report of cells already run: each cell's (scenario name, scenario) and its comparison,
/// in the same order, `runs` runs per policy from base seed `seed`. [`evaluate`] runs the cells
/// and reports here; `coopnav sweep merge` reports here from a sweep's merged runs.
pub fn report(
    named: &[(&str, &Scenario)],
    comparisons: Vec<Comparison>,
    runs: usize,
    seed: u64,
) -> Result<ReproReport, ExperimentError> {
    let policies: Vec<String> =
        comparisons.first().map_or(Vec::new(), |c| c.policies.iter().map(|p| p.policy.clone()).collect());
    check_inputs(seed, &policies)?;
    if named.len() != comparisons.len() {
        return Err(fail(format!("{} cells but {} comparisons", named.len(), comparisons.len())));
    }
    // The AUV CNA's true-error model as the rule gives it for the first AUV-CNA scenario.
    let auv_diffusion = named.iter().find_map(|(_, s)| s.cna.auv.as_ref().map(|_| s.cna.navigation.diffusion_m2_s()));
    let auv_cna_truth = auto::auv_cna_truth(auv_diffusion.unwrap_or(0.0));
    let mut table = format!(
        "True mean navigation error of the survey AUVs (m), {runs} runs per policy and cell, base seed {seed} \
         (settings chosen on base seed {TUNING_SEED}); planners A=5, L=5; planner-estimator: its tree and cost per \
         cell below (with the AUV CNA: every policy cruising at the depth the sound-speed profile favours for the \
         fleet, its pitch options at level 0 only, from 2 AUVs on its depth chosen by the profile with the \
         range bias the profile gives plus {DEPTH_AWARE_BIAS_PER_KM} m/km, levelling off at each step's depth), \
         aggregate sigma_sum, range bias {BIAS_PER_KM} m/km; from \
         {SPREAD_FLEET_MIN_AUVS} AUVs on no level-0 distance penalty and the reach cost-to-go (p_u {REACH_SUCCESS}). \
         The true-error cost scores the AUVs' expected true error: with the ASC in a current its filters do not \
         model, the current (its ADCP) as their mean error (drift {} m²/s, ranges σ {} m); with the AUV CNA drift \
         {} m²/s and the CNA's own diffusion {} m²/s.\n\
         Every difference is planner-estimator minus the baseline, paired by run; a cell is won when its 95 % CI \
         lies below zero.\n",
        ASC_TRUTH.drift_m2_s, ASC_TRUTH.range_noise.sigma_m, auv_cna_truth.drift_m2_s, auv_cna_truth.cna_diffusion_m2_s
    );
    let (mut checks, mut cells, mut data) = (Vec::new(), Vec::new(), Vec::new());
    table += &estimator_trees(named);
    table.push('\n');
    for ((name, sc), c) in named.iter().zip(comparisons) {
        let comms = &sc.comms;
        let _ = writeln!(
            table,
            "scenario {name}, tau = {} s, CNA rate {}, status rate {}, slots for {} m",
            comms.tau, comms.cna_rate, comms.status_rate, comms.max_range_m
        );
        table += &comparison_table(&c);
        let inherits_cna_error = sc.cna.auv.is_some() && !matches!(sc.cna.navigation, CnaNavigation::Exact(_));
        cell_checks(name, &c, inherits_cna_error, &mut table, &mut checks, &mut cells)?;
        table.push('\n');
        data.push(serde_json::to_value(&c).map_err(|e| fail(e.to_string()))?);
    }
    table += &summary_grid(&cells);
    let mut plots = Vec::new();
    let mut scenario_names: Vec<&str> = named.iter().map(|(name, _)| *name).collect();
    scenario_names.dedup();
    for name in scenario_names {
        let own: Vec<Cell> = cells.iter().filter(|c| c.scenario == name).cloned().collect();
        plots.push((format!("differences-{name}.svg"), difference_svg(&own).map_err(|e| fail(e.to_string()))?));
    }
    let data = serde_json::json!({ "comparisons": data, "cells": cells });
    Ok(ReproReport { plots, ..ReproReport::new(ID.into(), table, checks, data) })
}

/// planner-estimator's tree and cost in every cell, as its scenario and the rule set them: A
/// headings, L levels, H levels of cost-to-go, whether it scores true error or the filters'
/// covariances, and how it joins the AUVs' terms.
fn estimator_trees(scenarios: &[(&str, &Scenario)]) -> String {
    let mut out = String::from(
        "planner-estimator's tree per cell (A headings, L levels, H levels of cost-to-go, cost, aggregate):\n",
    );
    let mut names: Vec<&str> = scenarios.iter().map(|(name, _)| *name).collect();
    names.dedup();
    for name in names {
        let cells: Vec<String> = scenarios
            .iter()
            .filter(|(own, _)| *own == name)
            .map(|(_, sc)| {
                let Some(e) = sc.estimator_settings() else {
                    return format!("N={}: Hudson's cost", sc.fleet.n_auvs);
                };
                let (a, l, h) = (e.heading_options, e.look_ahead, e.terminal_levels);
                let cost = if e.truth.is_some() { "true error" } else { "covariance" };
                let aggregate = serde_json::to_value(e.aggregate).unwrap_or_default();
                let aggregate = aggregate.as_str().unwrap_or("?");
                format!("N={}: A={a} L={l} H={h} {cost} {aggregate}", sc.fleet.n_auvs)
            })
            .collect();
        let _ = writeln!(out, "  {name}: {}", cells.join(" | "));
    }
    out
}

/// The checks of one comparison: one per baseline (won or not, with the cause), filter health.
/// `inherits_cna_error`: the CNA is an AUV broadcasting its own navigation estimate.
fn cell_checks(
    scenario: &str,
    c: &Comparison,
    inherits_cna_error: bool,
    table: &mut String,
    checks: &mut Vec<Check>,
    cells: &mut Vec<Cell>,
) -> Result<(), ExperimentError> {
    let n = c.n_auvs;
    let planner = c.policies.first().ok_or_else(|| fail("no policy in the comparison".into()))?;
    for p in &c.paired {
        let b = find(c, &p.baseline).ok_or_else(|| fail(format!("{} missing from the comparison", p.baseline)))?;
        let d = p.difference;
        if !p.planner_better {
            let _ = writeln!(
                table,
                "  cell not won, {scenario} N={n} vs {}: {}",
                p.baseline,
                why(planner, b, d.low <= 0.0)
            );
        }
        checks.push(Check::new(
            format!("{scenario} N={n}: planner-estimator beats {}", p.baseline),
            p.planner_better,
            format!("difference {:.2} m [{:.2}, {:.2}]", d.mean, d.low, d.high),
        ));
        cells.push(Cell {
            scenario: scenario.into(),
            n,
            baseline: p.baseline.clone(),
            mean: d.mean,
            low: d.low,
            high: d.high,
            won: p.planner_better,
        });
    }
    if c.paired.iter().any(|p| !p.planner_better) {
        let cna_error = if inherits_cna_error { format!("; {CNA_ERROR_CAUSE}") } else { String::new() };
        let _ = writeln!(table, "  cell cause, {scenario} N={n}: {}{cna_error}", how_much_the_path_decides(c));
    }
    checks.push(Check::new(
        format!("{scenario} N={n}: every filter healthy"),
        c.policies.iter().all(|s| s.healthy),
        "no NaN, finite covariances",
    ));
    Ok(())
}

fn find<'a>(c: &'a Comparison, name: &str) -> Option<&'a PolicySummary> {
    c.policies.iter().find(|s| s.policy == name)
}

/// Cells won per scenario and N, as a compact grid.
fn summary_grid(cells: &[Cell]) -> String {
    let mut out = String::from("Cells won (paired 95 % CI below zero), per scenario and N:\n");
    let mut keys: Vec<(&str, usize)> = cells.iter().map(|c| (c.scenario.as_str(), c.n)).collect();
    keys.dedup();
    for (scenario, n) in keys {
        let row: Vec<&Cell> = cells.iter().filter(|c| c.scenario == scenario && c.n == n).collect();
        let lost: Vec<&str> = row.iter().filter(|c| !c.won).map(|c| c.baseline.as_str()).collect();
        let _ = writeln!(
            out,
            "  {scenario:<16} N={n}: {}/{} won{}",
            row.len() - lost.len(),
            row.len(),
            if lost.is_empty() { String::new() } else { format!("; not won vs {}", lost.join(", ")) }
        );
    }
    out
}

/// A cause to check in an AUV-CNA cell not won; whether it decides the cell is measured
/// elsewhere (`closed-loop-cna-navigation`: at N = 1 it does, at N = 8 it does not), so the
/// report names it as a question with its measurement, not as the cell's cause.
const CNA_ERROR_CAUSE: &str = "to check: every AUV the CNA pings inherits the AUV CNA's own navigation error (a \
     random walk, 1 to 3 m between GPS fixes) whatever the CNA's path; whether that decides this cell, `coopnav \
     reproduce closed-loop-cna-navigation` measures (the same cells with the CNA broadcasting its true position, on \
     the same seeds)";

/// The cell-wide measured argument for a cell not won: how far apart the policies that ping end
/// (the best, the median), how far no CNA at all is, and how wide the paired intervals are at
/// this number of runs. Where the median pinging policy ends within about one interval width of
/// the best, the path decides less than the runs can resolve.
fn how_much_the_path_decides(c: &Comparison) -> String {
    let mut pinging: Vec<&PolicySummary> = c.policies.iter().filter(|s| s.policy != "none").collect();
    pinging.sort_by(|a, b| a.mean_error.mean.total_cmp(&b.mean_error.mean));
    let mut half_widths: Vec<f64> = c.paired.iter().map(|p| 0.5 * (p.difference.high - p.difference.low)).collect();
    half_widths.sort_by(f64::total_cmp);
    let (Some(best), Some(median), Some(half)) =
        (pinging.first(), pinging.get(pinging.len() / 2), half_widths.get(half_widths.len() / 2))
    else {
        return "no policy to compare".into();
    };
    let none = find(c, "none").map_or("not run".into(), |s| format!("{:.2} m", s.mean_error.mean));
    format!(
        "the median of the {} policies that ping ends {:.2} m behind the best ({} {:.2} m); no CNA at all {none}; \
         the median paired 95 % CI half-width at {} runs is {:.2} m",
        pinging.len(),
        median.mean_error.mean - best.mean_error.mean,
        best.policy,
        best.mean_error.mean,
        c.runs,
        half
    )
}

/// Where in the fleet the difference lies (two AUVs or more): the paired difference per AUV, the
/// AUVs on which either policy is significantly better, and the AUVs whose status messages never
/// reached the CNA under either policy (a policy steering by the reports never looks for those:
/// the thesis's start rule, Hudson 2012, Sec. 4.2).
fn fleet_split(planner: &PolicySummary, b: &PolicySummary) -> Option<String> {
    let per_auv = paired_per_auv(planner, b);
    if per_auv.len() < 2 {
        return None;
    }
    let auvs = |keep: &dyn Fn(usize, &Ci) -> bool| -> String {
        let ks: Vec<String> =
            per_auv.iter().enumerate().filter(|(k, d)| keep(*k, d)).map(|(k, _)| k.to_string()).collect();
        match ks.len() {
            0 => "no AUV".into(),
            1 => format!("AUV {}", ks[0]),
            _ => format!("AUVs {}", ks.join(", ")),
        }
    };
    let values: Vec<String> = per_auv.iter().map(|d| format!("{:+.2}", d.mean)).collect();
    let mut split = format!(
        "per AUV (planner-estimator minus {}, paired, m: {}) it is better on {} and worse on {}",
        b.policy,
        values.join(" "),
        auvs(&|_, d| d.high < 0.0),
        auvs(&|_, d| d.low > 0.0)
    );
    let unheard = |k: usize| planner.auv_heard_runs.get(k) == Some(&0) && b.auv_heard_runs.get(k) == Some(&0);
    if (0..per_auv.len()).any(unheard) {
        let _ = write!(
            split,
            "; no status message from {} reached the CNA in any run under either policy: policies that steer by \
             the reports never look for such an AUV",
            auvs(&|k, _| unheard(k))
        );
        for k in (0..per_auv.len()).filter(|&k| unheard(k)) {
            split += &lost_in_air(k, [planner, b]);
        }
    }
    Some(split)
}

/// Of unheard AUV `k`'s statuses under both policies, how many the channel decoded and a
/// collision or half-duplex lost: the schedule's slots hold the travel time of
/// `comms.max_range_m` only, so a status sent from farther arrives while another modem sends
/// (the CNA's own broadcast, for the slot before it).
fn lost_in_air(k: usize, policies: [&PolicySummary; 2]) -> String {
    let total = |f: &dyn Fn(&PolicySummary) -> Option<u64>| policies.iter().filter_map(|p| f(p)).sum::<u64>();
    let sent = total(&|p| p.auv_status_sent.get(k).copied());
    let lost = total(&|p| p.auv_status_lost_in_air.get(k).copied());
    if lost == 0 {
        return String::new();
    }
    format!(
        "; of AUV {k}'s {sent} statuses, {lost} that the channel decoded were lost to a collision or half-duplex (a \
         slot holds the travel time of comms.max_range_m only, and from farther a status arrives while another \
         modem sends)"
    )
}

/// The measured differences that explain a cell not won, only those that apply.
fn why(planner: &PolicySummary, b: &PolicySummary, tie: bool) -> String {
    let mut reasons = Vec::new();
    if tie {
        reasons.push("the paired 95 % CI includes zero: no significant difference either way".to_string());
    }
    if b.downlink_success > planner.downlink_success + 0.01 {
        reasons.push(format!(
            "{} delivers more ranges ({:.0}% vs {:.0}%)",
            b.policy,
            100.0 * b.downlink_success,
            100.0 * planner.downlink_success
        ));
    }
    if b.limit_violation > planner.limit_violation + 0.02 {
        reasons.push(format!(
            "{} spends {:.0}% of the time outside the distance limits (planner {:.0}%): it uses geometry the \
             planner's limit penalties forbid",
            b.policy,
            100.0 * b.limit_violation,
            100.0 * planner.limit_violation
        ));
    }
    if planner.nees_mean + 0.05 < b.nees_mean {
        reasons.push(format!(
            "the filters are more conservative under the planner (NEES {:.2} vs {:.2}; consistent = 2): the \
             covariances it minimises overstate the error",
            planner.nees_mean, b.nees_mean
        ));
    }
    reasons.extend(fleet_split(planner, b));
    if reasons.is_empty() {
        reasons.push("no single measured factor stands out".into());
    }
    format!(
        "planner-estimator {:.2} m vs {} {:.2} m; {}.",
        planner.mean_error.mean,
        b.policy,
        b.mean_error.mean,
        reasons.join("; ")
    )
}

/// An SVG of every cell's paired difference with its 95 % CI (one row per scenario, N and
/// baseline; zero marked): the plot beside the table.
pub fn difference_svg(cells: &[Cell]) -> Result<String, PlotError> {
    let title = "planner-estimator minus baseline, true mean error (m), paired 95 % CI";
    let rows: Vec<Interval> = cells
        .iter()
        .map(|c| Interval {
            label: format!("{} N={} vs {}", c.scenario, c.n, c.baseline),
            mean: c.mean,
            low: c.low,
            high: c.high,
            good: c.won,
        })
        .collect();
    intervals_svg(title, "difference, m (negative = planner better)", &rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::mc::monte_carlo;
    use crate::models::surfacing::at_surface;
    use coopnav_acomms::Rate;
    use coopnav_plan::{CnaKind, PenaltyCase};

    #[test]
    fn reduced_form_runs_every_cell_and_explains_each_cell_not_won() {
        let r = closed_loop_vs_baselines(&ReproOptions::new(Size::Reduced, 1)).unwrap();
        let by_name =
            |name: String| r.checks.iter().find(|c| c.name == name).unwrap_or_else(|| panic!("no check {name}"));
        for (scenario, n) in [("current", 1), ("current", 3), ("sloping-auv-cna", 2)] {
            assert!(by_name(format!("{scenario} N={n}: every filter healthy")).passed());
        }
        // In a current, dead reckoning alone must lose clearly, whatever else happens. (Without
        // current, over the reduced 15 minutes, it does not: see the module's report.)
        for n in [1, 3] {
            let dr = by_name(format!("current N={n}: planner-estimator beats none"));
            assert!(dr.passed(), "{}", dr.detail);
        }
        // With current at N = 3 the planner must beat every baseline, Hudson's planner included:
        // before the range-bias model and the cost-to-go it lost to zigzag, centroid and trail.
        // centroid-standoff is the one exception the runs of 15 minutes cannot resolve (8 runs
        // leave its interval across zero, while one-hour runs resolve it in the planner's favour);
        // its check must still be there and explained.
        for name in policies().iter().skip(1).filter(|&name| name != "centroid-standoff") {
            let c = by_name(format!("current N=3: planner-estimator beats {name}"));
            assert!(c.passed(), "{name}: {}", c.detail);
        }
        let standoff = by_name("current N=3: planner-estimator beats centroid-standoff".into());
        assert!(standoff.passed() || r.table.contains("cell not won, current N=3 vs centroid-standoff"));
        // One check per baseline and cell, plus health per cell.
        assert_eq!(r.checks.len(), 3 * policies().len());
        assert!(r.table.contains("greedy-fisher") && r.table.contains("open-loop"));
        let lost = r.checks.iter().filter(|c| c.name.contains("beats") && !c.passed()).count();
        assert_eq!(r.table.matches("cell not won").count(), lost);
        let cells_lost: std::collections::BTreeSet<&str> = r
            .checks
            .iter()
            .filter(|c| c.name.contains("beats") && !c.passed())
            .filter_map(|c| c.name.split(':').next())
            .collect();
        assert_eq!(r.table.matches("cell cause,").count(), cells_lost.len());
        assert!(r.table.contains("Cells won"));
    }

    #[test]
    fn spread_fleets_trade_the_level_0_penalty_for_the_reach_cost_to_go() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        for setting in &settings {
            let small = setting.scenario(2, 1, None).unwrap().estimator_settings().unwrap();
            let spread = setting.scenario(5, 1, None).unwrap().estimator_settings().unwrap();
            assert_eq!((small.penalty_case, small.reach_success, small.terminal_levels), (None, 0.0, 10.0));
            assert_eq!(spread.penalty_case, Some(PenaltyCase::C3));
            assert_eq!((spread.reach_success, spread.terminal_levels), (0.79, 20.0));
        }
    }

    /// The ASC's cells score true error with the current the default mission's ADCP measures as
    /// its mean, and `simulate` on the default mission flies the same planner as the N = 3 cell.
    #[test]
    fn in_the_current_the_estimator_scores_true_error_with_the_current_as_its_mean() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        let cell = |name: &str| settings.iter().find(|s| s.name == name).unwrap().scenario(3, 1, None).unwrap();
        // (The sloping scenario's AUV CNA: `the_auv_cna_works_below_the_surface_at_every_fleet_size`.)
        let current = cell("current");
        let e = current.estimator_settings().unwrap();
        assert_eq!(e.truth, Some(ASC_TRUTH));
        let water = [current.fleet.current.0, current.fleet.current.1];
        assert!(water != [0.0, 0.0] && e.unmodelled_current == water && current.cna.adcp_current == water);
        let default = Scenario::example();
        assert_eq!(default.policy, current.policy);
        assert_eq!(default.estimator_settings(), Some(e));
        assert_eq!(e.look_ahead, 4);
    }

    fn summary(policy: &str, auv_runs: Vec<Vec<f64>>, auv_heard_runs: Vec<usize>) -> PolicySummary {
        let runs: Vec<f64> = (0..auv_runs[0].len())
            .map(|i| auv_runs.iter().map(|a| a[i]).sum::<f64>() / auv_runs.len() as f64)
            .collect();
        PolicySummary {
            policy: policy.into(),
            mean_error: Ci::of(&runs),
            rms_error: 0.0,
            p95_error: 0.0,
            max_error: 0.0,
            modelled_mean: None,
            downlink_success: 0.5,
            uplink_success: 0.5,
            limit_violation: 0.0,
            deadline_misses: 0,
            healthy: true,
            nees_mean: 1.0,
            diverged: 0,
            recoveries: 0,
            auv_status_sent: vec![10; auv_runs.len()],
            auv_status_lost_in_air: vec![0; auv_runs.len()],
            runs,
            auv_runs,
            auv_heard_runs,
        }
    }

    /// A tie made of a gain on one end of the fleet and a loss on the other, with an AUV never
    /// heard from: the cell's explanation names both ends and the unheard AUV.
    #[test]
    fn a_cell_not_won_says_where_in_the_fleet_the_difference_lies() {
        let planner = summary(
            "planner-estimator",
            vec![vec![2.0, 2.1, 1.9], vec![4.0, 5.0, 3.0], vec![6.0, 6.1, 5.9]],
            vec![3, 3, 0],
        );
        let trail =
            summary("trail", vec![vec![5.0, 5.1, 4.9], vec![4.0, 5.0, 3.0], vec![3.0, 3.1, 2.9]], vec![3, 2, 0]);
        let text = why(&planner, &trail, true);
        assert!(text.contains("(planner-estimator minus trail, paired, m: -3.00 +0.00 +3.00)"), "{text}");
        assert!(text.contains("better on AUV 0 and worse on AUV 2"), "{text}");
        assert!(text.contains("no status message from AUV 2 reached the CNA"), "{text}");
        assert!(!text.contains("lost to a collision"), "none was lost in the air: {text}");
        // Lost in the air: the count over both policies, for the unheard AUV only.
        let (mut p_air, mut t_air) = (planner.clone(), trail.clone());
        p_air.auv_status_lost_in_air = vec![1, 0, 4];
        t_air.auv_status_lost_in_air = vec![0, 0, 3];
        let text = why(&p_air, &t_air, true);
        assert!(text.contains("of AUV 2's 20 statuses, 7 that the channel decoded were lost to a collision"), "{text}");
        assert!(!text.contains("AUV 0's"), "{text}");
        // Heard under one of the two: not named.
        let heard = summary("trail", trail.auv_runs.clone(), vec![3, 2, 1]);
        assert!(!why(&planner, &heard, true).contains("no status message"));
        // One AUV: no split.
        let one = |name: &str| summary(name, vec![vec![1.0, 2.0]], vec![2]);
        assert!(!why(&one("planner-estimator"), &one("zigzag"), true).contains("per AUV"));
    }

    /// The second scenario is an AUV-CNA one: at every N every policy's CNA works submerged (at the
    /// surface it would have its GPS there and be a surface craft in all but speed). At N = 1, 3, 5
    /// and 8 planner-estimator scores true error with the CNA's own diffusion.
    #[test]
    fn the_auv_cna_works_below_the_surface_at_every_fleet_size() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        let sloping = settings.iter().find(|s| s.name == "sloping-auv-cna").unwrap();
        for n in [1, 2, 3, 5, 8] {
            let sc = sloping.scenario(n, 1, None).unwrap();
            let depth = sc.cna_cruise_depth();
            assert!(!at_surface(depth), "N = {n}: cruise depth {depth} m");
            match sc.planner_config().motion.cna {
                CnaKind::Auv { min_depth, .. } => assert!(!at_surface(min_depth) && depth >= min_depth, "N = {n}"),
                CnaKind::Asc {} => panic!("N = {n}: an ASC"),
            }
            let diffusion = sc.cna.navigation.diffusion_m2_s();
            assert_eq!(diffusion, 0.01, "the scenario's own diffusion");
            let truth = sc.estimator_settings().unwrap().truth;
            assert_eq!(
                truth.map(|t| (t.drift_m2_s, t.cna_diffusion_m2_s)),
                (n != 2).then_some((0.01, diffusion)),
                "N = {n}"
            );
        }
    }

    /// The report's header says which tree and cost each cell flies (the rule's, written out:
    /// `coopnav_plan::auto`'s test holds every setting of every cell).
    #[test]
    fn each_cell_plans_with_its_tree() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        let cells: Vec<(String, Scenario)> = settings
            .iter()
            .flat_map(|s| s.n.iter().map(|&n| (s.name.clone(), s.scenario(n, 1, None).unwrap())))
            .collect();
        for (name, sc) in &cells {
            let hudson = sc.planner_config();
            assert_eq!((hudson.motion.heading_options, hudson.look_ahead), (5, 5), "Hudson's planner, {name}");
        }
        let named: Vec<(&str, &Scenario)> = cells.iter().map(|(name, sc)| (name.as_str(), sc)).collect();
        let header = estimator_trees(&named);
        let current = "current: N=1: A=5 L=4 H=10 true error sigma_sum | N=2: A=5 L=4 H=10 true error sigma_sum | \
                       N=3: A=5 L=4 H=10 true error sigma_sum | N=5: A=5 L=4 H=20 true error sigma_sum | \
                       N=8: A=21 L=2 H=40 true error trace_sum";
        let sloping =
            "sloping-auv-cna: N=1: A=9 L=3 H=40 true error sigma_sum | N=2: A=5 L=5 H=10 covariance sigma_sum | \
                       N=3: A=9 L=3 H=40 true error sigma_sum | N=5: A=9 L=3 H=20 true error sigma_sum | \
                       N=8: A=21 L=2 H=40 true error trace_sum";
        assert!(header.contains(current), "{header}");
        assert!(header.contains(sloping), "{header}");
    }

    /// From 6 AUVs on the schedule is sized for the fleet: rate 1 in 44 s slots holding 2.5 km,
    /// where rate 0's 1 km slots lost the last slot's AUV for every policy. A 15-minute mission
    /// of centroid-standoff with 8 AUVs hears every AUV under the sized schedule, and never the
    /// last one under rate 0's (the measured reason for the change); smaller fleets keep rate 0.
    #[test]
    fn eight_auvs_fly_a_schedule_sized_for_the_fleet() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        let heard = |sc: &Scenario| {
            let c = monte_carlo(sc, &["centroid-standoff".to_string()], 1, &|_| {}).unwrap();
            c.policies[0].auv_heard_runs.clone()
        };
        for setting in &settings {
            let small = setting.scenario(5, 1, None).unwrap().comms;
            assert_eq!((small.cna_rate, small.status_rate, small.tau), (Rate::R0, Rate::R0, 30.0), "{}", setting.name);
            let sized = setting.scenario(8, 1, Some(900.0)).unwrap();
            let c = &sized.comms;
            assert_eq!((c.cna_rate, c.status_rate, c.tau, c.max_range_m), (Rate::R1, Rate::R1, 44.0, 2500.0));
            assert_eq!(heard(&sized), vec![1; 8], "{}: every AUV heard", setting.name);
            let mut rate0 = sized.clone();
            (rate0.comms.cna_rate, rate0.comms.status_rate, rate0.comms.max_range_m) = (Rate::R0, Rate::R0, 1000.0);
            assert_eq!(heard(&rate0)[7], 0, "{}: the last slot's AUV, rate 0", setting.name);
        }
    }

    /// A cell file naming a scenario file the experiment does not embed, a reduced cell of a
    /// scenario it does not list, or another list of policies is refused by name; a bad
    /// fleet-size overlay is refused before any run.
    #[test]
    fn bad_cells_are_refused_by_name() {
        let opts = ReproOptions::new(Size::Reduced, 1);
        let err = |text: String| {
            assert_ne!(text, CELLS);
            setup_from(&text, &opts).map(|_| ()).unwrap_err().to_string()
        };
        let e = err(CELLS.replace("file = \"default\"", "file = \"elsewhere.toml\""));
        assert!(
            e.contains("scenario[0].file = \"elsewhere.toml\": not one of default, ../sloping-auv-cna.toml"),
            "{e}"
        );
        let e = err(CELLS.replace("{ name = \"current\"", "{ name = \"nowhere\""));
        assert!(e.contains("reduced.scenario[0].name = \"nowhere\": no such base scenario"), "{e}");
        let e = err(CELLS.replace("\"none\", ", ""));
        assert!(e.contains("policies = [") && e.contains("every other policy"), "{e}");
        let full = ReproOptions::new(Size::Full, 1);
        let bad = CELLS.replace("max_range_m = 2500.0", "max_range_m = \"far\"");
        assert_ne!(bad, CELLS);
        let e = setup_from(&bad, &full).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("overlay.fleet-sized-schedule: ") && e.contains("max_range_m"), "{e}");
        assert!(setup_from(CELLS, &full).is_ok());
    }

    /// The reduced form is the file's [reduced] table: its runs, its cells in its order, its
    /// 15-minute missions; the full form flies one hour.
    #[test]
    fn the_reduced_form_is_the_sweep_files_reduced_table() {
        let (settings, runs) = setup(&ReproOptions::new(Size::Reduced, 1)).unwrap();
        assert_eq!(runs, 8);
        let cells: Vec<(&str, Vec<usize>)> = settings.iter().map(|s| (s.name.as_str(), s.n.clone())).collect();
        assert_eq!(cells, [("current", vec![1, 3]), ("sloping-auv-cna", vec![2])]);
        assert_eq!(settings[0].scenario(3, 7, None).unwrap().duration_s, 900.0);
        assert_eq!(settings[0].scenario(3, 7, None).unwrap().seed, 7);
        let (full, runs) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        assert_eq!((runs, full[1].n.clone()), (100, vec![1, 2, 3, 5, 8]));
        assert_eq!(full[0].scenario(3, 1, None).unwrap().duration_s, 3600.0);
    }

    #[test]
    fn the_tuning_seed_is_refused() {
        let e = closed_loop_vs_baselines(&ReproOptions::new(Size::Reduced, TUNING_SEED)).unwrap_err();
        assert!(e.to_string().contains("--seed"), "{e}");
    }

    #[test]
    fn the_difference_plot_draws_one_interval_per_cell() {
        let cell = |baseline: &str, mean: f64, won: bool| Cell {
            scenario: "current".into(),
            n: 3,
            baseline: baseline.into(),
            mean,
            low: mean - 1.0,
            high: mean + 1.0,
            won,
        };
        let svg = difference_svg(&[cell("centroid", -2.0, true), cell("trail", 0.5, false)]).unwrap();
        assert!(svg.contains("current N=3 vs centroid") && svg.contains("current N=3 vs trail"));
        assert_eq!(svg.matches("<circle").count(), 2);
    }
}
