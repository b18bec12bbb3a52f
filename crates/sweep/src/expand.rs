//! Checking a whole sweep file and expanding it into cells. Every problem is found before any
//! is reported (a bad axis, path, value, overlay or policy, a cell whose scenario is invalid),
//! each named with the file and what is allowed.
//!
//! The order, which the run ids and so the shards follow: base scenario by base scenario (file
//! order), then every combination of the axes' values, the first axis changing slowest and the
//! last fastest; within a cell, policy by policy (file order), run 0, 1, ... `runs - 1`.
//!
//! A path names a scenario field by its tables and key (`comms.tau`); it is checked against the
//! scenario after defaults (every table and key the base scenario holds) and, for an optional
//! field the scenario leaves unset, by reading the scenario with the field set.

use crate::error::SweepError;
use crate::file::{Axis, SweepFile, EMBEDDED};
use coopnav_core::limits::{self, Estimate, MAX_POINTS};
use coopnav_sim::batch::work;
use coopnav_sim::policy::registry::{PolicySpec, POLICY_NAMES};
use coopnav_sim::scenario::file::{overlay, read_scenario_text};
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use std::path::{Path, PathBuf};

/// One cell: a base scenario with one value of every axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// The base scenario as the sweep file names it.
    pub base: String,
    /// (axis name, value) for every axis, in axis order.
    pub labels: Vec<(String, toml::Value)>,
    pub scenario: Scenario,
}

impl Cell {
    /// "base, axis = value, ..." (how tables and messages name the cell).
    pub fn label(&self) -> String {
        std::iter::once(self.base.clone())
            .chain(self.labels.iter().map(|(a, v)| format!("{a} = {v}")))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// A sweep file, checked and expanded.
#[derive(Debug, Clone, PartialEq)]
pub struct Expansion {
    /// The axes' names, in order: a path, or `overlay` (`overlay2`, ... for further overlay axes).
    pub axes: Vec<String>,
    pub cells: Vec<Cell>,
    pub policies: Vec<String>,
    pub runs: usize,
}

/// One axis, checked: its name and, per value, the patch merged over the scenario.
struct Checked {
    name: String,
    values: Vec<(toml::Value, toml::Value)>,
}

/// Checks the sweep read from `file` and expands it (`allow_large`: the cell count's limit is
/// lifted).
pub fn expand(sweep: &SweepFile, file: &Path, allow_large: bool) -> Result<Expansion, SweepError> {
    let invalid = |problems| SweepError::Invalid { file: file.to_path_buf(), problems };
    let mut problems = Vec::new();
    if sweep.runs == 0 {
        problems.push("runs = 0: allowed at least 1".to_string());
    }
    check_policies(&sweep.policies, &mut problems);
    let bases = load_bases(sweep, file, &mut problems);
    let axes = check_axes(sweep, &bases, &mut problems);
    check_overlays(sweep, &bases, &mut problems);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    let count = bases.len() as f64 * axes.iter().map(|a| a.values.len() as f64).product::<f64>();
    let estimate = Estimate::new("sweep cells", "scenarios x values of every [[axis]]", count, MAX_POINTS);
    limits::check([estimate], allow_large)?;
    let mut cells = Vec::new();
    for (name, base) in &bases {
        for choice in combinations(&axes) {
            match cell(name, base, &axes, &choice, &sweep.policies) {
                Ok(c) => cells.push(c),
                Err(p) => problems.push(p),
            }
        }
    }
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    Ok(Expansion {
        axes: axes.into_iter().map(|a| a.name).collect(),
        cells,
        policies: sweep.policies.clone(),
        runs: sweep.runs,
    })
}

fn check_policies(policies: &[String], problems: &mut Vec<String>) {
    if policies.is_empty() {
        problems.push(format!("policies = []: give at least one of {}", POLICY_NAMES.join(", ")));
    }
    for (i, p) in policies.iter().enumerate() {
        if !POLICY_NAMES.contains(&p.as_str()) {
            problems.push(format!("policies[{i}] = \"{p}\": allowed {}", POLICY_NAMES.join(", ")));
        } else if policies[..i].contains(p) {
            problems.push(format!("policies[{i}] = \"{p}\": listed twice"));
        }
    }
}

/// The base scenarios, read and validated: (name as written, scenario).
fn load_bases(sweep: &SweepFile, file: &Path, problems: &mut Vec<String>) -> Vec<(String, Scenario)> {
    if sweep.scenarios.is_empty() {
        problems.push(format!("scenarios = []: give at least one closed-loop scenario file (or \"{EMBEDDED}\")"));
    }
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut bases = Vec::new();
    for (i, name) in sweep.scenarios.iter().enumerate() {
        let loaded = if name == EMBEDDED {
            Scenario::parse(EXAMPLE, Path::new("<embedded default>"))
        } else {
            let path: PathBuf = dir.join(name);
            read_scenario_text(&path, false).and_then(|text| Scenario::parse(&text, &path))
        };
        match loaded {
            Ok(s) => bases.push((name.clone(), s)),
            Err(e) => problems.push(format!("scenarios[{i}] = \"{name}\": {e}")),
        }
    }
    bases
}

/// The patch that sets `path` to `value`: nested tables down to the key.
fn patch(path: &str, value: toml::Value) -> toml::Value {
    path.rsplit('.').fold(value, |inner, key| {
        let mut t = toml::Table::new();
        t.insert(key.to_string(), inner);
        toml::Value::Table(t)
    })
}

fn check_axes(sweep: &SweepFile, bases: &[(String, Scenario)], problems: &mut Vec<String>) -> Vec<Checked> {
    let mut out = Vec::new();
    let mut overlay_axes = 0;
    for (i, axis) in sweep.axes.iter().enumerate() {
        let checked = match axis {
            Axis { path: Some(path), values: Some(values), overlays: None } => {
                check_path(i, path, values, bases, problems)
            }
            Axis { path: None, values: None, overlays: Some(names) } => {
                overlay_axes += 1;
                let name = if overlay_axes == 1 { "overlay".to_string() } else { format!("overlay{overlay_axes}") };
                check_overlay_axis(i, name, names, sweep, problems)
            }
            Axis { path: Some(_), values: None, overlays: None } => {
                problems.push(format!("axis[{i}]: path needs its values (values = [...])"));
                None
            }
            _ => {
                problems.push(format!("axis[{i}]: give either path and values, or overlays"));
                None
            }
        };
        if let Some(c) = checked {
            if out.iter().any(|o: &Checked| o.name == c.name) {
                problems.push(format!("axis[{i}].path = \"{}\": already an axis", c.name));
            }
            out.push(c);
        }
    }
    out
}

fn check_path(
    i: usize,
    path: &str,
    values: &[toml::Value],
    bases: &[(String, Scenario)],
    problems: &mut Vec<String>,
) -> Option<Checked> {
    if values.is_empty() {
        problems.push(format!("axis[{i}].values = []: give at least one value"));
        return None;
    }
    let before = problems.len();
    for (name, base) in bases {
        if let Err(why) = field_exists(base, path, &values[0]) {
            problems.push(format!("axis[{i}].path = \"{path}\": {why} in scenario {name}"));
            continue;
        }
        for (j, v) in values.iter().enumerate() {
            if let Err(e) = overlay(base, patch(path, v.clone())) {
                problems.push(format!("axis[{i}].values[{j}] = {v}: {} (scenario {name})", e.trim()));
            }
        }
    }
    (problems.len() == before).then(|| Checked {
        name: path.to_string(),
        values: values.iter().map(|v| (v.clone(), patch(path, v.clone()))).collect(),
    })
}

/// Whether `path` names a field of `base` (see the module doc), or why not.
fn field_exists(base: &Scenario, path: &str, value: &toml::Value) -> Result<(), String> {
    let tree = toml::Value::try_from(base).map_err(|e| e.to_string())?;
    let mut node = &tree;
    let mut walked = Vec::new();
    for key in path.split('.') {
        let toml::Value::Table(table) = node else {
            return Err(format!("{} is a value, not a table", walked.join(".")));
        };
        match table.get(key) {
            Some(next) => node = next,
            None if overlay(base, patch(path, value.clone())).is_ok() => return Ok(()),
            None => {
                let keys: Vec<&str> = table.keys().map(String::as_str).collect();
                let place = if walked.is_empty() {
                    "at the top level".to_string()
                } else {
                    format!("in [{}]", walked.join("."))
                };
                return Err(format!("no field `{key}` {place} (allowed: {})", keys.join(", ")));
            }
        }
        walked.push(key);
    }
    if node.is_table() {
        return Err(format!("{path} is a table, not a value (name one of its keys)"));
    }
    Ok(())
}

fn check_overlay_axis(
    i: usize,
    name: String,
    names: &[String],
    sweep: &SweepFile,
    problems: &mut Vec<String>,
) -> Option<Checked> {
    if names.is_empty() {
        problems.push(format!("axis[{i}].overlays = []: give at least one overlay name"));
        return None;
    }
    let known: Vec<&str> = sweep.overlays.keys().map(String::as_str).collect();
    let mut values = Vec::new();
    for (j, n) in names.iter().enumerate() {
        match sweep.overlays.get(n) {
            Some(t) => values.push((toml::Value::String(n.clone()), toml::Value::Table(t.clone()))),
            None => problems.push(format!(
                "axis[{i}].overlays[{j}] = \"{n}\": no [overlay.{n}] (allowed: {})",
                if known.is_empty() { "none defined".to_string() } else { known.join(", ") }
            )),
        }
    }
    (values.len() == names.len()).then_some(Checked { name, values })
}

/// Every overlay reads over every base scenario, and is used by an axis.
fn check_overlays(sweep: &SweepFile, bases: &[(String, Scenario)], problems: &mut Vec<String>) {
    for (name, table) in &sweep.overlays {
        if !sweep.axes.iter().any(|a| a.overlays.as_ref().is_some_and(|o| o.contains(name))) {
            problems.push(format!("overlay.{name}: no axis uses it (name it in an axis: overlays = [\"{name}\"])"));
        }
        for (base, sc) in bases {
            if let Err(e) = overlay(sc, toml::Value::Table(table.clone())) {
                problems.push(format!("overlay.{name}: {} (scenario {base})", e.trim()));
            }
        }
    }
}

/// Every choice of one value index per axis, the last axis fastest.
fn combinations(axes: &[Checked]) -> Vec<Vec<usize>> {
    axes.iter().fold(vec![Vec::new()], |acc, axis| {
        acc.into_iter()
            .flat_map(|prefix| (0..axis.values.len()).map(move |v| [prefix.clone(), vec![v]].concat()))
            .collect()
    })
}

/// The cell of `base` with value `choice[k]` of axis k: patched in axis order, validated, and
/// every policy built for it.
fn cell(name: &str, base: &Scenario, axes: &[Checked], choice: &[usize], policies: &[String]) -> Result<Cell, String> {
    let mut scenario = base.clone();
    let mut labels = Vec::new();
    for (axis, &v) in axes.iter().zip(choice) {
        let (value, patch) = &axis.values[v];
        scenario = overlay(&scenario, patch.clone()).map_err(|e| e.trim().to_string())?;
        labels.push((axis.name.clone(), value.clone()));
    }
    let c = Cell { base: name.to_string(), labels, scenario };
    c.scenario.validate(Path::new(&c.label())).map_err(|e| format!("cell {}: {e}", c.label()))?;
    for p in policies {
        PolicySpec::new(p, &c.scenario).map_err(|e| format!("cell {}: {e}", c.label()))?;
    }
    Ok(c)
}

/// The work of the whole sweep: the runs' simulated vehicle-steps and planner updates summed
/// over the cells, every other size the largest of one cell.
pub fn work(e: &Expansion) -> Vec<Estimate> {
    let mut out: Vec<Estimate> = Vec::new();
    for c in &e.cells {
        for est in work::closed_loop(&c.scenario, e.runs, e.policies.len()) {
            let summed = matches!(est.what, "simulated vehicle-steps" | "planner AUV-node updates");
            match out.iter_mut().find(|o| o.what == est.what) {
                Some(o) if summed => o.value += est.value,
                Some(o) => o.value = o.value.max(est.value),
                None => out.push(Estimate { fields: format!("every cell: {}", est.fields), ..est }),
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
