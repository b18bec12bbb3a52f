//! Checking a whole sweep file and expanding it into cells. Every problem is found before any
//! is reported (a bad axis, path, value, overlay, condition or policy, a cell whose scenario is
//! invalid), each named with the file and what is allowed.
//!
//! The order, which the run ids and so the shards follow: base scenario by base scenario (file
//! order; the reduced form: its own order), then every combination of the axes' values for that
//! scenario (its own `values.NAME` where it gives them), the first axis changing slowest and the
//! last fastest; within a cell, policy by policy (file order), run 0, 1, ... `runs - 1`.
//!
//! A cell is made ([`Rules::cell`]) from its base scenario by merging, in this order: each axis's
//! value (a field set by its path, or the overlay named), every `[[conditional]]` overlay whose
//! conditions the cell's axis values meet (file order), and the reduced form's overlay.
//!
//! A path names a scenario field by its tables and key (`comms.tau`), with an index for an entry
//! of an array (`comms.success.curves[1].p_a`, `buoys[0].x`); it is checked against the
//! scenario after defaults (every table, key and array entry the base scenario holds) and, for an
//! optional field the scenario leaves unset, by reading the scenario with the field set.

use super::file::{Axis, Condition, SweepFile, EMBEDDED};
use super::SweepFileError;
use crate::batch::work;
use crate::policy::registry::{PolicySpec, POLICY_NAMES};
use crate::scenario::file::{overlay, read_scenario_text};
use crate::scenario::{Scenario, EXAMPLE};
use coopnav_core::limits::{self, Estimate, MAX_POINTS};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The fixed columns of the sweep's results tables (docs/sweeps.md, Columns), which a name given
/// to an axis (its own column) may not be.
pub const RESERVED_NAMES: [&str; 42] = [
    "auv",
    "auv_name",
    "buoy_received",
    "buoy_sent",
    "cell",
    "distance_max_m",
    "distance_mean_m",
    "distance_min_m",
    "diverged",
    "diverged_at_s",
    "downlink_lost_in_air",
    "downlink_received",
    "downlink_sent",
    "error",
    "error_cep50_m",
    "error_max_m",
    "error_mean_m",
    "error_p95_m",
    "error_rms_m",
    "error_to_sigma",
    "healthy",
    "limit_violation",
    "modelled_mean_m",
    "n_auvs",
    "nees_in_95",
    "nees_mean",
    "nis_in_95",
    "nis_mean",
    "planner_deadline_misses",
    "planner_decisions",
    "planner_failures",
    "planner_mean_levels",
    "policy",
    "ranges_applied",
    "run",
    "run_id",
    "scenario",
    "seed",
    "sigma_mean_m",
    "uplink_lost_in_air",
    "uplink_received",
    "uplink_sent",
];

/// Which form of the sweep to expand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    Full,
    /// The `[reduced]` table's runs, overlay and cells.
    Reduced,
}

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
    /// The axes' names, in order: as given, else a path, or `overlay` (`overlay2`, ... for
    /// further overlay axes).
    pub axes: Vec<String>,
    pub cells: Vec<Cell>,
    pub policies: Vec<String>,
    pub runs: usize,
    pub form: Form,
    /// The base scenarios of this form, in expansion order, each with its values of every axis.
    pub bases: Vec<BaseCells>,
    /// How every cell was made from its base scenario (to make the cell of other values).
    pub rules: Rules,
}

/// A base scenario of the expansion and the values of every axis it is flown with.
#[derive(Debug, Clone, PartialEq)]
pub struct BaseCells {
    pub name: String,
    pub scenario: Scenario,
    /// Per axis (in axis order), its values for this scenario.
    pub values: Vec<Vec<toml::Value>>,
}

/// How an axis value changes the scenario.
#[derive(Debug, Clone, PartialEq)]
enum Setter {
    /// Sets the field at the path.
    Path(String),
    /// Merges the overlay named by the value (every overlay of the file, by name).
    Overlays(BTreeMap<String, toml::Table>),
}

#[derive(Debug, Clone, PartialEq)]
struct AxisRule {
    name: String,
    setter: Setter,
}

/// A `[[conditional]]`, checked: which axis each condition reads, and the overlay.
#[derive(Debug, Clone, PartialEq)]
struct ConditionalRule {
    /// `conditional[K] (overlay.NAME)`, for messages.
    what: String,
    when: Vec<(usize, Condition)>,
    patch: toml::Table,
}

/// How a cell is made from its base scenario and one value per axis (the module doc's order).
#[derive(Debug, Clone, PartialEq)]
pub struct Rules {
    axes: Vec<AxisRule>,
    conditionals: Vec<ConditionalRule>,
    /// The reduced form's overlay: (`reduced.overlay (overlay.NAME)`, table).
    last: Option<(String, toml::Table)>,
}

impl Rules {
    /// The axes' names, in order.
    pub fn axis_names(&self) -> Vec<String> {
        self.axes.iter().map(|a| a.name.clone()).collect()
    }

    /// The scenario of `base` with `values` (one per axis, in axis order): every patch merged,
    /// nothing validated. The error names the patch that does not read.
    pub fn scenario(&self, base: &Scenario, values: &[toml::Value]) -> Result<Scenario, String> {
        if values.len() != self.axes.len() {
            return Err(format!("{} axis values given for {} axes", values.len(), self.axes.len()));
        }
        let mut scenario = base.clone();
        for (axis, value) in self.axes.iter().zip(values) {
            let patch = match &axis.setter {
                Setter::Path(path) if path.contains('[') => {
                    scenario = set_field(&scenario, path, value.clone())
                        .map_err(|e| format!("{} = {value}: {}", axis.name, e.trim()))?;
                    continue;
                }
                Setter::Path(path) => patch(path, value.clone()),
                Setter::Overlays(tables) => {
                    let table = value.as_str().and_then(|n| tables.get(n));
                    let table = table.ok_or_else(|| format!("axis {}: no overlay named {value}", axis.name))?;
                    toml::Value::Table(table.clone())
                }
            };
            scenario = overlay(&scenario, patch).map_err(|e| format!("{} = {value}: {}", axis.name, e.trim()))?;
        }
        for c in &self.conditionals {
            if c.when.iter().all(|(k, cond)| meets(cond, &values[*k])) {
                scenario = overlay(&scenario, toml::Value::Table(c.patch.clone()))
                    .map_err(|e| format!("{}: {}", c.what, e.trim()))?;
            }
        }
        if let Some((what, table)) = &self.last {
            scenario =
                overlay(&scenario, toml::Value::Table(table.clone())).map_err(|e| format!("{what}: {}", e.trim()))?;
        }
        Ok(scenario)
    }

    /// The cell of base scenario `base` (named `name`) with `values`: its scenario, validated,
    /// and every one of `policies` built for it.
    pub fn cell(
        &self,
        name: &str,
        base: &Scenario,
        values: &[toml::Value],
        policies: &[String],
    ) -> Result<Cell, String> {
        let labels: Vec<(String, toml::Value)> =
            self.axes.iter().map(|a| a.name.clone()).zip(values.iter().cloned()).collect();
        let mut c = Cell { base: name.to_string(), labels, scenario: base.clone() };
        c.scenario = self.scenario(base, values).map_err(|e| format!("cell {}: {e}", c.label()))?;
        c.scenario.validate(Path::new(&c.label())).map_err(|e| format!("cell {}: {e}", c.label()))?;
        for p in policies {
            PolicySpec::new(p, &c.scenario).map_err(|e| format!("cell {}: {e}", c.label()))?;
        }
        Ok(c)
    }
}

/// Whether axis value `v` meets `cond` (checked: min and max only on numbers).
fn meets(cond: &Condition, v: &toml::Value) -> bool {
    let x = number(v);
    cond.min.is_none_or(|m| x.is_some_and(|x| x >= m))
        && cond.max.is_none_or(|m| x.is_some_and(|x| x <= m))
        && cond.one_of.as_ref().is_none_or(|list| list.contains(v))
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

/// Reads the base scenario a sweep file names (a file relative to the sweep file, or
/// [`EMBEDDED`]); the error says why not.
pub type Loader<'a> = dyn Fn(&str) -> Result<Scenario, String> + 'a;

/// The loader of `coopnav sweep`: [`EMBEDDED`] or a file relative to the sweep file `file`.
pub fn from_disk(file: &Path) -> impl Fn(&str) -> Result<Scenario, String> + '_ {
    move |name: &str| {
        if name == EMBEDDED {
            return Scenario::parse(EXAMPLE, Path::new("<embedded default>")).map_err(|e| e.to_string());
        }
        let path: PathBuf = file.parent().unwrap_or(Path::new("")).join(name);
        read_scenario_text(&path, false).and_then(|text| Scenario::parse(&text, &path)).map_err(|e| e.to_string())
    }
}

/// Checks the sweep read from `file` and expands its full form, reading its base scenarios
/// from disk (`allow_large`: the cell count's limit is lifted).
pub fn expand(sweep: &SweepFile, file: &Path, allow_large: bool) -> Result<Expansion, SweepFileError> {
    expand_with(sweep, file, Form::Full, allow_large, &from_disk(file))
}

/// A base scenario as checked: its name, the scenario, per axis its values (None: the axis's
/// own) and where those were written.
struct Loaded {
    name: String,
    scenario: Scenario,
    own: BTreeMap<String, (String, Vec<toml::Value>)>,
}

/// One axis, checked.
struct CheckedAxis {
    rule: AxisRule,
    /// The axis's own values (None: every base scenario gives its own).
    values: Option<Vec<toml::Value>>,
    index: usize,
}

/// Checks the sweep read from `file` and expands its `form`, reading base scenarios with `load`.
pub fn expand_with(
    sweep: &SweepFile,
    file: &Path,
    form: Form,
    allow_large: bool,
    load: &Loader,
) -> Result<Expansion, SweepFileError> {
    let invalid = |problems| SweepFileError::Invalid { file: file.to_path_buf(), problems };
    let mut problems = Vec::new();
    if sweep.runs == 0 {
        problems.push("runs = 0: allowed at least 1".to_string());
    }
    check_policies(&sweep.policies, &mut problems);
    let loaded = load_bases(sweep, load, &mut problems);
    let axes = check_axes(sweep, &mut problems);
    let bases = base_values(sweep, &axes, &loaded, &mut problems);
    let conditionals = check_conditionals(sweep, &axes, &bases, &mut problems);
    check_overlays(sweep, &loaded, &mut problems);
    let (runs, last, bases) = select_form(sweep, form, &axes, bases, &mut problems);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    let count: f64 = bases.iter().map(|b| b.values.iter().map(|v| v.len() as f64).product::<f64>()).sum();
    let estimate = Estimate::new("sweep cells", "scenarios x values of every [[axis]]", count, MAX_POINTS);
    limits::check([estimate], allow_large)?;
    let rules = Rules { axes: axes.into_iter().map(|a| a.rule).collect(), conditionals, last };
    let mut cells = Vec::new();
    for b in &bases {
        for choice in combinations(&b.values) {
            match rules.cell(&b.name, &b.scenario, &choice, &sweep.policies) {
                Ok(c) => cells.push(c),
                Err(p) => problems.push(p),
            }
        }
    }
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    Ok(Expansion { axes: rules.axis_names(), cells, policies: sweep.policies.clone(), runs, form, bases, rules })
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

/// The base scenarios, read and validated, in file order.
fn load_bases(sweep: &SweepFile, load: &Loader, problems: &mut Vec<String>) -> Vec<Loaded> {
    match (sweep.scenarios.is_empty(), sweep.bases.is_empty()) {
        (true, true) => problems.push(format!(
            "scenarios = []: give at least one closed-loop scenario file (or \"{EMBEDDED}\"), or [[scenario]] tables"
        )),
        (false, false) => problems.push("give either scenarios = [...] or [[scenario]] tables, not both".to_string()),
        _ => {}
    }
    let mut out: Vec<Loaded> = Vec::new();
    let short = sweep.scenarios.iter().enumerate().map(|(i, name)| {
        (
            format!("scenarios[{i}] = \"{name}\""),
            name.clone(),
            name.as_str(),
            BTreeMap::new(),
            format!("scenarios[{i}]"),
        )
    });
    let long = sweep.bases.iter().enumerate().map(|(i, b)| {
        let own = b.values.iter().map(|(k, v)| (k.clone(), (format!("scenario[{i}].values.{k}"), v.clone()))).collect();
        (
            format!("scenario[{i}].file = \"{}\"", b.file),
            b.name().to_string(),
            b.file.as_str(),
            own,
            format!("scenario[{i}]"),
        )
    });
    for (what, name, file, own, place) in short.chain(long) {
        if out.iter().any(|o| o.name == name) {
            problems.push(format!("{place}: a second base scenario named \"{name}\" (give each its own name)"));
        }
        match load(file) {
            Ok(scenario) => out.push(Loaded { name, scenario, own }),
            Err(e) => problems.push(format!("{what}: {e}")),
        }
    }
    out
}

/// The patch that sets `path` to `value`: nested tables down to the key.
fn patch(path: &str, value: toml::Value) -> toml::Value {
    path.rsplit('.').fold(value, |inner, key| {
        let mut t = toml::Table::new();
        t.insert(key.to_string(), inner);
        toml::Value::Table(t)
    })
}

fn check_axes(sweep: &SweepFile, problems: &mut Vec<String>) -> Vec<CheckedAxis> {
    let mut out: Vec<CheckedAxis> = Vec::new();
    let mut overlay_axes = 0;
    let given_by_every_base = |name: &str| {
        !sweep.bases.is_empty() && sweep.scenarios.is_empty() && sweep.bases.iter().all(|b| b.values.contains_key(name))
    };
    for (i, axis) in sweep.axes.iter().enumerate() {
        let checked = match axis {
            Axis { path: Some(path), values, overlays: None, name } => {
                let name = name.clone().unwrap_or_else(|| path.clone());
                match values {
                    Some(v) if v.is_empty() => {
                        problems.push(format!("axis[{i}].values = []: give at least one value"));
                        None
                    }
                    None if !given_by_every_base(&name) => {
                        problems.push(format!(
                            "axis[{i}]: path needs its values (values = [...], or values.{name} in every [[scenario]])"
                        ));
                        None
                    }
                    _ => Some(CheckedAxis {
                        rule: AxisRule { name, setter: Setter::Path(path.clone()) },
                        values: values.clone(),
                        index: i,
                    }),
                }
            }
            Axis { path: None, values: None, overlays: Some(names), name } => {
                overlay_axes += 1;
                let default = if overlay_axes == 1 { "overlay".to_string() } else { format!("overlay{overlay_axes}") };
                let name = name.clone().unwrap_or(default);
                if names.is_empty() {
                    problems.push(format!("axis[{i}].overlays = []: give at least one overlay name"));
                    None
                } else {
                    let values: Vec<toml::Value> = names.iter().map(|n| toml::Value::String(n.clone())).collect();
                    let before = problems.len();
                    check_overlay_names(&format!("axis[{i}].overlays"), &values, sweep, problems);
                    (problems.len() == before).then(|| CheckedAxis {
                        rule: AxisRule { name, setter: Setter::Overlays(sweep.overlays.clone()) },
                        values: Some(values),
                        index: i,
                    })
                }
            }
            _ => {
                problems.push(format!("axis[{i}]: give either path and values, or overlays"));
                None
            }
        };
        if let Some(c) = checked {
            if RESERVED_NAMES.contains(&c.rule.name.as_str()) {
                problems.push(if axis.name.is_some() {
                    format!(
                        "axis[{i}].name = \"{}\": a column of the results tables already has that name (give another)",
                        c.rule.name
                    )
                } else {
                    format!(
                        "axis[{i}].path = \"{}\": a column of the results tables already has that name (give the axis a name)",
                        c.rule.name
                    )
                });
            }
            if out.iter().any(|o| o.rule.name == c.rule.name) {
                problems.push(format!("axis[{i}].path = \"{}\": already an axis", c.rule.name));
            }
            out.push(c);
        }
    }
    out
}

/// Each of `values` (at `place`, `place[j]` each) names an `[overlay.NAME]`.
fn check_overlay_names(place: &str, values: &[toml::Value], sweep: &SweepFile, problems: &mut Vec<String>) {
    for (j, v) in values.iter().enumerate() {
        problems.extend(overlay_name_problem(&format!("{place}[{j}]"), v, sweep));
    }
}

/// Why `v` (at `place`) does not name an `[overlay.NAME]`, if it does not.
fn overlay_name_problem(place: &str, v: &toml::Value, sweep: &SweepFile) -> Option<String> {
    if v.as_str().is_some_and(|n| sweep.overlays.contains_key(n)) {
        return None;
    }
    let known: Vec<&str> = sweep.overlays.keys().map(String::as_str).collect();
    let shown = v.as_str().map_or_else(|| v.to_string(), |n| format!("\"{n}\""));
    Some(format!(
        "{place} = {shown}: no [overlay.{}] (allowed: {})",
        v.as_str().unwrap_or("NAME"),
        if known.is_empty() { "none defined".to_string() } else { known.join(", ") }
    ))
}

/// Checks `values` of path axis `path` against base scenario `b`; `place` names where they
/// are written.
fn check_path_values(place: &str, path: &str, values: &[toml::Value], b: &Loaded, problems: &mut Vec<String>) {
    if let Err(why) = field_exists(&b.scenario, path, &values[0]) {
        problems.push(format!("{place}: path \"{path}\": {why} in scenario {}", b.name));
        return;
    }
    for (j, v) in values.iter().enumerate() {
        if let Err(e) = set_field(&b.scenario, path, v.clone()) {
            problems.push(format!("{place}[{j}] = {v}: {} (scenario {})", e.trim(), b.name));
        }
    }
}

/// Every base scenario with its values of every axis (its own where it gives them), checked.
fn base_values(
    sweep: &SweepFile,
    axes: &[CheckedAxis],
    loaded: &[Loaded],
    problems: &mut Vec<String>,
) -> Vec<BaseCells> {
    let names: Vec<&str> = axes.iter().map(|a| a.rule.name.as_str()).collect();
    let mut out = Vec::new();
    for b in loaded {
        for (key, (place, _)) in &b.own {
            if !names.contains(&key.as_str()) {
                problems.push(format!("{place}: no axis named {key} (axes: {})", axis_list(&names)));
            }
        }
        let mut values = Vec::new();
        for a in axes {
            match (b.own.get(&a.rule.name), &a.values) {
                (Some((place, own)), _) => {
                    check_values(place, &a.rule, own, b, sweep, problems);
                    values.push(own.clone());
                }
                (None, Some(v)) => values.push(v.clone()),
                (None, None) => values.push(Vec::new()),
            }
        }
        out.push(BaseCells { name: b.name.clone(), scenario: b.scenario.clone(), values });
    }
    // The axes' own values, against every base scenario that uses them.
    for a in axes {
        let Setter::Path(path) = &a.rule.setter else { continue };
        let Some(values) = &a.values else { continue };
        for b in loaded.iter().filter(|b| !b.own.contains_key(&a.rule.name)) {
            if let Err(why) = field_exists(&b.scenario, path, &values[0]) {
                problems.push(format!("axis[{}].path = \"{path}\": {why} in scenario {}", a.index, b.name));
                continue;
            }
            for (j, v) in values.iter().enumerate() {
                if let Err(e) = set_field(&b.scenario, path, v.clone()) {
                    problems.push(format!("axis[{}].values[{j}] = {v}: {} (scenario {})", a.index, e.trim(), b.name));
                }
            }
        }
    }
    out
}

/// Checks a base scenario's own `values` (at `place`) of the axis `rule`.
fn check_values(
    place: &str,
    rule: &AxisRule,
    values: &[toml::Value],
    b: &Loaded,
    sweep: &SweepFile,
    problems: &mut Vec<String>,
) {
    if values.is_empty() {
        problems.push(format!("{place} = []: give at least one value"));
        return;
    }
    match &rule.setter {
        Setter::Path(path) => check_path_values(place, path, values, b, problems),
        Setter::Overlays(_) => check_overlay_names(place, values, sweep, problems),
    }
}

fn axis_list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

/// One step of a path: a table's key, or an array's index (`curves[1]`).
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// The steps of `path` (`comms.tau`, `comms.success.curves[1].p_a`), or why it is not a path.
fn steps(path: &str) -> Result<Vec<Step>, String> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let end = part.find('[').unwrap_or(part.len());
        if end == 0 {
            return Err(format!("`{part}`: a path is keys joined by dots, each key followed by any [N] indices"));
        }
        out.push(Step::Key(part[..end].to_string()));
        let mut rest = &part[end..];
        while !rest.is_empty() {
            let index = rest.strip_prefix('[').and_then(|r| r.split_once(']'));
            let Some((n, after)) = index.and_then(|(n, after)| n.parse::<usize>().ok().map(|n| (n, after))) else {
                return Err(format!("`{part}`: an index is written [N], N a whole number from 0"));
            };
            out.push(Step::Index(n));
            rest = after;
        }
    }
    Ok(out)
}

/// `scenario` with the field at `path` set to `value`. A path without indices is a patch merged
/// over the scenario; one with indices sets the array entry it names (every other entry kept).
fn set_field(scenario: &Scenario, path: &str, value: toml::Value) -> Result<Scenario, String> {
    if !path.contains('[') {
        return overlay(scenario, patch(path, value));
    }
    let steps = steps(path)?;
    let mut tree = toml::Value::try_from(scenario).map_err(|e| e.to_string())?;
    let mut node = &mut tree;
    let mut walked = String::new();
    for (k, step) in steps.iter().enumerate() {
        let last = k + 1 == steps.len();
        match (step, node) {
            (Step::Key(key), toml::Value::Table(table)) => {
                if last {
                    table.insert(key.clone(), value);
                    break;
                }
                node = table.entry(key.clone()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
                walked += &if walked.is_empty() { key.clone() } else { format!(".{key}") };
            }
            (Step::Index(i), toml::Value::Array(items)) => {
                let len = items.len();
                let slot = items.get_mut(*i).ok_or_else(|| format!("{walked} has {len} entries, none at [{i}]"))?;
                if last {
                    *slot = value;
                    break;
                }
                node = slot;
                walked += &format!("[{i}]");
            }
            (Step::Key(_), _) => return Err(format!("{walked} is a value, not a table")),
            (Step::Index(i), _) => return Err(format!("{walked} is not an array (an index [{i}] needs one)")),
        }
    }
    tree.try_into().map_err(|e: toml::de::Error| e.to_string())
}

/// Whether `path` names a field of `base` (see the module doc), or why not.
fn field_exists(base: &Scenario, path: &str, value: &toml::Value) -> Result<(), String> {
    let tree = toml::Value::try_from(base).map_err(|e| e.to_string())?;
    let mut node = &tree;
    let mut walked = String::new();
    for step in steps(path)? {
        match step {
            Step::Key(key) => {
                let toml::Value::Table(table) = node else {
                    return Err(format!("{walked} is a value, not a table"));
                };
                match table.get(&key) {
                    Some(next) => node = next,
                    None if set_field(base, path, value.clone()).is_ok() => return Ok(()),
                    None => {
                        let keys: Vec<&str> = table.keys().map(String::as_str).collect();
                        let place =
                            if walked.is_empty() { "at the top level".to_string() } else { format!("in [{walked}]") };
                        return Err(format!("no field `{key}` {place} (allowed: {})", keys.join(", ")));
                    }
                }
                walked += &if walked.is_empty() { key } else { format!(".{key}") };
            }
            Step::Index(i) => {
                let toml::Value::Array(items) = node else {
                    return Err(format!("{walked} is not an array (an index [{i}] needs one)"));
                };
                node = items.get(i).ok_or_else(|| format!("{walked} has {} entries, none at [{i}]", items.len()))?;
                walked += &format!("[{i}]");
            }
        }
    }
    if node.is_table() {
        return Err(format!("{path} is a table, not a value (name one of its keys)"));
    }
    Ok(())
}

/// The `[[conditional]]` tables, checked: each names an overlay, and each condition an axis, is
/// a table of `min`, `max` and `in` (min and max only where the axis's values are numbers).
fn check_conditionals(
    sweep: &SweepFile,
    axes: &[CheckedAxis],
    bases: &[BaseCells],
    problems: &mut Vec<String>,
) -> Vec<ConditionalRule> {
    let names: Vec<&str> = axes.iter().map(|a| a.rule.name.as_str()).collect();
    let mut out = Vec::new();
    for (k, c) in sweep.conditionals.iter().enumerate() {
        let before = problems.len();
        let name = toml::Value::String(c.overlay.clone());
        problems.extend(overlay_name_problem(&format!("conditional[{k}].overlay"), &name, sweep));
        let mut when = Vec::new();
        for (axis, value) in &c.when {
            let place = format!("conditional[{k}].when.{axis}");
            let Some(index) = names.iter().position(|n| n == axis) else {
                problems.push(format!("{place}: no axis named {axis} (axes: {})", axis_list(&names)));
                continue;
            };
            let cond: Condition = match value.clone().try_into() {
                Ok(cond) => cond,
                Err(e) => {
                    let e: toml::de::Error = e;
                    problems.push(format!(
                        "{place} = {value}: {} (allowed: a table of min, max and in, e.g. {{ min = 6 }})",
                        e.message().trim()
                    ));
                    continue;
                }
            };
            if cond.min.is_none() && cond.max.is_none() && cond.one_of.is_none() {
                problems.push(format!("{place} = {{}}: give min, max or in"));
                continue;
            }
            if let (Some(lo), Some(hi)) = (cond.min, cond.max) {
                if lo > hi {
                    problems.push(format!("{place}: min = {lo} is above max = {hi}: no value meets it"));
                }
            }
            if cond.min.is_some() || cond.max.is_some() {
                let text =
                    bases.iter().flat_map(|b| b.values.get(index).into_iter().flatten()).find(|v| number(v).is_none());
                if let Some(v) = text {
                    problems.push(format!(
                        "{place}: min and max compare numbers, and axis {axis} has the value {v} (use in = [...])"
                    ));
                }
            }
            when.push((index, cond));
        }
        if problems.len() == before {
            let what = format!("conditional[{k}] (overlay.{})", c.overlay);
            out.push(ConditionalRule { what, when, patch: sweep.overlays[&c.overlay].clone() });
        }
    }
    out
}

/// Every overlay reads over every base scenario, and is used by an axis, a conditional or the
/// reduced form.
fn check_overlays(sweep: &SweepFile, bases: &[Loaded], problems: &mut Vec<String>) {
    let named = |name: &String| {
        let listed = |v: &Vec<toml::Value>| v.iter().any(|x| x.as_str() == Some(name));
        sweep.axes.iter().any(|a| a.overlays.as_ref().is_some_and(|o| o.contains(name)))
            || sweep.bases.iter().any(|b| b.values.values().any(listed))
            || sweep.conditionals.iter().any(|c| &c.overlay == name)
            || sweep.reduced.as_ref().is_some_and(|r| {
                r.overlay.as_ref() == Some(name) || r.bases.iter().any(|b| b.values.values().any(listed))
            })
    };
    for (name, table) in &sweep.overlays {
        if !named(name) {
            problems.push(format!(
                "overlay.{name}: no axis uses it (name it in an axis: overlays = [\"{name}\"], a [[conditional]] or \
                 [reduced] overlay)"
            ));
        }
        for b in bases {
            if let Err(e) = overlay(&b.scenario, toml::Value::Table(table.clone())) {
                problems.push(format!("overlay.{name}: {} (scenario {})", e.trim(), b.name));
            }
        }
    }
}

/// The form's runs, its last overlay and its base scenarios with their values.
fn select_form(
    sweep: &SweepFile,
    form: Form,
    axes: &[CheckedAxis],
    bases: Vec<BaseCells>,
    problems: &mut Vec<String>,
) -> (usize, Option<(String, toml::Table)>, Vec<BaseCells>) {
    let Some(reduced) = &sweep.reduced else {
        if form == Form::Reduced {
            problems.push("no [reduced] table: the file has no reduced form".to_string());
        }
        return (sweep.runs, None, bases);
    };
    // The reduced form is checked whichever form is expanded.
    if reduced.runs == Some(0) {
        problems.push("reduced.runs = 0: allowed at least 1".to_string());
    }
    let mut last = None;
    if let Some(name) = &reduced.overlay {
        let before = problems.len();
        problems.extend(overlay_name_problem("reduced.overlay", &toml::Value::String(name.clone()), sweep));
        if problems.len() == before {
            last = Some((format!("reduced.overlay (overlay.{name})"), sweep.overlays[name].clone()));
        }
    }
    let names: Vec<&str> = axes.iter().map(|a| a.rule.name.as_str()).collect();
    let known: Vec<&str> = bases.iter().map(|b| b.name.as_str()).collect();
    let mut kept = Vec::new();
    for (i, r) in reduced.bases.iter().enumerate() {
        let Some(b) = bases.iter().find(|b| b.name == r.name) else {
            problems.push(format!(
                "reduced.scenario[{i}].name = \"{}\": no such base scenario (allowed: {})",
                r.name,
                known.join(", ")
            ));
            continue;
        };
        if reduced.bases[..i].iter().any(|o| o.name == r.name) {
            problems.push(format!("reduced.scenario[{i}].name = \"{}\": listed twice", r.name));
        }
        let mut values = b.values.clone();
        for (key, own) in &r.values {
            let place = format!("reduced.scenario[{i}].values.{key}");
            let Some(k) = names.iter().position(|n| n == key) else {
                problems.push(format!("{place}: no axis named {key} (axes: {})", axis_list(&names)));
                continue;
            };
            let loaded = Loaded { name: b.name.clone(), scenario: b.scenario.clone(), own: BTreeMap::new() };
            check_values(&place, &axes[k].rule, own, &loaded, sweep, problems);
            values[k] = own.clone();
        }
        kept.push(BaseCells { values, ..b.clone() });
    }
    match form {
        Form::Full => (sweep.runs, None, bases),
        Form::Reduced => {
            let kept = if reduced.bases.is_empty() { bases } else { kept };
            (reduced.runs.unwrap_or(sweep.runs), last, kept)
        }
    }
}

/// Every choice of one value per axis, the last axis fastest.
fn combinations(values: &[Vec<toml::Value>]) -> Vec<Vec<toml::Value>> {
    values.iter().fold(vec![Vec::new()], |acc, axis| {
        acc.into_iter()
            .flat_map(|prefix| axis.iter().map(move |v| [prefix.clone(), vec![v.clone()]].concat()))
            .collect()
    })
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
