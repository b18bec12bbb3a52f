//! The plan directory `coopnav sweep plan` writes, and reading it back.
//!
//! ```text
//! DIR/manifest.json           coopnav's manifest; its inputs: the sweep file's text, policies, runs,
//!                             axes, shards, every cell's base and axis values, and the plan's digest
//! DIR/sweep.toml              the sweep file as read
//! DIR/cells/cell-NNNN.toml    each cell's whole scenario (after defaults and axes): a scenario file
//!                             `coopnav simulate` reads
//! DIR/shards/shard-NNN.json   the run ids of each shard
//! DIR/results/                shard results (`sweep run`), see [`crate::shard`]
//! DIR/merged/                 the comparison and tables (`sweep merge`), see [`crate::merge`]
//! ```
//!
//! Run `id` is run `id % runs` of policy `(id / runs) % policies` in cell `id / (runs × policies)`
//! (the order of [`crate::expand`]); shard `s` of `S` holds the ids with `id % S == s`, so every
//! shard gets a share of every cell and policy.
//!
//! The digest (FNV-1a, 64 bits, of the version, policies, runs, axes, shards and every cell file)
//! ties shard and result files to their plan: a plan written by another coopnav version, one
//! edited since it was written, or a shard file of another plan is refused.

use crate::error::{io, SweepError};
use crate::expand::{Cell, Expansion, Form};
use coopnav_sim::experiments::SWEEP_REPORTS;
use coopnav_sim::output::{Manifest, RunDir, MANIFEST};
use coopnav_sim::scenario::Scenario;
use serde::{Deserialize, Serialize};
use std::hash::Hasher;
use std::path::{Path, PathBuf};

/// The coopnav version that writes and reads plans.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// What `manifest.json` holds as its inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanInputs {
    /// The sweep file as named on the command line, and its text.
    pub sweep_file: String,
    pub sweep: String,
    pub digest: String,
    pub shards: usize,
    pub policies: Vec<String>,
    pub runs: usize,
    pub axes: Vec<String>,
    pub cells: Vec<CellEntry>,
    /// Whether this is the sweep file's reduced form (`sweep plan --reduced`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reduced: bool,
}

/// One cell as the manifest lists it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellEntry {
    /// Its scenario file, relative to the plan directory.
    pub file: String,
    pub base: String,
    pub labels: Vec<(String, toml::Value)>,
}

/// A shard file: the run ids one `sweep run --shard I` runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardFile {
    pub tool: String,
    pub version: String,
    pub digest: String,
    pub shard: usize,
    pub shards: usize,
    pub runs: Vec<usize>,
}

/// Where one run sits in the plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunId {
    pub cell: usize,
    pub policy: usize,
    pub run: usize,
}

/// A plan directory, read and checked.
#[derive(Debug, Clone)]
pub struct Plan {
    pub dir: PathBuf,
    pub inputs: PlanInputs,
    pub cells: Vec<Cell>,
}

fn width(count: usize, min: usize) -> usize {
    count.saturating_sub(1).to_string().len().max(min)
}

/// The file of cell `k` of `count`, relative to the plan directory.
pub fn cell_file(k: usize, count: usize) -> String {
    format!("cells/cell-{k:0w$}.toml", w = width(count, 4))
}

/// The file of shard `s` of `count`, relative to the plan directory.
pub fn shard_file(s: usize, count: usize) -> String {
    format!("shards/shard-{s:0w$}.json", w = width(count, 3))
}

/// A cell's scenario file: a comment naming the cell, then the scenario.
fn cell_text(c: &Cell) -> Result<String, String> {
    let body = toml::to_string(&c.scenario).map_err(|e| e.to_string())?;
    Ok(format!("# sweep cell: {}\n{body}", c.label()))
}

fn digest(inputs: &PlanInputs, cell_texts: &[String]) -> String {
    let mut h = fnv::FnvHasher::default();
    let head = serde_json::json!([VERSION, inputs.shards, inputs.policies, inputs.runs, inputs.axes, inputs.cells]);
    h.write(head.to_string().as_bytes());
    for t in cell_texts {
        h.write(&(t.len() as u64).to_le_bytes());
        h.write(t.as_bytes());
    }
    format!("{:016x}", h.finish())
}

/// Writes the plan of `e` (read from `sweep_file`, text `sweep_text`) with `shards` shards into
/// `target` (replaced only with `force`, never when it holds one of `inputs`).
#[allow(clippy::too_many_arguments)]
pub fn write_plan(
    e: &Expansion,
    sweep_file: &Path,
    sweep_text: &str,
    shards: usize,
    target: &Path,
    force: bool,
    inputs: &[&Path],
    command: &str,
) -> Result<PathBuf, SweepError> {
    if shards == 0 {
        return Err(SweepError::Invalid {
            file: sweep_file.to_path_buf(),
            problems: vec!["--shards 0: allowed at least 1".into()],
        });
    }
    let dir = RunDir::create_for(target, force, inputs)?;
    let n = e.cells.len();
    let mut texts = Vec::with_capacity(n);
    for (k, c) in e.cells.iter().enumerate() {
        let text = cell_text(c).map_err(|m| SweepError::Corrupt { path: cell_file(k, n).into(), message: m })?;
        // The file must read back as the very scenario the sweep expanded.
        let back = Scenario::parse(&text, Path::new(&cell_file(k, n)));
        if back.as_ref().ok() != Some(&c.scenario) {
            let message = format!("the cell's scenario does not read back as written: {:?}", back.err());
            return Err(SweepError::Corrupt { path: cell_file(k, n).into(), message });
        }
        texts.push(text);
    }
    let mut plan = PlanInputs {
        sweep_file: sweep_file.display().to_string(),
        sweep: sweep_text.to_string(),
        digest: String::new(),
        shards,
        policies: e.policies.clone(),
        runs: e.runs,
        axes: e.axes.clone(),
        cells: e
            .cells
            .iter()
            .enumerate()
            .map(|(k, c)| CellEntry { file: cell_file(k, n), base: c.base.clone(), labels: c.labels.clone() })
            .collect(),
        reduced: e.form == Form::Reduced,
    };
    plan.digest = digest(&plan, &texts);
    let inputs_json = serde_json::to_value(&plan)
        .map_err(|e| SweepError::Corrupt { path: MANIFEST.into(), message: e.to_string() })?;
    dir.write_json(MANIFEST, &Manifest::new(command, None, inputs_json))?;
    dir.write_text("sweep.toml", sweep_text)?;
    for (entry, text) in plan.cells.iter().zip(&texts) {
        dir.write_text(&entry.file, text)?;
    }
    let total = n * e.policies.len() * e.runs;
    for s in 0..shards {
        let file = ShardFile {
            tool: "coopnav".into(),
            version: VERSION.into(),
            digest: plan.digest.clone(),
            shard: s,
            shards,
            runs: (s..total).step_by(shards).collect(),
        };
        dir.write_json(&shard_file(s, shards), &file)?;
    }
    Ok(dir.finish()?)
}

impl Plan {
    /// Reads and checks the plan in `dir` (see the module doc for what is refused).
    pub fn open(dir: &Path) -> Result<Plan, SweepError> {
        let not_a_plan = |reason: String| SweepError::NotAPlan { dir: dir.to_path_buf(), reason };
        let manifest_path = dir.join(MANIFEST);
        let text =
            std::fs::read_to_string(&manifest_path).map_err(|e| not_a_plan(format!("cannot read {MANIFEST}: {e}")))?;
        let manifest: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| not_a_plan(format!("{MANIFEST} is not JSON: {e}")))?;
        if manifest.get("tool").and_then(|t| t.as_str()) != Some("coopnav") {
            return Err(not_a_plan(format!("its {MANIFEST} was not written by coopnav")));
        }
        let found = manifest.get("version").and_then(|v| v.as_str()).unwrap_or("(none)");
        let inputs = manifest.get("inputs").filter(|i| i.get("sweep").is_some() && i.get("digest").is_some());
        let Some(inputs) = inputs else {
            return Err(not_a_plan(format!("its {MANIFEST} is not a sweep plan's")));
        };
        if found != VERSION {
            return Err(SweepError::OtherVersion { dir: dir.to_path_buf(), found: found.into(), ours: VERSION.into() });
        }
        let inputs: PlanInputs = serde_json::from_value(inputs.clone())
            .map_err(|e| SweepError::Corrupt { path: manifest_path.clone(), message: e.to_string() })?;
        let mut texts = Vec::new();
        let mut cells = Vec::new();
        for entry in &inputs.cells {
            let path = dir.join(&entry.file);
            let text = std::fs::read_to_string(&path).map_err(io(&path))?;
            let scenario = Scenario::parse(&text, &path)
                .map_err(|e| SweepError::Corrupt { path: path.clone(), message: e.to_string() })?;
            cells.push(Cell { base: entry.base.clone(), labels: entry.labels.clone(), scenario });
            texts.push(text);
        }
        let ours = digest(&inputs, &texts);
        if ours != inputs.digest {
            return Err(SweepError::Corrupt {
                path: dir.to_path_buf(),
                message: format!(
                    "the plan was changed after it was written (digest {ours}, the manifest says {}): plan it again",
                    inputs.digest
                ),
            });
        }
        Ok(Plan { dir: dir.to_path_buf(), inputs, cells })
    }

    /// Runs in the whole plan.
    pub fn total_runs(&self) -> usize {
        self.cells.len() * self.inputs.policies.len() * self.inputs.runs
    }

    pub fn locate(&self, id: usize) -> RunId {
        let (p, r) = (self.inputs.policies.len(), self.inputs.runs);
        RunId { cell: id / (p * r), policy: (id / r) % p, run: id % r }
    }

    /// The run ids of shard `s`, from its shard file (checked against this plan).
    pub fn shard_runs(&self, s: usize) -> Result<Vec<usize>, SweepError> {
        let shards = self.inputs.shards;
        if s >= shards {
            return Err(SweepError::NoShard { dir: self.dir.clone(), shard: s, shards });
        }
        let path = self.dir.join(shard_file(s, shards));
        let text = std::fs::read_to_string(&path).map_err(io(&path))?;
        let file: ShardFile = serde_json::from_str(&text)
            .map_err(|e| SweepError::Corrupt { path: path.clone(), message: e.to_string() })?;
        if file.digest != self.inputs.digest {
            return Err(SweepError::OtherPlan { path, found: file.digest, ours: self.inputs.digest.clone() });
        }
        let expected: Vec<usize> = (s..self.total_runs()).step_by(shards).collect();
        if file.shard != s || file.shards != shards || file.runs != expected {
            return Err(SweepError::Corrupt { path, message: format!("not the run list of shard {s} of {shards}") });
        }
        Ok(file.runs)
    }
}

/// `coopnav sweep plan`: checks the sweep file `file` (text `text`) whole, estimates its work
/// against the limits (lifted by `allow_large`), and writes the plan of its full form into
/// `target`.
pub fn plan_file(
    file: &Path,
    text: &str,
    shards: usize,
    target: &Path,
    force: bool,
    allow_large: bool,
    command: &str,
) -> Result<(PathBuf, Expansion), SweepError> {
    plan_form(file, text, Form::Full, shards, target, force, allow_large, command)
}

/// [`plan_file`] of the sweep's `form` (`sweep plan --reduced`: its `[reduced]` table).
#[allow(clippy::too_many_arguments)]
pub fn plan_form(
    file: &Path,
    text: &str,
    form: Form,
    shards: usize,
    target: &Path,
    force: bool,
    allow_large: bool,
    command: &str,
) -> Result<(PathBuf, Expansion), SweepError> {
    let sweep = crate::file::SweepFile::parse(text, file)?;
    if let Some(id) = sweep.report.as_ref().filter(|id| !SWEEP_REPORTS.contains(&id.as_str())) {
        let allowed = SWEEP_REPORTS.join(", ");
        let problems =
            vec![format!("report = \"{id}\": no reproduction reports from a sweep's runs (allowed: {allowed})")];
        return Err(SweepError::Invalid { file: file.to_path_buf(), problems });
    }
    let e = crate::expand::expand_with(&sweep, file, form, allow_large, &crate::expand::from_disk(file))?;
    coopnav_core::limits::check(crate::expand::work(&e), allow_large)?;
    let dir = file.parent().unwrap_or(Path::new(""));
    let bases: Vec<PathBuf> =
        sweep.scenario_files().into_iter().filter(|s| *s != crate::file::EMBEDDED).map(|s| dir.join(s)).collect();
    let mut inputs: Vec<&Path> = bases.iter().map(PathBuf::as_path).collect();
    inputs.push(file);
    let out = write_plan(&e, file, text, shards, target, force, &inputs, command)?;
    Ok((out, e))
}
