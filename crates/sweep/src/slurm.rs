//! `coopnav sweep slurm DIR`: the Slurm batch scripts that run a plan on a cluster, written into
//! `DIR/slurm/`: `shards.sbatch`, one `sbatch --array` task per shard (`sweep run DIR --shard
//! $SLURM_ARRAY_TASK_ID`, rayon on the task's CPUs); `merge.sbatch`, the merge; and `submit.sh`,
//! which submits the array and then the merge as a job that starts once every shard has succeeded
//! (`--dependency=afterok`). Each task's log, in `DIR/slurm/logs/`, opens with the node it ran on.
//!
//! Every file is written staged and renamed into place, and an existing one is replaced only with
//! `force` and only when coopnav wrote it (its second line is [`MARK`]).

use crate::error::{io, SweepError};
use crate::plan::{Plan, VERSION};
use coopnav_sim::output::write_file;
use std::path::{Path, PathBuf};

/// The second line of every script written here.
pub const MARK: &str = "# coopnav sweep slurm";

/// What the scripts ask of Slurm.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlurmSpec {
    /// The coopnav binary the tasks run (an absolute path the nodes can reach).
    pub coopnav: PathBuf,
    /// CPUs per shard task (rayon's threads).
    pub cpus_per_task: usize,
    pub partition: Option<String>,
    /// Wall-time limit per task, in Slurm's notation (`2:00:00`).
    pub time: Option<String>,
    /// Further `#SBATCH` options for both scripts, e.g. `--account=lab`.
    pub extra: Vec<String>,
}

/// `s` quoted for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

fn header(what: &str, spec: &SlurmSpec, options: &[String]) -> String {
    let mut out = format!("#!/bin/bash\n{MARK} (coopnav {VERSION}): {what}\n");
    let mut lines: Vec<String> = options.to_vec();
    lines.extend(spec.partition.iter().map(|p| format!("--partition={p}")));
    lines.extend(spec.time.iter().map(|t| format!("--time={t}")));
    lines.extend(spec.extra.iter().cloned());
    for l in lines {
        out += &format!("#SBATCH {l}\n");
    }
    out + "set -euo pipefail\n"
}

fn is_ours(head: &[u8]) -> bool {
    String::from_utf8_lossy(head).lines().nth(1).is_some_and(|l| l.starts_with(MARK))
}

/// The three scripts for `plan`: (file name, text).
pub fn scripts(plan: &Plan, spec: &SlurmSpec) -> Result<Vec<(&'static str, String)>, SweepError> {
    let dir = std::fs::canonicalize(&plan.dir).map_err(io(&plan.dir))?;
    let d = dir.display().to_string();
    let slurm = dir.join("slurm");
    let logs = slurm.join("logs").display().to_string();
    let coopnav = quote(&spec.coopnav.display().to_string());
    let n = plan.inputs.shards;
    let shards = header(
        &format!("the {n} shards of the sweep plan {d}, one array task each"),
        spec,
        &[
            "--job-name=coopnav-sweep".into(),
            format!("--array=0-{}", n - 1),
            format!("--cpus-per-task={}", spec.cpus_per_task.max(1)),
            format!("--chdir={d}"),
            format!("--output={logs}/shard-%a.out"),
        ],
    ) + &format!(
        "export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\"\n\
         echo \"coopnav sweep: shard ${{SLURM_ARRAY_TASK_ID}} on node ${{SLURMD_NODENAME:-$(hostname)}}\"\n\
         exec {coopnav} sweep run {} --shard \"${{SLURM_ARRAY_TASK_ID}}\"\n",
        quote(&d)
    );
    let merge = header(
        &format!("the merge of the sweep plan {d}, once every shard has run"),
        spec,
        &["--job-name=coopnav-sweep-merge".into(), format!("--chdir={d}"), format!("--output={logs}/merge.out")],
    ) + &format!(
        "echo \"coopnav sweep: merge on node ${{SLURMD_NODENAME:-$(hostname)}}\"\n\
         exec {coopnav} sweep merge {} --force\n",
        quote(&d)
    );
    let s = slurm.display().to_string();
    let submit = format!(
        "#!/bin/bash\n{MARK} (coopnav {VERSION}): submits the shards of {d} as an array, then their merge\n\
         set -euo pipefail\n\
         array=\"$(sbatch --parsable {})\"\n\
         array=\"${{array%%;*}}\"\n\
         merge=\"$(sbatch --parsable --dependency=afterok:\"$array\" {})\"\n\
         echo \"shards: job $array; merge: job ${{merge%%;*}} (starts once every shard has succeeded)\"\n",
        quote(&format!("{s}/shards.sbatch")),
        quote(&format!("{s}/merge.sbatch")),
    );
    Ok(vec![("shards.sbatch", shards), ("merge.sbatch", merge), ("submit.sh", submit)])
}

/// Writes the scripts into `DIR/slurm/` (and makes `DIR/slurm/logs/`); returns `submit.sh`.
pub fn write_scripts(plan: &Plan, spec: &SlurmSpec, force: bool) -> Result<PathBuf, SweepError> {
    let slurm = plan.dir.join("slurm");
    let logs = slurm.join("logs");
    std::fs::create_dir_all(&logs).map_err(io(&logs))?;
    let scripts = scripts(plan, spec)?;
    for (name, _) in &scripts {
        coopnav_sim::output::check_file_target(&slurm.join(name), force, is_ours, &[])?;
    }
    for (name, text) in &scripts {
        let path = slurm.join(name);
        write_file(&path, text.as_bytes(), force, is_ours, &[])?;
        set_executable(&path)?;
    }
    Ok(slurm.join("submit.sh"))
}

fn set_executable(path: &Path) -> Result<(), SweepError> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).map_err(io(path))
}
