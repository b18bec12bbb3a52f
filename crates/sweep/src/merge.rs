//! Joining a plan's finished shards: per cell the paired comparison `coopnav simulate --runs`
//! writes (the same table, JSON and plot), over all cells the runs and fleet tables, and the
//! failed runs, named. Everything lands in one run directory (`DIR/merged` unless told
//! otherwise) written the project's way (staged, renamed into place, replaced only with force).
//!
//! A cell with a failed run gets no comparison (its pairs would no longer be paired); the merge
//! lists every failure in `failures.csv`, in the fleet table's `error` column and in what it
//! returns.

use crate::error::SweepError;
use crate::plan::Plan;
use crate::shard::{read_finished, Outcome, Record};
use crate::table::tables;
use coopnav_sim::batch::mc::{compare, comparison_table, Comparison};
use coopnav_sim::experiments::{sweep_report, ReproReport};
use coopnav_sim::observe::metrics::RunResult;
use coopnav_sim::output::run::differences_svg;
use coopnav_sim::output::{Manifest, RunDir, MANIFEST};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files of a merged sweep: (file, what it holds).
pub const FILES: [(&str, &str); 8] = [
    ("manifest.json", "the command, the plan's digest and the sweep file"),
    ("comparison.txt", "each cell's table as `simulate --runs` prints it"),
    ("comparison.json", "each cell's axis values, statistics and paired differences"),
    ("differences.svg", "each cell's paired differences from the first policy, with their 95 % CIs"),
    ("runs.parquet", "one row per run and survey AUV (docs/sweeps.md)"),
    ("fleet.parquet", "one row per run (docs/sweeps.md)"),
    ("runs.csv", "runs.parquet as CSV"),
    ("fleet.csv", "fleet.parquet as CSV"),
];

/// A failed run, as the merge reports it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Failure {
    pub run_id: usize,
    pub cell: usize,
    pub policy: String,
    pub run: usize,
    pub error: String,
}

/// One cell of `comparison.json`.
#[derive(Debug, Clone, Serialize)]
struct CellOut<'a> {
    cell: usize,
    scenario: &'a str,
    axes: serde_json::Map<String, serde_json::Value>,
    failed_runs: usize,
    comparison: Option<&'a Comparison>,
}

/// Where the merge writes the report of the reproduction the sweep file names (`report`):
/// `table.txt`, `report.json` and the plots, as `coopnav reproduce ID -o DIR` writes them.
pub const REPORT_DIR: &str = "reproduction";

/// What a merge wrote.
#[derive(Debug, Clone)]
pub struct Merged {
    pub dir: PathBuf,
    /// comparison.txt's text.
    pub table: String,
    pub failures: Vec<Failure>,
    /// The reproduction's report (the sweep file's `report`), when every run finished.
    pub report: Option<ReproReport>,
}

/// Every record of the plan, in id order, or the shards not finished.
pub fn collect(plan: &Plan) -> Result<Vec<Record>, SweepError> {
    let mut records = Vec::with_capacity(plan.total_runs());
    let mut unfinished = Vec::new();
    for s in 0..plan.inputs.shards {
        match read_finished(plan, s)? {
            Some(r) => records.extend(r),
            None => unfinished.push(s),
        }
    }
    if !unfinished.is_empty() {
        return Err(SweepError::Unfinished { dir: plan.dir.clone(), shards: unfinished });
    }
    records.sort_by_key(|r| r.id);
    Ok(records)
}

/// Each cell's comparison (None where a run failed) and the failures, from `records` (every run
/// of the plan in id order).
pub fn comparisons(plan: &Plan, records: &[Record]) -> (Vec<Option<Comparison>>, Vec<Failure>) {
    let per_cell = plan.inputs.policies.len() * plan.inputs.runs;
    let mut failures = Vec::new();
    let mut out = Vec::new();
    for (c, cell) in plan.cells.iter().enumerate() {
        let chunk = &records[c * per_cell..(c + 1) * per_cell];
        let mut results: Vec<RunResult> = Vec::with_capacity(per_cell);
        for r in chunk {
            match &r.outcome {
                Outcome::Done(result) => results.push(result.as_ref().clone()),
                Outcome::Failed(error) => {
                    let at = plan.locate(r.id);
                    failures.push(Failure {
                        run_id: r.id,
                        cell: c,
                        policy: plan.inputs.policies[at.policy].clone(),
                        run: at.run,
                        error: error.clone(),
                    });
                }
            }
        }
        out.push(
            (results.len() == per_cell)
                .then(|| compare(&cell.scenario, &plan.inputs.policies, plan.inputs.runs, &results)),
        );
    }
    (out, failures)
}

/// comparison.txt: one cell's table alone; several cells each under a line naming it.
fn text(plan: &Plan, comparisons: &[Option<Comparison>], failures: &[Failure]) -> String {
    if let [Some(only)] = comparisons {
        return comparison_table(only);
    }
    let mut out = String::new();
    for (c, (cell, comparison)) in plan.cells.iter().zip(comparisons).enumerate() {
        out += &format!("cell {c}: {}\n", cell.label());
        match comparison {
            Some(cmp) => out += &comparison_table(cmp),
            None => {
                let n = failures.iter().filter(|f| f.cell == c).count();
                out += &format!("no comparison: {n} of its runs failed (failures.csv)\n");
            }
        }
        out += "\n";
    }
    out
}

/// Merges the finished shards of `plan` into `target` (default `DIR/merged`).
pub fn merge(plan: &Plan, target: Option<&Path>, force: bool, command: &str) -> Result<Merged, SweepError> {
    let target = target.map_or_else(|| plan.dir.join("merged"), Path::to_path_buf);
    let dir = RunDir::create_for(&target, force, &[])?;
    let records = collect(plan)?;
    let (comparisons, failures) = comparisons(plan, &records);
    let table = text(plan, &comparisons, &failures);
    let encode =
        |file: &str, e: &dyn std::fmt::Display| SweepError::Encode { file: file.into(), message: e.to_string() };
    let inputs =
        serde_json::json!({ "plan": plan.dir, "digest": plan.inputs.digest, "sweep_file": plan.inputs.sweep_file });
    dir.write_json(MANIFEST, &Manifest::new(command, None, inputs))?;
    dir.write_text(FILES[1].0, &table)?;
    let cells: Vec<CellOut> = plan
        .cells
        .iter()
        .zip(&comparisons)
        .enumerate()
        .map(|(c, (cell, cmp))| CellOut {
            cell: c,
            scenario: &cell.base,
            axes: cell
                .labels
                .iter()
                .map(|(a, v)| (a.clone(), serde_json::to_value(v).unwrap_or(serde_json::Value::Null)))
                .collect(),
            failed_runs: failures.iter().filter(|f| f.cell == c).count(),
            comparison: cmp.as_ref(),
        })
        .collect();
    dir.write_json(FILES[2].0, &serde_json::json!({ "cells": cells, "failures": failures }))?;
    let labelled: Vec<(String, &Comparison)> = plan
        .cells
        .iter()
        .zip(&comparisons)
        .filter_map(|(cell, cmp)| cmp.as_ref().map(|c| (short_label(plan, cell), c)))
        .collect();
    dir.write_text(FILES[3].0, &differences_svg(&labelled).map_err(coopnav_sim::output::WriteError::from)?)?;
    let (runs, fleet) = tables(plan, &records);
    for ((file, _), table) in FILES[4..6].iter().zip([&runs, &fleet]) {
        dir.write_bytes(file, table.parquet().map_err(|e| encode(file, &e))?)?;
    }
    for ((file, _), table) in FILES[6..8].iter().zip([&runs, &fleet]) {
        dir.write_bytes(file, table.csv().map_err(|e| encode(file, &e))?)?;
    }
    if !failures.is_empty() {
        dir.write_csv("failures.csv", failures.iter())?;
    }
    let report = match (reproduction(plan)?, failures.is_empty()) {
        (Some(id), true) => {
            let cells: Vec<(&str, &coopnav_sim::scenario::Scenario)> =
                plan.cells.iter().map(|c| (c.base.as_str(), &c.scenario)).collect();
            let all: Vec<Comparison> = comparisons.into_iter().flatten().collect();
            let report = sweep_report(&id, &cells, all, plan.inputs.runs).map_err(|e| SweepError::Report {
                dir: plan.dir.clone(),
                id: id.clone(),
                message: e.to_string(),
            })?;
            dir.write_text(&format!("{REPORT_DIR}/table.txt"), &report.printed())?;
            dir.write_json(&format!("{REPORT_DIR}/report.json"), &report)?;
            for (name, svg) in &report.plots {
                dir.write_text(&format!("{REPORT_DIR}/{name}"), svg)?;
            }
            Some(report)
        }
        _ => None,
    };
    Ok(Merged { dir: dir.finish()?, table, failures, report })
}

/// The reproduction the plan's sweep file names (`report`), if any.
fn reproduction(plan: &Plan) -> Result<Option<String>, SweepError> {
    let sweep = crate::file::SweepFile::parse(&plan.inputs.sweep, Path::new(&plan.inputs.sweep_file))?;
    Ok(sweep.report)
}

/// A cell's name in the plot: its axis values, or its base scenario when there are no axes.
fn short_label(plan: &Plan, cell: &crate::expand::Cell) -> String {
    if cell.labels.is_empty()
        || plan.inputs.cells.iter().map(|c| &c.base).collect::<std::collections::BTreeSet<_>>().len() > 1
    {
        return cell.label();
    }
    cell.labels.iter().map(|(a, v)| format!("{a}={v}")).collect::<Vec<_>>().join(" ")
}
