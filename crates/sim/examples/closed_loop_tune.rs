//! Tuning runs of `closed-loop-vs-baselines` on base seed `TUNING_SEED` only (the evaluation refuses it):
//! one cell, chosen policies, optional scenario overrides, the comparison table printed.
//! `cargo run --release -p coopnav-sim --example closed_loop_tune -- RUNS current|sloping-auv-cna N
//! POLICY,POLICY,... [DURATION_S|-] [section.key=TOML_VALUE ...]`
//! e.g. `... -- 6 current 3 planner-estimator,centroid,trail - planner.look_ahead=6`.

use coopnav_sim::batch::mc::paired_per_auv;
use coopnav_sim::batch::mc::{comparison_table, monte_carlo, PolicySummary};
use coopnav_sim::experiments::closed_loop::{setup, TUNING_SEED};
use coopnav_sim::experiments::{ReproOptions, Size};
use coopnav_sim::scenario::Scenario;
use std::time::Instant;

type Error = Box<dyn std::error::Error>;

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [runs, scenario, n, policies, rest @ ..] = args.as_slice() else {
        return Err("usage: closed_loop_tune RUNS SCENARIO N POLICIES [DURATION_S|-] [section.key=VALUE ...]".into());
    };
    let (runs, n): (usize, usize) = (runs.parse()?, n.parse()?);
    let duration = match rest.first().map(String::as_str) {
        None | Some("-") => None,
        Some(d) => Some(d.parse::<f64>()?),
    };
    let (settings, _) = setup(&ReproOptions::new(Size::Full, TUNING_SEED + 1))?;
    let setting =
        settings.iter().find(|s| s.name == scenario.as_str()).ok_or_else(|| format!("no scenario {scenario}"))?;
    let mut sc = setting.scenario(n, TUNING_SEED, duration)?;
    for assignment in rest.iter().skip(1) {
        sc = overridden(&sc, assignment)?;
    }
    let policies: Vec<String> = policies.split(',').map(str::to_string).collect();
    let start = Instant::now();
    let c = monte_carlo(&sc, &policies, runs, &|_| {})?;
    print!("{}", comparison_table(&c));
    // Filter consistency (2 = consistent; above: the filters' covariances understate the error).
    let nees: Vec<String> = c.policies.iter().map(|s| format!("{} {:.2}", s.policy, s.nees_mean)).collect();
    println!("mean NEES: {}", nees.join(", "));
    per_auv(&c.policies);
    println!("wall time {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// Per AUV: the first policy's mean error, it minus each other policy (paired by run), and per
/// policy the runs in which the CNA heard it: where in the fleet a difference lies.
fn per_auv(policies: &[PolicySummary]) {
    let Some((reference, baselines)) = policies.split_first() else { return };
    for (k, runs) in reference.auv_runs.iter().enumerate() {
        let mean = runs.iter().sum::<f64>() / runs.len() as f64;
        let minus: Vec<String> = baselines
            .iter()
            .map(|b| {
                let d = &paired_per_auv(reference, b)[k];
                format!("{} {:+.2}", b.policy, d.mean)
            })
            .collect();
        let heard: Vec<String> = policies
            .iter()
            .map(|p| {
                format!(
                    "{} ({} lost in air of {})",
                    p.auv_heard_runs[k], p.auv_status_lost_in_air[k], p.auv_status_sent[k]
                )
            })
            .collect();
        println!("AUV {k}: {mean:.2} m; minus {}; runs heard {}", minus.join(", "), heard.join(" "));
    }
}

/// `sc` with `section.key = value` (a TOML value) set.
fn overridden(sc: &Scenario, assignment: &str) -> Result<Scenario, Error> {
    let (path, value) = assignment.split_once('=').ok_or_else(|| format!("{assignment}: expected key=value"))?;
    let value: toml::Value = toml::from_str::<toml::Table>(&format!("v = {value}"))?["v"].clone();
    let mut doc = toml::Value::try_from(sc)?;
    let mut slot = &mut doc;
    for key in path.split('.') {
        let table = slot.as_table_mut().ok_or_else(|| format!("{path}: not a table"))?;
        slot = table.entry(key).or_insert(toml::Value::Table(Default::default()));
    }
    *slot = value;
    Ok(doc.try_into()?)
}
