//! `closed-loop-cna-navigation` (docs/evaluation.md, study 2): what the AUV CNA's own navigation
//! error costs in the AUV-CNA cells of `closed-loop-vs-baselines`. The
//! cells of `closed-loop-vs-baselines` whose CNA is an AUV, run twice on the same seeds: as
//! evaluated, and with the CNA broadcasting its true position (`cna.navigation = { kind =
//! "exact" }`, a counterfactual: its navigation error is still drawn, its σ grows and it surfaces as before,
//! but no range carries the error). Every survey AUV fixed by the CNA's ranges inherits the
//! CNA's own navigation error, whatever the CNA's path; the second run shows how much of every
//! policy's error, and of the planner's margins, that error is.

use super::closed_loop::{evaluate, policies, setup, Cell, Setting};
use super::{Experiment, ExperimentError, ReproOptions, ReproReport};
use crate::models::cna_navigation::CnaNavigation;
use std::fmt::Write as _;

const ID: &str = "closed-loop-cna-navigation";

/// Suffix of the counterfactual settings' names.
const EXACT: &str = "exact-cna";

pub fn experiments() -> Vec<Experiment> {
    vec![Experiment {
        id: ID,
        about: "Closed loop, AUV CNA: the cells of closed-loop-vs-baselines as evaluated and with the CNA broadcasting its true position (how much its own navigation error decides)",
        run: cna_navigation,
    }]
}

fn fail(message: String) -> ExperimentError {
    ExperimentError::Failed { id: ID.into(), message }
}

fn cna_navigation(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    let (settings, runs) = setup(opts)?;
    let as_evaluated: Vec<Setting> = settings.into_iter().filter(|s| s.base.cna.auv.is_some()).collect();
    if as_evaluated.is_empty() {
        return Err(fail("closed-loop-vs-baselines has no setting with an AUV CNA".into()));
    }
    let exact: Vec<Setting> = as_evaluated.iter().map(broadcasting_truth).collect();
    let both: Vec<Setting> = as_evaluated.into_iter().chain(exact).collect();
    let report = evaluate(&both, runs, None, opts.seed, &policies(), opts.progress)?;
    let cells: Vec<Cell> = serde_json::from_value(report.data["cells"].clone()).map_err(|e| fail(e.to_string()))?;
    let table = format!("{}\n{}", side_by_side(&both, &cells), report.table);
    Ok(ReproReport { id: ID.into(), table, ..report })
}

/// `s` with the CNA broadcasting its true position, named `<name>-exact-cna`.
fn broadcasting_truth(s: &Setting) -> Setting {
    let mut base = s.base.clone();
    if let CnaNavigation::DeadReckoning(walk) = base.cna.navigation {
        base.cna.navigation = CnaNavigation::Exact(walk);
    }
    Setting { name: format!("{}-{EXACT}", s.name), base, ..s.clone() }
}

/// Per scenario, N and baseline: the paired difference as evaluated beside the one with the
/// CNA's navigation exact, and the cells won either way.
fn side_by_side(settings: &[Setting], cells: &[Cell]) -> String {
    let mut out = String::from(
        "planner-estimator minus baseline (m, paired 95 % CI; * = won): as evaluated | the CNA broadcasting its true \
         position\n",
    );
    for s in settings.iter().filter(|s| !s.name.ends_with(EXACT)) {
        let exact = format!("{}-{EXACT}", s.name);
        for &n in &s.n {
            let won = |scenario: &str| cells_of(cells, scenario, n).filter(|c| c.won).count();
            let _ = writeln!(
                out,
                "{} N={n}: {} of {} won as evaluated, {} with the CNA exact",
                s.name,
                won(&s.name),
                cells_of(cells, &s.name, n).count(),
                won(&exact)
            );
            for c in cells_of(cells, &s.name, n) {
                let e = cells_of(cells, &exact, n).find(|e| e.baseline == c.baseline);
                let _ = writeln!(
                    out,
                    "  vs {:<18} {} | {}",
                    c.baseline,
                    interval(c),
                    e.map_or_else(|| "not run".into(), interval)
                );
            }
        }
    }
    out
}

fn cells_of<'a>(cells: &'a [Cell], scenario: &'a str, n: usize) -> impl Iterator<Item = &'a Cell> + 'a {
    cells.iter().filter(move |c| c.scenario == scenario && c.n == n)
}

fn interval(c: &Cell) -> String {
    format!("{:+.2} [{:+.2}, {:+.2}]{}", c.mean, c.low, c.high, if c.won { "*" } else { " " })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::Size;

    #[test]
    fn the_counterfactual_runs_every_auv_cna_cell_twice_and_the_exact_cna_navigates_the_fleet_better() {
        let r = cna_navigation(&ReproOptions::new(Size::Reduced, 1)).unwrap();
        assert_eq!(r.id, ID);
        let comparisons = r.data["comparisons"].as_array().unwrap();
        // The reduced form flies the sloping scenario at N = 2: as evaluated, then exact.
        assert_eq!(comparisons.len(), 2);
        let planner_error = |c: &serde_json::Value| c["policies"][0]["mean_error"]["mean"].as_f64().unwrap();
        let (evaluated, exact) = (planner_error(&comparisons[0]), planner_error(&comparisons[1]));
        assert!(exact < evaluated, "the CNA's navigation error must cost something: {exact} vs {evaluated}");
        assert!(r.table.contains("sloping-auv-cna N=2:") && r.table.contains("sloping-auv-cna-exact-cna"));
        assert!(r.table.matches("  vs ").count() >= policies().len() - 1);
    }

    #[test]
    fn only_the_broadcast_changes_in_the_counterfactual() {
        let (settings, _) = setup(&ReproOptions::new(Size::Full, 1)).unwrap();
        let sloping = settings.iter().find(|s| s.base.cna.auv.is_some()).unwrap();
        let exact = broadcasting_truth(sloping);
        let (a, b) = (sloping.scenario(3, 1, None).unwrap(), exact.scenario(3, 1, None).unwrap());
        let CnaNavigation::DeadReckoning(walk) = a.cna.navigation else { panic!("{:?}", a.cna.navigation) };
        assert_eq!(b.cna.navigation, CnaNavigation::Exact(walk));
        let mut b = b;
        b.cna.navigation = CnaNavigation::DeadReckoning(walk);
        assert_eq!(a, b);
    }
}
