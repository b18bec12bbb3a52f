//! `closed-loop-generalization`: `planner-estimator` against Hudson's planner and every baseline
//! on missions nobody tuned for: the seeded generator's missions of `scenarios/generators/generalization.toml`
//! (N 1–8; adjacent, spread, diagonal and separated blocks; any lane heading; currents to
//! 0.15 m/s; ASC and AUV CNA; mild and harsh channels; 5- and 7-state filters; 1–3 h), each flown
//! exactly as `coopnav simulate` flies its written file, paired by run (common random numbers) and
//! judged on the AUVs' TRUE mean error.
//!
//! Per mission and baseline the paired 95 % CI of (planner-estimator − baseline) is below zero
//! (won), straddles it (tied) or lies above it (lost). Per baseline, the pooled difference is the
//! mean over missions of each mission's mean difference, its CI the t interval over missions (the
//! missions are the generator's draws). The checks: every pooled CI below zero, and at most
//! [`MAX_LOST_SHARE`] of the missions lost against any one baseline. Every lost mission is printed
//! with what its runs measured ([`missions::measured`]).
//!
//! Seeds: the file's mission seeds (and their runs') are refused when they meet any seed a setting
//! was chosen on ([`missions::CHOSEN_ON`]).

use super::closed_loop::policies;
use super::missions::{self, Study, StudySize};
use super::study_dir::{digest, Stamp, StudyDir};
use super::{Check, Experiment, ExperimentError, ReproOptions, ReproReport};
use crate::batch::mc::{compare, monte_carlo_grid, monte_carlo_runs, Ci, Comparison};
use crate::observe::metrics::RunResult;
use crate::output::plot::{intervals_svg, Interval};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// The experiment's id; `coopnav reproduce` writes it to its output directory as it goes ([`run_in`]).
pub const ID: &str = "closed-loop-generalization";
/// The generator file the study flies, and its text (embedded).
pub const FILE: &str = "scenarios/generators/generalization.toml";
pub const RANGES: &str = include_str!("../../../../scenarios/generators/generalization.toml");

/// The study's size: every mission of the file, 10 paired runs each.
pub const FULL: StudySize = StudySize { missions: None, runs: 10 };
/// The reduced form: the file's first 3 missions, 3 runs each.
pub const REDUCED: StudySize = StudySize { missions: Some(3), runs: 3 };

/// The largest share of missions `planner-estimator` may lose against any one baseline.
pub const MAX_LOST_SHARE: f64 = 0.02;

pub fn experiments() -> Vec<Experiment> {
    vec![Experiment {
        id: ID,
        about: "Closed loop on generated missions nobody tuned for: planner-estimator vs Hudson's planner and every baseline, won/tied/lost per mission",
        run: generalization,
    }]
}

fn fail(message: String) -> ExperimentError {
    ExperimentError::Failed { id: ID.into(), message }
}

/// A mission's paired 95 % CI against one baseline: below zero, across it, above it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Won,
    Tied,
    Lost,
}

impl Verdict {
    pub fn of(d: &Ci) -> Verdict {
        if d.high < 0.0 {
            Verdict::Won
        } else if d.low > 0.0 {
            Verdict::Lost
        } else {
            Verdict::Tied
        }
    }
}

/// planner-estimator minus one baseline on one mission.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    pub mission: usize,
    pub baseline: String,
    pub difference: Ci,
    pub verdict: Verdict,
}

/// One baseline over every mission.
#[derive(Debug, Clone, Serialize)]
pub struct Tally {
    pub baseline: String,
    pub won: usize,
    pub tied: usize,
    pub lost: usize,
    /// Mean over missions of the per-mission mean difference, t CI over missions.
    pub pooled: Ci,
}

/// Per baseline (in first-seen order), its counts and pooled difference.
pub fn tallies(outcomes: &[Outcome]) -> Vec<Tally> {
    let mut names: Vec<&str> = Vec::new();
    for o in outcomes {
        if !names.contains(&o.baseline.as_str()) {
            names.push(&o.baseline);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let own: Vec<&Outcome> = outcomes.iter().filter(|o| o.baseline == name).collect();
            let count = |v: Verdict| own.iter().filter(|o| o.verdict == v).count();
            let means: Vec<f64> = own.iter().map(|o| o.difference.mean).collect();
            Tally {
                baseline: name.to_string(),
                won: count(Verdict::Won),
                tied: count(Verdict::Tied),
                lost: count(Verdict::Lost),
                pooled: Ci::of(&means),
            }
        })
        .collect()
}

/// The checks on the outcomes: per baseline, the pooled CI below zero and at most
/// [`MAX_LOST_SHARE`] of its missions lost.
pub fn verdict(outcomes: &[Outcome]) -> Vec<Check> {
    let mut checks = Vec::new();
    for t in tallies(outcomes) {
        let missions = t.won + t.tied + t.lost;
        let p = &t.pooled;
        checks.push(Check::new(
            format!("pooled difference vs {} below zero", t.baseline),
            p.high < 0.0,
            format!("{:.2} m [{:.2}, {:.2}] over {missions} missions", p.mean, p.low, p.high),
        ));
        let allowed = (MAX_LOST_SHARE * missions as f64).floor() as usize;
        checks.push(Check::new(
            format!("at most {:.0} % of missions lost vs {}", 100.0 * MAX_LOST_SHARE, t.baseline),
            t.lost <= allowed,
            format!("{} lost, {} tied, {} won of {missions} (at most {allowed} may be lost)", t.lost, t.tied, t.won),
        ));
    }
    checks
}

fn generalization(opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    run_with_progress(opts, opts.progress)
}

/// Runs the study; `progress(done)` counts the finished runs.
pub fn run_with_progress(opts: &ReproOptions, progress: &(dyn Fn(u64) + Sync)) -> Result<ReproReport, ExperimentError> {
    let study = missions::study(ID, FILE, RANGES, opts, FULL, REDUCED)?;
    evaluate(&study, progress)
}

/// Every mission of `study`, every policy (planner-estimator first), its runs.
pub fn evaluate(study: &Study, progress: &(dyn Fn(u64) + Sync)) -> Result<ReproReport, ExperimentError> {
    let names = policies();
    let scenarios: Vec<_> = study.missions.iter().map(|m| m.scenario.clone()).collect();
    let comparisons = monte_carlo_grid(&scenarios, &names, study.runs, progress).map_err(|e| fail(e.to_string()))?;
    report(study, &comparisons)
}

/// How far a study written to a directory ([`run_in`]) has got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Status {
    /// Missions whose runs are in the directory, of `missions_total`.
    pub missions_done: usize,
    pub missions_total: usize,
    /// Of `missions_done`, those an earlier process wrote (read back, not flown).
    pub missions_resumed: usize,
    /// Runs this process has finished, of the `runs_total` it has to fly.
    pub runs_done: u64,
    pub runs_total: u64,
}

/// The study for `opts`, each mission's runs written to `dir/missions/` as soon as the mission
/// finishes and missions already there (from an earlier, interrupted run of the same study) read
/// back instead of flown ([`StudyDir`]); the report is computed from the files, so it is the same
/// whether the study ran straight through or was resumed. `tell` hears after every run and every
/// mission. The missions are flown one after another, each mission's runs in parallel: each
/// mission's comparison is bit-identical to its own [`monte_carlo`].
pub fn run_in(opts: &ReproOptions, dir: &Path, tell: &(dyn Fn(Status) + Sync)) -> Result<ReproReport, ExperimentError> {
    let study = missions::study(ID, FILE, RANGES, opts, FULL, REDUCED)?;
    let names = policies();
    let ranges = &study.ranges;
    let stamp = Stamp {
        experiment: ID.into(),
        generator: FILE.into(),
        generator_digest: digest(RANGES.as_bytes()),
        seed: ranges.seed,
        missions: ranges.missions,
        runs: study.runs,
        policies: names.clone(),
        version: env!("CARGO_PKG_VERSION").into(),
    };
    let store = StudyDir::open(dir, stamp).map_err(|e| fail(e.to_string()))?;
    let digests = study
        .missions
        .iter()
        .map(|m| toml::to_string(&m.scenario).map(|t| digest(t.as_bytes())).map_err(|e| fail(e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let mut results: Vec<Option<Vec<RunResult>>> = Vec::with_capacity(study.missions.len());
    for (m, d) in study.missions.iter().zip(&digests) {
        results.push(store.load(m.facts.index, m.facts.seed, d).map_err(|e| fail(e.to_string()))?);
    }
    let resumed = results.iter().filter(|r| r.is_some()).count();
    let per_mission = (names.len() * study.runs) as u64;
    let runs_total = (study.missions.len() - resumed) as u64 * per_mission;
    let status = std::sync::Mutex::new(Status {
        missions_done: resumed,
        missions_total: study.missions.len(),
        missions_resumed: resumed,
        runs_done: 0,
        runs_total,
    });
    let report_status = |f: &dyn Fn(&mut Status)| {
        let mut s = status.lock().unwrap_or_else(|p| p.into_inner());
        f(&mut s);
        tell(*s);
    };
    report_status(&|_| {});
    for (i, m) in study.missions.iter().enumerate() {
        if results[i].is_some() {
            continue;
        }
        let runs = monte_carlo_runs(&m.scenario, &names, study.runs, &|_| report_status(&|s| s.runs_done += 1))
            .map_err(|e| fail(e.to_string()))?;
        store.store(m.facts.index, m.facts.seed, &digests[i], &runs).map_err(|e| fail(e.to_string()))?;
        report_status(&|s| s.missions_done += 1);
    }
    // Every mission read back from its file, the fresh ones too: the report sees the same bytes
    // however the study got there.
    let mut comparisons = Vec::with_capacity(study.missions.len());
    for (m, d) in study.missions.iter().zip(&digests) {
        let runs = store
            .load(m.facts.index, m.facts.seed, d)
            .map_err(|e| fail(e.to_string()))?
            .ok_or_else(|| fail(format!("{} vanished", store.mission_path(m.facts.index).display())))?;
        comparisons.push(compare(&m.scenario, &names, study.runs, &runs));
    }
    report(&study, &comparisons)
}

/// The report on `study` from each mission's comparison (in the order of `study.missions`).
fn report(study: &Study, comparisons: &[Comparison]) -> Result<ReproReport, ExperimentError> {
    let mut outcomes = Vec::new();
    for (m, c) in study.missions.iter().zip(comparisons) {
        for p in &c.paired {
            outcomes.push(Outcome {
                mission: m.facts.index,
                baseline: p.baseline.clone(),
                difference: p.difference,
                verdict: Verdict::of(&p.difference),
            });
        }
    }
    let r = &study.ranges;
    let mut table = format!(
        "planner-estimator minus each baseline, true mean navigation error of the survey AUVs (m), paired by run: \
         {} generated missions ({FILE}, mission seeds {}..{}), {} runs per policy and mission; each mission flown as \
         `coopnav simulate` flies its file (`coopnav generate {FILE}` writes them). A mission is won when its paired \
         95 % CI lies below zero, lost when above; the pooled difference is the mean over missions, CI over missions.\n\n",
        study.missions.len(),
        r.seed,
        r.seed + study.missions.len() as u64,
        study.runs
    );
    let tallies = tallies(&outcomes);
    let _ =
        writeln!(table, "{:<18} {:>4} {:>4} {:>4}   pooled difference [95 % CI]", "baseline", "won", "tied", "lost");
    for t in &tallies {
        let p = &t.pooled;
        let _ = writeln!(
            table,
            "{:<18} {:>4} {:>4} {:>4}   {:+8.2} [{:+8.2}, {:+8.2}]",
            t.baseline, t.won, t.tied, t.lost, p.mean, p.low, p.high
        );
    }
    table += "\nEvery mission lost, with what its runs measured (planner-estimator | the baseline):\n";
    let lost: Vec<&Outcome> = outcomes.iter().filter(|o| o.verdict == Verdict::Lost).collect();
    if lost.is_empty() {
        table += "  none\n";
    }
    for o in &lost {
        let (m, c) = mission(study, comparisons, o.mission)?;
        let b = index_of(c, &o.baseline)?;
        let d = &o.difference;
        let _ = writeln!(
            table,
            "  mission {} (seed {}) vs {}: {:+.2} m [{:+.2}, {:+.2}]\n    {}\n    {}",
            o.mission,
            m.facts.seed,
            o.baseline,
            d.mean,
            d.low,
            d.high,
            m.facts.line(),
            missions::measured(c, 0, b)
        );
    }
    table += "\nThe five largest differences (whatever their verdict):\n";
    let mut worst: Vec<&Outcome> = outcomes.iter().collect();
    worst.sort_by(|a, b| b.difference.mean.total_cmp(&a.difference.mean));
    for o in worst.iter().take(5) {
        let (m, _) = mission(study, comparisons, o.mission)?;
        let d = &o.difference;
        let _ = writeln!(
            table,
            "  mission {} vs {}: {:+.2} m [{:+.2}, {:+.2}] ({:?}); {}",
            o.mission,
            o.baseline,
            d.mean,
            d.low,
            d.high,
            o.verdict,
            m.facts.line()
        );
    }
    let mut checks = verdict(&outcomes);
    let unhealthy: Vec<usize> = study
        .missions
        .iter()
        .zip(comparisons)
        .filter(|(_, c)| c.policies.iter().any(|s| !s.healthy))
        .map(|(m, _)| m.facts.index)
        .collect();
    checks.push(Check::new(
        "every filter stays finite",
        unhealthy.is_empty(),
        format!("missions with a non-finite filter: {unhealthy:?}"),
    ));
    let mut plots = Vec::new();
    for t in &tallies {
        let rows: Vec<Interval> = outcomes
            .iter()
            .filter(|o| o.baseline == t.baseline)
            .map(|o| {
                let f = &study.missions.iter().find(|m| m.facts.index == o.mission).expect("own mission").facts;
                Interval {
                    label: format!("{} N={} {} {} {}", o.mission, f.n_auvs, f.layout.name(), f.cna, f.filter),
                    mean: o.difference.mean,
                    low: o.difference.low,
                    high: o.difference.high,
                    good: o.verdict == Verdict::Won,
                }
            })
            .collect();
        let title = format!("planner-estimator minus {}, per mission, true mean error (m), paired 95 % CI", t.baseline);
        let svg = intervals_svg(&title, "difference, m (negative = planner-estimator better)", &rows)
            .map_err(|e| fail(e.to_string()))?;
        plots.push((format!("differences-vs-{}.svg", t.baseline), svg));
    }
    let facts: Vec<_> = study.missions.iter().map(|m| &m.facts).collect();
    let data = serde_json::json!({
        "missions": facts, "runs": study.runs, "outcomes": outcomes, "tallies": tallies, "comparisons": comparisons,
    });
    Ok(ReproReport { plots, ..ReproReport::new(ID.into(), table, checks, data) })
}

fn mission<'a>(
    study: &'a Study,
    comparisons: &'a [Comparison],
    index: usize,
) -> Result<(&'a crate::scenario::generate::Mission, &'a Comparison), ExperimentError> {
    study
        .missions
        .iter()
        .zip(comparisons)
        .find(|(m, _)| m.facts.index == index)
        .ok_or_else(|| fail(format!("mission {index} not in the study")))
}

fn index_of(c: &Comparison, policy: &str) -> Result<usize, ExperimentError> {
    c.policies.iter().position(|s| s.policy == policy).ok_or_else(|| fail(format!("{policy} not in the comparison")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::{closed_loop::TUNING_SEED, Size};

    #[test]
    fn the_reduced_study_reports_every_baseline_and_every_mission() {
        let report = generalization(&ReproOptions::new(Size::Reduced, 1)).unwrap();
        let baselines = policies().len() - 1;
        let tallies = report.data["tallies"].as_array().unwrap();
        assert_eq!(tallies.len(), baselines);
        for t in tallies {
            let n: u64 = ["won", "tied", "lost"].iter().map(|k| t[k].as_u64().unwrap()).sum();
            assert_eq!(n, 3, "{t}");
            assert!(report.table.contains(t["baseline"].as_str().unwrap()));
        }
        assert_eq!(report.data["missions"].as_array().unwrap().len(), 3);
        assert_eq!(report.data["runs"], 3);
        // Two checks per baseline, and the filters' finiteness.
        assert_eq!(report.checks.len(), 2 * baselines + 1);
        assert_eq!(report.plots.len(), baselines);
        assert!(report.plots.iter().all(|(name, svg)| name.starts_with("differences-vs-") && svg.contains("<svg")));
        assert!(report.table.contains("Every mission lost"));
        // Written to a directory as it goes, each mission read back from its file: the same
        // report, number for number (CBOR keeps every f64), and one file per mission.
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("study");
        let seen = std::sync::Mutex::new(Vec::new());
        let written = run_in(&ReproOptions::new(Size::Reduced, 1), &dir, &|s| seen.lock().unwrap().push(s)).unwrap();
        assert_eq!(written.printed(), report.printed());
        assert_eq!(serde_json::to_string(&written).unwrap(), serde_json::to_string(&report).unwrap());
        for i in 0..3 {
            assert!(dir.join(format!("missions/{i:03}.cbor")).is_file(), "mission {i}");
        }
        let seen = seen.into_inner().unwrap();
        let last = *seen.last().unwrap();
        let per_mission = (baselines as u64 + 1) * 3;
        assert_eq!(
            last,
            Status {
                missions_done: 3,
                missions_total: 3,
                missions_resumed: 0,
                runs_done: 3 * per_mission,
                runs_total: 3 * per_mission
            }
        );
        assert_eq!(seen.iter().filter(|s| s.missions_done == 1).count() as u64, per_mission + 1, "{seen:?}");
    }

    fn outcome(mission: usize, baseline: &str, mean: f64, half: f64) -> Outcome {
        let difference = Ci { mean, low: mean - half, high: mean + half };
        Outcome { mission, baseline: baseline.into(), difference, verdict: Verdict::of(&difference) }
    }

    #[test]
    fn the_verdict_fails_on_a_lost_share_above_two_percent_or_a_pooled_ci_not_below_zero() {
        // 100 missions vs one baseline, all won: both checks pass.
        let won: Vec<Outcome> = (0..100).map(|i| outcome(i, "zigzag", -2.0 - (i % 7) as f64, 0.5)).collect();
        assert!(verdict(&won).iter().all(|c| c.passed()), "{:?}", verdict(&won));
        // Three lost of 100 (> 2 %): the lost-share check fails, the pooled one still passes.
        let mut three = won.clone();
        for o in three.iter_mut().take(3) {
            *o = outcome(o.mission, "zigzag", 1.0, 0.5);
        }
        let checks = verdict(&three);
        assert!(checks[0].passed() && !checks[1].passed(), "{checks:?}");
        assert!(checks[1].detail.starts_with("3 lost"), "{}", checks[1].detail);
        // Two lost of 100 is allowed.
        let two: Vec<Outcome> = three.iter().skip(1).cloned().chain([won[0].clone()]).collect();
        assert!(verdict(&two)[1].passed());
        // No mission lost, but a pooled difference whose CI reaches zero: the pooled check fails.
        let tied: Vec<Outcome> =
            (0..50).map(|i| outcome(i, "racetrack", if i % 2 == 0 { -1.0 } else { 0.9 }, 3.0)).collect();
        let checks = verdict(&tied);
        assert!(!checks[0].passed() && checks[1].passed(), "{checks:?}");
        assert_eq!(tallies(&tied)[0].tied, 50);
    }

    #[test]
    fn a_seed_range_holding_the_tuning_seed_is_refused() {
        let e = generalization(&ReproOptions::new(Size::Reduced, TUNING_SEED - 1)).unwrap_err();
        assert!(e.to_string().contains(&TUNING_SEED.to_string()), "{e}");
    }
}
