//! `closed-loop-vs-baselines`: the underway planner (A = 5, L = 5) against every baseline CNA
//! policy in the closed loop, for N = 1, 2, 3, 5 survey AUVs, judged on the AUVs' TRUE mean
//! navigation error (paired by run: common random numbers). The Hudson thesis never measured
//! this (it reported only its own modelled error), so there is no thesis number to print; where
//! the planner does not beat a baseline the output says so and shows the measured reasons
//! (modelled vs true error, packet success, CNA–AUV distance).

use super::{Check, Experiment, ExperimentError, ReproOptions, ReproReport, Size};
use crate::closed_loop::mc::{Comparison, PolicySummary};
use crate::closed_loop::{comparison_table, monte_carlo, Scenario, POLICY_NAMES};
use std::fmt::Write as _;

const ID: &str = "closed-loop-vs-baselines";

pub fn experiments() -> Vec<Experiment> {
    vec![Experiment {
        id: ID,
        about: "Closed loop: underway planner (A=5, L=5) vs every baseline CNA policy, true survey-AUV navigation error, N = 1, 2, 3, 5",
        run: closed_loop_vs_baselines,
    }]
}

/// The scenario for N survey AUVs.
pub type ScenarioFor = Box<dyn Fn(usize) -> Scenario>;

/// The set-up at a given size: (N values, runs per policy, scenario for N).
pub fn setup(opts: &ReproOptions) -> (Vec<usize>, usize, ScenarioFor) {
    let seed = opts.seed;
    let base = move |n: usize, duration: Option<f64>| {
        let mut sc = Scenario::example().with_auvs(n);
        sc.seed = seed;
        sc.planner.heading_options = 5;
        sc.planner.look_ahead = 5;
        if let Some(d) = duration {
            sc.duration_s = d;
        }
        sc
    };
    match opts.size {
        Size::Full => (vec![1, 2, 3, 5], 50, Box::new(move |n| base(n, None))),
        Size::Reduced => (vec![1, 3], 4, Box::new(move |n| base(n, Some(900.0)))),
    }
}

fn closed_loop_vs_baselines(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    run_with_progress(opts, &|_| {})
}

/// Runs the experiment; `progress(done)` counts finished runs within the current N.
pub fn run_with_progress(opts: &ReproOptions, progress: &(dyn Fn(u64) + Sync)) -> Result<ReproReport, ExperimentError> {
    let fail = |message: String| ExperimentError::Failed { id: ID.into(), message };
    let (ns, runs, scenario) = setup(opts);
    let policies: Vec<String> = POLICY_NAMES.iter().map(|s| s.to_string()).collect();
    let mut table = format!(
        "True mean navigation error of the survey AUVs (m), {runs} runs per policy and N, planner A=5 L=5, tau = 30 s.\n\
         The thesis reports no true-error figures (only its modelled error), so there is no thesis column.\n\n"
    );
    let mut checks = Vec::new();
    let mut data = Vec::new();
    for &n in &ns {
        let sc = scenario(n);
        let c = monte_carlo(&sc, &policies, runs, progress).map_err(|e| fail(e.to_string()))?;
        table += &comparison_table(&c);
        let planner = find(&c, "planner").ok_or_else(|| fail("planner missing from the comparison".into()))?;
        for p in &c.paired {
            if !p.planner_better {
                if let Some(b) = find(&c, &p.baseline) {
                    let _ =
                        writeln!(table, "  where/why vs {}: {}", p.baseline, why(planner, b, p.difference.low <= 0.0));
                }
            }
            checks.push(Check::new(
                format!("N={n}: planner beats {} on mean true error", p.baseline),
                p.planner_better,
                format!(
                    "planner - {} = {:.2} m [{:.2}, {:.2}]",
                    p.baseline, p.difference.mean, p.difference.low, p.difference.high
                ),
            ));
        }
        checks.push(Check::new(
            format!("N={n}: every filter healthy"),
            c.policies.iter().all(|s| s.healthy),
            "no NaN, finite covariances",
        ));
        checks.push(Check::new(
            format!("N={n}: planner deadline misses"),
            planner.deadline_misses == 0,
            format!("{} misses", planner.deadline_misses),
        ));
        table.push('\n');
        data.push(serde_json::to_value(&c).map_err(|e| fail(e.to_string()))?);
    }
    Ok(ReproReport { id: ID.into(), table, checks, data: serde_json::Value::Array(data) })
}

fn find<'a>(c: &'a Comparison, name: &str) -> Option<&'a PolicySummary> {
    c.policies.iter().find(|s| s.policy == name)
}

/// The measured differences that explain a loss, only those that apply: the planner optimises
/// its modelled error (eq. 1) under distance-limit penalties, so a gap between modelled and true
/// error, a limit trade-off or a link difference shows why.
fn why(planner: &PolicySummary, b: &PolicySummary, tie: bool) -> String {
    let mut reasons = Vec::new();
    if tie {
        reasons.push("the paired 95 % CI includes zero: no significant difference either way".to_string());
    }
    if let (Some(pm), Some(bm)) = (planner.modelled_mean, b.modelled_mean) {
        if pm < bm {
            reasons.push(format!(
                "the planner wins on its own eq. 1 model ({pm:.2} vs {bm:.2} m) but not on the truth: the model ignores \
                 range noise growing with distance, compass bias and the EKF's linearisation, so it mis-ranks CNA paths"
            ));
        } else {
            reasons.push(format!("even the modelled error is not lower ({pm:.2} vs {bm:.2} m)"));
        }
    }
    if b.limit_violation > planner.limit_violation + 0.02 {
        reasons.push(format!(
            "the planner keeps the CNA within the distance limits ({:.0}% of the time outside vs {:.0}% for {}); \
             its limit penalties cost it geometry the baseline uses freely",
            100.0 * planner.limit_violation,
            100.0 * b.limit_violation,
            b.policy
        ));
    }
    if b.downlink_success > planner.downlink_success + 0.01 {
        reasons.push(format!(
            "{} delivers more ranges ({:.0}% vs {:.0}%): eq. 1 assumes every ping arrives (try planner.model_lost_pings)",
            b.policy,
            100.0 * b.downlink_success,
            100.0 * planner.downlink_success
        ));
    }
    if reasons.is_empty() {
        reasons.push(
            "no single measured factor stands out; the difference is within run-to-run variation of the geometry"
                .into(),
        );
    }
    format!(
        "planner {:.2} m vs {} {:.2} m true mean error; {}.",
        planner.mean_error.mean,
        b.policy,
        b.mean_error.mean,
        reasons.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_form_runs_and_the_planner_beats_dead_reckoning() {
        let r = closed_loop_vs_baselines(&ReproOptions { size: Size::Reduced, seed: 1 }).unwrap();
        for n in [1, 3] {
            let by_name =
                |name: String| r.checks.iter().find(|c| c.name == name).unwrap_or_else(|| panic!("no check {name}"));
            let dr = by_name(format!("N={n}: planner beats none on mean true error"));
            assert!(dr.passed, "{}", dr.detail);
            assert!(by_name(format!("N={n}: every filter healthy")).passed);
        }
        // One check per baseline and N, plus health and deadline per N.
        assert_eq!(r.checks.len(), 2 * (POLICY_NAMES.len() - 1 + 2));
        assert!(r.table.contains("centroid") && r.table.contains("open-loop"));
        // Every loss is explained in the output.
        let losses = r.checks.iter().filter(|c| c.name.contains("planner beats") && !c.passed).count();
        assert_eq!(r.table.matches("where/why").count(), losses);
    }
}
