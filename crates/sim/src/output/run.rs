//! The run directory of one closed-loop mission: time series CSV, the comms log, summary.json,
//! manifest.json, SVG plots (tracks true/estimated/CNA, error vs time per AUV with its marked
//! jumps, comms timeline) and a self-contained report.html that shows every plot inline.

use crate::batch::mc::{comparison_table, Comparison};
use crate::engine::{Trace, TraceRow};
use crate::observe::metrics::RunResult;
use crate::output::jumps::{self, Jump};
use crate::output::plot::{intervals_svg, Interval};
use crate::output::plot::{line_svg, line_svg_marked, track_svg, Labels, Marker, PlotError, Series};
use crate::output::report::HtmlReport;
use crate::output::{Manifest, RunDir, WriteError};
use crate::scenario::world::Scenario;
use std::path::PathBuf;

/// The plots every run directory holds: (file, caption).
pub const PLOTS: [(&str, &str); 3] = [
    ("tracks.svg", "Tracks of every survey AUV, true (solid) and estimated (dashed, same colour), and the CNA's track"),
    ("error.svg", "True navigation error of each survey AUV over time (solid), beside the planner's modelled error (dashed, same colour); a triangle marks each one-second rise that stands out, with what the filter did then"),
    ("comms.svg", "Comms timeline: cumulative packets received per AUV, CNA broadcast down (solid) and status up (dashed, same colour)"),
];

/// Writes `result` (recorded with a trace) into `dir` and finishes it.
pub fn write_run(dir: RunDir, sc: &Scenario, result: &RunResult, command: &str) -> Result<PathBuf, WriteError> {
    let trace = result.trace.as_ref().ok_or(WriteError::NotRecorded)?;
    let inputs = serde_json::json!({ "scenario": sc, "policy": result.policy, "planners": sc.resolved_planners() });
    dir.write_json("manifest.json", &Manifest::new(command, Some(result.seed), inputs))?;
    dir.write_json("summary.json", result)?;
    dir.write_csv("timeseries.csv", trace.rows.iter())?;
    dir.write_csv("comms.csv", trace.comms.iter())?;
    let jumps = jumps::jumps(trace);
    let svgs = plots(sc.fleet.n_auvs, trace, &jumps, sc.filter.params.range_gate.max_nis)?;
    for ((file, _), svg) in PLOTS.iter().zip(&svgs) {
        dir.write_text(file, svg)?;
    }
    crate::output::moos_export::write_moos_files(&dir, &crate::output::moos_export::closed_loop_run(sc, result)?)?;
    dir.write_text("report.html", &report(sc, result, &svgs, &jumps, command))?;
    Ok(dir.finish()?)
}

/// The files of a Monte Carlo comparison's run directory: (file, what it holds).
pub const COMPARISON_FILES: [(&str, &str); 4] = [
    ("manifest.json", "the command, the seed and the scenario after defaults"),
    ("comparison.txt", "the table `simulate --runs` prints"),
    ("comparison.json", "every policy's statistics and every paired difference"),
    ("differences.svg", "each policy's paired difference from the first, with its 95 % CI"),
];

/// Writes the Monte Carlo comparison `c` of scenario `sc` (named `name` in the plot) into `dir`
/// and finishes it.
pub fn write_comparison(
    dir: RunDir,
    sc: &Scenario,
    c: &Comparison,
    name: &str,
    command: &str,
) -> Result<PathBuf, WriteError> {
    let policies: Vec<&str> = c.policies.iter().map(|p| p.policy.as_str()).collect();
    let inputs =
        serde_json::json!({ "scenario": sc, "policies": policies, "runs": c.runs, "planners": sc.resolved_planners() });
    dir.write_json(COMPARISON_FILES[0].0, &Manifest::new(command, Some(c.seed), inputs))?;
    dir.write_text(COMPARISON_FILES[1].0, &comparison_table(c))?;
    dir.write_json(COMPARISON_FILES[2].0, c)?;
    dir.write_text(COMPARISON_FILES[3].0, &difference_svg(c, name)?)?;
    Ok(dir.finish()?)
}

/// The paired differences of a comparison: the first policy minus each other one.
fn difference_svg(c: &Comparison, name: &str) -> Result<String, PlotError> {
    differences_svg(&[(name.to_string(), c)])
}

/// The paired differences of several comparisons (one per labelled cell), one row per
/// (cell, baseline): the first policy of each minus each other one.
pub fn differences_svg(cells: &[(String, &Comparison)]) -> Result<String, PlotError> {
    let reference =
        cells.first().and_then(|(_, c)| c.policies.first()).map_or("the first policy", |p| p.policy.as_str());
    let title = format!("{reference} minus each policy, fleet mean true error (m), paired 95 % CI");
    let rows: Vec<Interval> = cells
        .iter()
        .flat_map(|(name, c)| {
            c.paired.iter().map(move |p| Interval {
                label: format!("{name} N={} vs {}", c.n_auvs, p.baseline),
                mean: p.difference.mean,
                low: p.difference.low,
                high: p.difference.high,
                good: p.planner_better,
            })
        })
        .collect();
    intervals_svg(&title, &format!("difference, m (negative = {reference} better)"), &rows)
}

/// The most rises the error plot marks (each adds a line under it).
const MARKED: usize = 8;

/// The error plot's note: what its triangles mark (`gate`: the filters' NIS gate, if any), when
/// it marks `shown` of `total` rises.
fn jump_note(tr: &Trace, gate: Option<f64>, shown: usize, total: usize) -> String {
    let rise = jumps::threshold(tr);
    if shown < total {
        return format!(
            "Triangles: the {shown} largest of {total} rises of {rise:.1} m or more in one second (the report \
             lists all), and what the filter did then:"
        );
    }
    let gate = gate.map_or(String::new(), |g| format!(", gate {g:.2}"));
    format!(
        "Triangles: rises of {rise:.1} m or more in one second, and what the filter did then (a range: \
         its true error, NIS{gate}, σ before):"
    )
}

/// A jump's marker text: the AUV, the rise and its cause.
fn jump_text(j: &Jump) -> String {
    format!("auv{} {:.0} s, +{:.1} m: {}", j.auv, j.t, j.after - j.before, j.cause)
}

fn plots(n: usize, tr: &Trace, jumps: &[Jump], gate: Option<f64>) -> Result<Vec<String>, PlotError> {
    let per_auv = |f: &dyn Fn(&TraceRow) -> (f64, f64), k: usize| {
        tr.rows.iter().filter(|r| r.auv == k).map(f).collect::<Vec<_>>()
    };
    let mut tracks = Vec::new();
    for k in 0..n {
        tracks.push(Series::new(format!("auv{k} true"), per_auv(&|r| (r.true_x, r.true_y), k)).colour(k));
        tracks.push(Series::new(format!("auv{k} estimated"), per_auv(&|r| (r.est_x, r.est_y), k)).colour(k).dashed());
    }
    tracks.push(Series::new("CNA", tr.cna.iter().map(|(_, p)| (p.x, p.y)).collect()).cna());
    let mut errors = Vec::new();
    for k in 0..n {
        errors.push(Series::new(format!("auv{k} true error"), per_auv(&|r| (r.t, r.error), k)).colour(k));
        let modelled: Vec<(f64, f64)> =
            tr.rows.iter().filter(|r| r.auv == k).filter_map(|r| r.modelled.map(|m| (r.t, m))).collect();
        if !modelled.is_empty() {
            errors.push(Series::new(format!("auv{k} modelled"), modelled).colour(k).dashed());
        }
    }
    let mut comms = Vec::new();
    for (dir, dashed) in [("down", false), ("up", true)] {
        for k in 0..n {
            let mut count = 0.0;
            let pts = tr
                .comms
                .iter()
                .filter(|e| e.auv == k && e.direction == dir)
                .map(|e| {
                    count += f64::from(u8::from(e.received));
                    (e.t, count)
                })
                .collect();
            let line = Series::new(format!("{dir} auv{k}"), pts).colour(k);
            comms.push(if dashed { line.dashed() } else { line });
        }
    }
    Ok(vec![
        track_svg(Labels { title: "Tracks", x: "east [m]", y: "north [m]" }, &tracks)?,
        {
            // The largest MARKED rises, in time order; the report lists every one.
            let mut marked: Vec<&Jump> = jumps.iter().collect();
            marked.sort_by(|a, b| (b.after - b.before).total_cmp(&(a.after - a.before)));
            marked.truncate(MARKED);
            marked.sort_by(|a, b| a.t.total_cmp(&b.t));
            let markers: Vec<Marker> = marked
                .iter()
                .map(|j| Marker {
                    x: j.t,
                    y: j.after,
                    colour: coopnav_moos::palette::vehicle(j.auv),
                    text: jump_text(j),
                })
                .collect();
            let note = if jumps.is_empty() { String::new() } else { jump_note(tr, gate, markers.len(), jumps.len()) };
            line_svg_marked(
                Labels { title: "Navigation error", x: "time [s]", y: "error [m]" },
                &errors,
                &markers,
                &note,
            )?
        },
        line_svg(Labels { title: "Comms timeline", x: "time [s]", y: "packets received" }, &comms)?,
    ])
}

fn report(sc: &Scenario, r: &RunResult, svgs: &[String], jumps: &[Jump], command: &str) -> String {
    let mut h = HtmlReport::new(format!("coopnav closed-loop mission: policy {}", r.policy));
    h.provenance(command, Some(r.seed));
    h.paragraph(&format!(
        "{} survey AUVs, ASC CNA at {} m/s, τ = {} s, {} s mission, seed {}. Errors are the survey AUVs' TRUE navigation errors (EKF estimate minus truth).",
        sc.fleet.n_auvs, sc.cna.speed, sc.comms.tau, sc.duration_s, r.seed
    ));
    h.link(coopnav_moos::replay::FILE, "Interactive replay (tracks, 1σ/2σ ellipses, pulses, error against time)");
    h.heading("Per AUV");
    let fmt = |v: f64| format!("{v:.2}");
    let rows: Vec<Vec<String>> = r
        .auvs
        .iter()
        .map(|a| {
            vec![
                a.name.clone(),
                fmt(a.error.mean),
                fmt(a.error.rms),
                fmt(a.error.p95),
                fmt(a.error.max),
                fmt(a.error.cep50),
                a.modelled_mean.map_or("-".into(), fmt),
                format!("{}/{}", a.downlink.received, a.downlink.sent),
                format!("{}/{}", a.uplink.received, a.uplink.sent),
                fmt(a.distance_mean),
                format!("{:.1}", 100.0 * a.limit_violation),
            ]
        })
        .collect();
    h.table(
        &[
            "AUV",
            "mean [m]",
            "RMS",
            "p95",
            "max",
            "CEP50",
            "modelled",
            "ranges rx/tx",
            "status rx/tx",
            "mean dist [m]",
            "limit viol. %",
        ],
        &rows,
    );
    h.heading("Filter health (against the truth)");
    let health: Vec<Vec<String>> = r
        .auvs
        .iter()
        .map(|a| {
            let f = &a.health;
            vec![
                a.name.clone(),
                fmt(a.error.rms),
                fmt(f.sigma_mean),
                fmt(f.error_to_sigma),
                fmt(f.nees_mean),
                format!("{:.1}", 100.0 * f.nees_in_95),
                f.nis_mean.map_or("-".into(), fmt),
                fmt(a.distance_mean),
                f.diverged_at_s.map_or("no".into(), |t| format!("yes, at {t:.0} s")),
            ]
        })
        .collect();
    h.table(
        &[
            "AUV",
            "true RMS [m]",
            "filter σ [m]",
            "RMS/σ",
            "NEES mean (2 = consistent)",
            "NEES in 95 % bound %",
            "NIS mean (1)",
            "CNA dist [m]",
            "diverged",
        ],
        &health,
    );
    if let Some(p) = &r.planner {
        h.paragraph(&format!(
            "Planner: {} decisions, {} deadline misses, levels requested {}, mean levels searched {:.2}, {} failed decisions, {} waiting for reports.",
            p.decisions, p.deadline_misses, p.levels_requested, p.mean_levels_searched, p.failures, p.waiting
        ));
    }
    h.heading("Plots");
    if !jumps.is_empty() {
        let told: Vec<String> = jumps.iter().map(jump_text).collect();
        h.paragraph(&format!("Error jumps marked on the error plot: {}.", told.join("; ")));
    }
    for ((file, caption), svg) in PLOTS.iter().zip(svgs) {
        h.figure(file, caption, svg);
    }
    h.render()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_plot_marks_the_largest_rises_and_says_how_many_it_left_out() {
        // One AUV whose error falls back to 1 m after each of ten rises of 10 to 19 m.
        let mut trace = Trace::default();
        let row = |t: f64, error: f64| crate::output::jumps::tests::row(t, 0, error, 20.0);
        for i in 0..10 {
            let t = 10.0 * f64::from(i);
            trace.rows.extend([row(t, 1.0), row(t + 1.0, 11.0 + f64::from(i)), row(t + 2.0, 1.0)]);
        }
        let jumps = jumps::jumps(&trace);
        assert_eq!(jumps.len(), 10);
        let svg = &plots(1, &trace, &jumps, Some(10.83)).unwrap()[1];
        assert_eq!(svg.matches("<polygon").count(), MARKED);
        assert!(svg.contains("Triangles: the 8 largest of 10 rises of 5.0 m or more"), "the note");
        // The two smallest, +10 m at 1 s and +11 m at 11 s, are left out.
        assert!(!svg.contains("auv0 1 s,") && !svg.contains("auv0 11 s,") && svg.contains("auv0 21 s, +12.0 m"));
        let report = jumps.iter().map(jump_text).collect::<Vec<_>>().join("; ");
        assert!(report.starts_with("auv0 1 s, +10.0 m: no range applied: dead reckoning"), "{report}");
    }
}
