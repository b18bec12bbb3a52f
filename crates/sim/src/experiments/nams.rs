//! Nams (2014) reproductions: Tables 9–11 (bandwidth, status period, duty cycle of the adaptive
//! selector against the best control, in the most and least favourable scenarios).
//!
//! Our channel is not the thesis's: Bedford Basin bathymetry is not available, so vehicles fly
//! over the synthetic shelf, and the reproduction uses the analytic TL model (spherical
//! spreading + Thorp, k = 2, chosen because it is closer than k = 1.5 to what the real BELLHOP
//! gives on that shelf; see the note in the output) so that it runs anywhere in seconds.
//! Absolute numbers therefore differ; the orderings (adaptive against the best control) are
//! checked, and their effect sizes (adaptive over control) compared with the thesis's in the band
//! of docs/models.md#nams-bands.

use super::{
    ordering_verdict, Band, Check, Experiment, ExperimentError, ReproOptions, ReproReport, Size, ThesisNumber,
    ThesisTable, Verdict,
};
use crate::batch::nams::{run_experiment, Cell, ExperimentResult, ExperimentTl};
use crate::models::tl_spec::{GridModel, TlModel};
use crate::scenario::nams::{table_6, Behaviour, ExperimentConfig};
use coopnav_acomms::tl::analytic::Thorp;
use std::fmt::Write as _;
use std::sync::Arc;

const ID: &str = "nams-tables-9-11";
const GRID_ID: &str = "nams-tables-9-11-bellhop-grid";

pub fn experiments() -> Vec<Experiment> {
    vec![
        Experiment {
            id: ID,
            about: "Nams Tables 9–11: adaptive modem-rate selection vs the best fixed/alternating control (bandwidth, status period, duty cycle)",
            run: tables_9_11,
        },
        Experiment {
            id: GRID_ID,
            about: "Nams Tables 9–11 on a BELLHOP grid over each square (needs scripts/install-bellhop.sh; grids cached on disk)",
            run: tables_9_11_bellhop_grid,
        },
    ]
}

/// The reproduction's TL model (docs/models.md#nams-transmission-loss, k = 2).
pub fn default_tl() -> Thorp {
    Thorp { k: 2.0, ..Thorp::default() }
}

/// Configuration of the reproduction at a given size.
pub fn config(opts: &ReproOptions) -> ExperimentConfig {
    let mut cfg = ExperimentConfig { seed: opts.seed, ..ExperimentConfig::default() };
    if opts.size == Size::Reduced {
        // The two environments the tables compare, fewer runs.
        let table = table_6();
        cfg.scenarios = vec![table[0].clone(), table[3].clone()];
        cfg.runs = 6;
    }
    cfg
}

/// Thesis values: (scenario, adaptive, best control) for Tables 9, 10 and 11 (duty cycle per
/// Nams 2014, §5.4.3, which Table 11 contradicts: adaptive 0.38 vs control 1.00 in the least
/// favourable scenario; docs/models.md#nams-metrics).
const THESIS: [(&str, [(f64, f64); 3]); 2] = [
    ("scenario 1", [(14.8, 7.2), (32.4, 24.4), (1.00, 1.00)]),
    ("scenario 4", [(3.6, 2.9), (102.6, 57.8), (0.38, 1.00)]),
];

/// Adaptive duty cycle at or above which scenario 4's status period is measured to be out of the
/// thesis's reach: the thesis's adaptive vehicle skips 62 % of its slots (duty 0.38, Nams 2014,
/// §5.4.3), and those skipped slots are what lengthen its status period by 78 %; a vehicle that
/// skips fewer than two in five (duty ≥ 0.60) cannot lengthen it that much (docs/models.md#nams-bands).
const S4_DUTY_CAUSE: f64 = 0.60;

/// The measured cause of scenario 4's status-period direction failing: our adaptive duty, when it
/// is at least [`S4_DUTY_CAUSE`].
fn s4_period_cause(adaptive_duty: f64) -> Option<String> {
    (adaptive_duty >= S4_DUTY_CAUSE).then(|| {
        format!(
            "our adaptive vehicle transmits in {:.0} % of its slots (duty {adaptive_duty:.2} ≥ {S4_DUTY_CAUSE}) against \
             the thesis's 38 %: it skips {:.0} % of them where the thesis's skips 62 %, and the skipped slots are what \
             lengthen the thesis's status period",
            adaptive_duty * 100.0,
            (1.0 - adaptive_duty) * 100.0
        )
    })
}

/// Tables 9–11's band (docs/models.md#nams-bands): each effect size, adaptive over best control.
const BAND_NAMS: Band = Band::Relative { percent: 25.0 };

fn tables_9_11(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    let tl = default_tl();
    let label = format!("analytic spreading + Thorp absorption, k = {}", tl.k);
    report(opts, ID, &ExperimentTl::Shared(Arc::new(tl)), &label, opts.progress)
}

/// The same cells with the transmission loss of a BELLHOP grid over each square (the engine's
/// `bellhop_grid` at its defaults, over the shelf and the template's sound-speed profile).
fn tables_9_11_bellhop_grid(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    let g = GridModel::default();
    let label = format!(
        "BELLHOP grid over each square ({} bearings, anchors every {} m, source layers every {} m)",
        g.bearings, g.anchor_spacing_m, g.source_depth_step_m
    );
    report(opts, GRID_ID, &ExperimentTl::PerCell(TlModel::BellhopGrid(g)), &label, opts.progress)
}

fn best_control<'a>(r: &'a ExperimentResult, scenario: &str) -> Option<&'a Cell> {
    r.cells
        .iter()
        .filter(|c| c.scenario == scenario && c.control)
        .max_by(|a, b| a.mean.bandwidth.total_cmp(&b.mean.bandwidth))
}

/// Runs the experiment on `tl` and formats the report.
pub fn report(
    opts: &ReproOptions,
    id: &str,
    tl: &ExperimentTl,
    tl_label: &str,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ReproReport, ExperimentError> {
    let cfg = config(opts);
    let fail = |message: String| ExperimentError::Failed { id: id.into(), message };
    let result = run_experiment(&cfg, tl, progress).map_err(|e| fail(e.to_string()))?;
    let adaptive = Behaviour::Adaptive(Default::default()).label();
    let mut t = String::new();
    let _ = writeln!(t, "Nams Tables 9–11 — TL: {tl_label}; synthetic shelf 20→60 m; {} runs per cell", cfg.runs);
    let _ = writeln!(t, "\nAll behaviours (mean ± sd over runs; bandwidth = received payload bytes, both directions, per second;\n net = less frame-0 header and status bytes; header B = tracking header per packet; queue = header entries per packet;\n est. err = mean (max) horizontal error of the shadow estimate of the collaborator):");
    let _ = writeln!(
        t,
        "{:<11} {:<16} {:>5} {:>13} {:>7} {:>15} {:>6} {:>6} {:>9} {:>7} {:>13}",
        "scenario",
        "behaviour",
        "slot",
        "BW B/s",
        "net",
        "status period s",
        "duty",
        "score",
        "header B",
        "queue",
        "est. err m"
    );
    for c in &result.cells {
        let m = &c.mean;
        let _ = writeln!(
            t,
            "{:<11} {:<16} {:>4.0}s {:>7.2} ±{:<4.2} {:>7.2} {:>8.1} ±{:<5.1} {:>6.2} {:>6.3} {:>9.2} {:>7.2} {:>6.2} ({:>5.1})",
            c.scenario, c.behaviour, c.slot_len, m.bandwidth, c.sd.bandwidth, m.bandwidth_net, m.status_period, c.sd.status_period, m.duty_cycle, m.score,
            m.header_bytes_mean, m.queue_len_mean, m.estimate_error_mean, m.estimate_error_max
        );
    }
    let _ =
        writeln!(t, "\nTables 9–11: adaptive vs best control (the control with the highest bandwidth), ours | thesis:");
    let _ = writeln!(
        t,
        "{:<11} {:<24} {:>9} {:>9} {:>18} | {:>9} {:>9}",
        "scenario", "metric", "adaptive", "control", "(which)", "adaptive", "control"
    );
    let mut checks = Vec::new();
    let mut numbers = Vec::new();
    let mut data = Vec::new();
    for (scenario, thesis) in THESIS {
        if !cfg.scenarios.iter().any(|s| s.name == scenario) {
            continue;
        }
        let (Some(a), Some(c)) = (result.cell(scenario, &adaptive), best_control(&result, scenario)) else {
            return Err(fail(format!("{scenario}: missing adaptive or control results")));
        };
        let ours = [
            (a.mean.bandwidth, c.mean.bandwidth),
            (a.mean.status_period, c.mean.status_period),
            (a.mean.duty_cycle, c.mean.duty_cycle),
        ];
        for (k, name) in ["Table 9 bandwidth B/s", "Table 10 status period s", "Table 11 duty cycle"].iter().enumerate()
        {
            let _ = writeln!(
                t,
                "{:<11} {:<24} {:>9.2} {:>9.2} {:>18} | {:>9.2} {:>9.2}",
                scenario, name, ours[k].0, ours[k].1, c.behaviour, thesis[k].0, thesis[k].1
            );
            let (sa, sc) = match k {
                0 => (a.sd.bandwidth, c.sd.bandwidth),
                1 => (a.sd.status_period, c.sd.status_period),
                _ => (a.sd.duty_cycle, c.sd.duty_cycle),
            };
            let se = (sa.powi(2) + sc.powi(2)).sqrt() / (cfg.runs as f64).sqrt();
            if k > 0 {
                let check = direction_check(scenario, name, ours[k], thesis[k], se);
                let cause = (k == 1 && scenario == "scenario 4").then(|| s4_period_cause(a.mean.duty_cycle)).flatten();
                checks.push(check.caused_by(cause));
            }
            numbers.push(ThesisNumber::new(
                format!("{scenario} {name}: adaptive / control"),
                thesis[k].0 / thesis[k].1,
                Some(ours[k].0 / ours[k].1),
                BAND_NAMS,
            ));
        }
        let margin = 2.0 * (a.sd.bandwidth.powi(2) + c.sd.bandwidth.powi(2)).sqrt() / (cfg.runs as f64).sqrt();
        checks.push(Check::new(
            format!("{scenario}: adaptive beats the best control on bandwidth"),
            a.mean.bandwidth > c.mean.bandwidth,
            format!(
                "adaptive {:.2} B/s vs {} {:.2} B/s (2 s.e. of the difference {:.2}); thesis {:.1} vs {:.1}",
                a.mean.bandwidth, c.behaviour, c.mean.bandwidth, margin, thesis[0].0, thesis[0].1
            ),
        ));
        data.push(serde_json::json!({"scenario": scenario, "adaptive": a, "best_control": c, "thesis": {"bandwidth": thesis[0], "status_period": thesis[1], "duty_cycle": thesis[2]}}));
    }
    let _ = writeln!(t, "\nAbsolute values differ from the thesis by construction (no Bedford Basin bathymetry: the synthetic shelf, and the TL above); the thesis's own channel gave rate 1 only ≈ 38 % success in scenario 1.");
    let table = ThesisTable::new(
        id,
        "±25 % on each effect size, adaptive over the best control (docs/models.md#nams-bands): our channel is the \
         synthetic shelf, not Bedford Basin, so absolute values are not compared",
        numbers,
    );
    Ok(ReproReport::new(id.into(), t, checks, serde_json::json!({"cells": result.cells, "tables": data}))
        .with_tables(vec![table]))
}

/// Tables 10–11 (status period, duty cycle): adaptive vs best control lie the thesis's way round.
/// Where the thesis's two differ, the difference (oriented the thesis's way) with its 95 % CI
/// (±1.96 `se`, the standard error of the difference over the runs) decides: above zero
/// passes, below fails, spanning zero is undecided. Where the thesis's two are equal, ours must
/// be equal within 0.05.
fn direction_check(scenario: &str, metric: &str, ours: (f64, f64), thesis: (f64, f64), se: f64) -> Check {
    let verdict = if thesis.0 == thesis.1 {
        if (ours.0 - ours.1).abs() < 0.05 {
            Verdict::Pass
        } else {
            Verdict::Fail
        }
    } else {
        let d = (ours.0 - ours.1) * (thesis.0 - thesis.1).signum();
        ordering_verdict(d - 1.96 * se, d + 1.96 * se)
    };
    let relation = |a: f64, b: f64| {
        if a > b {
            ">"
        } else if a < b {
            "<"
        } else {
            "="
        }
    };
    Check::with_verdict(
        format!("{scenario}: {metric}, adaptive vs best control the thesis's way round"),
        verdict,
        format!(
            "ours {:.2} {} {:.2} (SE of the difference {se:.2}); thesis {:.2} {} {:.2}",
            ours.0,
            relation(ours.0, ours.1),
            ours.1,
            thesis.0,
            relation(thesis.0, thesis.1),
            thesis.1
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::nams::run_experiment;
    use crate::scenario::nams::ExperimentConfig;

    #[test]
    fn reduced_reproduction_keeps_the_ordering() {
        let r = tables_9_11(&ReproOptions::new(Size::Reduced, 1)).unwrap();
        for c in &r.checks {
            assert!(c.acceptable(), "{}: {}", c.name, c.detail);
        }
        // The bandwidth ordering is resolved even in the reduced form.
        for c in r.checks.iter().filter(|c| c.name.contains("bandwidth")) {
            assert!(c.passed(), "{}: {}", c.name, c.detail);
        }
        // Per scenario: bandwidth, and the status-period and duty-cycle directions.
        assert_eq!(r.checks.len(), 6);
    }

    #[test]
    fn a_direction_against_the_thesis_fails() {
        let v = |ours, thesis, se| direction_check("s", "m", ours, thesis, se).verdict;
        assert_eq!(v((40.0, 30.0), (32.4, 24.4), 1.0), Verdict::Pass);
        assert_eq!(v((20.0, 30.0), (32.4, 24.4), 1.0), Verdict::Fail);
        // Within noise of each other: undecided either way round.
        assert_eq!(v((31.0, 30.0), (32.4, 24.4), 1.0), Verdict::Undecided);
        assert_eq!(v((29.0, 30.0), (32.4, 24.4), 1.0), Verdict::Undecided);
        assert_eq!(v((0.60, 1.0), (0.38, 1.0), 0.01), Verdict::Pass);
        assert_eq!(v((1.0, 0.97), (1.0, 1.0), 0.0), Verdict::Pass);
        assert_eq!(v((0.6, 1.0), (1.0, 1.0), 0.0), Verdict::Fail);
    }

    #[test]
    fn the_thesis_effect_sizes_sit_in_their_band_and_moved_ones_do_not() {
        for (_, rows) in THESIS {
            for (a, c) in rows {
                let effect = a / c;
                assert!(BAND_NAMS.contains(effect, effect));
                assert!(BAND_NAMS.contains(effect, effect * 1.24) && !BAND_NAMS.contains(effect, effect * 1.26));
                assert!(!BAND_NAMS.contains(effect, effect * 0.74));
            }
        }
        // Scenario 4's status period against the thesis: ours +3 % (1.03) is out of +78 % (1.775).
        assert!(!BAND_NAMS.contains(102.6 / 57.8, 1.03));
    }

    #[test]
    fn the_duty_cycle_is_a_cause_only_at_or_above_its_threshold() {
        assert!(s4_period_cause(0.70).is_some());
        assert!(s4_period_cause(S4_DUTY_CAUSE).is_some());
        assert!(s4_period_cause(0.38).is_none() && s4_period_cause(0.59).is_none());
    }

    #[test]
    fn identical_on_one_and_two_threads() {
        let cfg = ExperimentConfig {
            scenarios: vec![table_6()[1].clone()],
            runs: 3,
            max_time: Some(1800.0),
            ..ExperimentConfig::default()
        };
        let tl = ExperimentTl::Shared(Arc::new(default_tl()));
        let go = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| serde_json::to_string(&run_experiment(&cfg, &tl, &|_| {}).unwrap()).unwrap())
        };
        assert_eq!(go(1), go(2));
    }

    /// The cells on a coarse BELLHOP grid of their own layout (scenario 1, four bearings, anchors
    /// every 1000 m: about 150 BELLHOP runs, then cached): the grid's channel is not the
    /// analytic model's, so the bandwidths differ, and every cell still delivers.
    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn cells_run_on_a_bellhop_grid_of_their_own_layout() {
        let cfg = ExperimentConfig { scenarios: vec![table_6()[0].clone()], runs: 2, ..ExperimentConfig::default() };
        let grid = GridModel { bearings: 4, anchor_spacing_m: 1000.0, ..GridModel::default() };
        let on_grid = run_experiment(&cfg, &ExperimentTl::PerCell(TlModel::BellhopGrid(grid)), &|_| {}).unwrap();
        let analytic = run_experiment(&cfg, &ExperimentTl::Shared(Arc::new(default_tl())), &|_| {}).unwrap();
        for (g, a) in on_grid.cells.iter().zip(&analytic.cells) {
            eprintln!("{}: grid {:.2} B/s, analytic {:.2} B/s", g.behaviour, g.mean.bandwidth, a.mean.bandwidth);
            assert!(g.mean.bandwidth > 0.0 && g.mean.bandwidth != a.mean.bandwidth, "{}", g.behaviour);
        }
    }

    #[test]
    fn bad_configuration_is_rejected_before_running() {
        let tl = ExperimentTl::Shared(Arc::new(default_tl()));
        let bad = ExperimentConfig { runs: 0, ..ExperimentConfig::default() };
        let e = run_experiment(&bad, &tl, &|_| {}).unwrap_err().to_string();
        assert!(e.contains("experiment.runs = 0"), "{e}");
        let mut s = table_6()[0].clone();
        s.noise_db = -3.0;
        let bad = ExperimentConfig { scenarios: vec![s], ..ExperimentConfig::default() };
        assert!(run_experiment(&bad, &tl, &|_| {}).unwrap_err().to_string().contains("noise_db"));
    }
}
