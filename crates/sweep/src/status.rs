//! Where each shard of a plan stands: done (every run finished, none failed), failed (finished,
//! with failed runs), running (its journal is locked by a live process), interrupted (a journal
//! no process holds: `sweep run` resumes it) or missing (never started).

use crate::error::SweepError;
use crate::plan::Plan;
use crate::shard::{finished_path, journal_path, read_finished, read_frames, try_lock, Outcome};

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum State {
    Done { runs: usize },
    Failed { runs: usize, failed: usize },
    Running { journaled: usize, runs: usize },
    Interrupted { journaled: usize, runs: usize },
    Missing { runs: usize },
}

impl State {
    pub fn word(&self) -> &'static str {
        match self {
            State::Done { .. } => "done",
            State::Failed { .. } => "failed",
            State::Running { .. } => "running",
            State::Interrupted { .. } => "interrupted",
            State::Missing { .. } => "missing",
        }
    }
}

impl std::fmt::Display for State {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            State::Done { runs } => write!(f, "done ({runs} runs)"),
            State::Failed { runs, failed } => write!(f, "failed ({failed} of {runs} runs failed)"),
            State::Running { journaled, runs } => write!(f, "running ({journaled} of {runs} runs finished)"),
            State::Interrupted { journaled, runs } => {
                write!(f, "interrupted ({journaled} of {runs} runs finished; `sweep run` resumes it)")
            }
            State::Missing { runs } => write!(f, "missing ({runs} runs, not started)"),
        }
    }
}

/// The state of every shard, in shard order.
pub fn status(plan: &Plan) -> Result<Vec<State>, SweepError> {
    (0..plan.inputs.shards).map(|s| shard_state(plan, s)).collect()
}

fn shard_state(plan: &Plan, s: usize) -> Result<State, SweepError> {
    let runs = plan.shard_runs(s)?.len();
    if let Some(records) = read_finished(plan, s)? {
        let failed = records.iter().filter(|r| matches!(r.outcome, Outcome::Failed(_))).count();
        return Ok(if failed == 0 { State::Done { runs } } else { State::Failed { runs, failed } });
    }
    let path = journal_path(plan, s);
    let Ok(file) = std::fs::File::open(&path) else {
        return Ok(State::Missing { runs });
    };
    let journaled = std::fs::read(&path).map(|b| read_frames(&b).records.len()).unwrap_or(0);
    let free = try_lock(&file).map_err(crate::error::io(&path))?;
    drop(file);
    debug_assert!(finished_path(plan, s) != path);
    Ok(if free { State::Interrupted { journaled, runs } } else { State::Running { journaled, runs } })
}

/// The states as a table, with a last line of totals.
pub fn status_table(states: &[State]) -> String {
    let mut out = String::new();
    let w = states.len().saturating_sub(1).to_string().len();
    for (s, state) in states.iter().enumerate() {
        out += &format!("shard {s:>w$}  {state}\n");
    }
    let count = |word| states.iter().filter(|s| s.word() == word).count();
    out += &format!(
        "{} shards: {} done, {} failed, {} running, {} interrupted, {} missing\n",
        states.len(),
        count("done"),
        count("failed"),
        count("running"),
        count("interrupted"),
        count("missing")
    );
    out
}
