//! The batch runner: prepares every (scenario, slot length) once, then runs scenarios ×
//! behaviours × repetitions in parallel (rayon), merging results in index order so the output is
//! bit-identical on any thread count. Repetition i of scenario s uses seed
//! run_seed(run_seed(base, s), i) for every behaviour (common random numbers).

use super::metrics::RunMetrics;
use super::prepare::{prepare, Prepared};
use super::scenario::ExperimentConfig;
use super::world::{self, WorldError};
use coopnav_acomms::{TlError, TransmissionLoss};
use coopnav_core::{run_seed, Bathymetry, BathymetryError};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum BatchError {
    #[error("experiment configuration: {0}")]
    Config(String),
    #[error(transparent)]
    Bathymetry(#[from] BathymetryError),
    #[error("transmission loss: {0}")]
    Tl(#[from] TlError),
    #[error(transparent)]
    World(#[from] WorldError),
}

/// Results of one (scenario, behaviour).
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    pub scenario: String,
    pub behaviour: String,
    pub control: bool,
    pub slot_len: f64,
    pub runs: usize,
    pub mean: RunMetrics,
    pub sd: RunMetrics,
}

#[derive(Debug, Clone, Serialize)]
pub struct ExperimentResult {
    /// Scenario-major, behaviours in configuration order.
    pub cells: Vec<Cell>,
}

impl ExperimentResult {
    pub fn cell(&self, scenario: &str, behaviour: &str) -> Option<&Cell> {
        self.cells.iter().find(|c| c.scenario == scenario && c.behaviour == behaviour)
    }
}

/// Runs the whole experiment; `progress(1)` after every run.
pub fn run_experiment(
    cfg: &ExperimentConfig,
    tl: &dyn TransmissionLoss,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ExperimentResult, BatchError> {
    cfg.validate().map_err(BatchError::Config)?;
    let bathy = Bathymetry::shelf(&cfg.shelf)?;
    let slot_lens = cfg.behaviours.iter().map(|b| world::slot_length(cfg, b)).collect::<Result<Vec<f64>, _>>()?;
    let mut keys: Vec<(usize, u64)> =
        (0..cfg.scenarios.len()).flat_map(|s| slot_lens.iter().map(move |l| (s, l.to_bits()))).collect();
    keys.sort_unstable();
    keys.dedup();
    let prepared: BTreeMap<(usize, u64), Prepared> = keys
        .par_iter()
        .map(|&(s, l)| Ok(((s, l), prepare(&cfg.scenarios[s], cfg, &bathy, tl, f64::from_bits(l))?)))
        .collect::<Result<Vec<_>, TlError>>()?
        .into_iter()
        .collect();
    let (ns, nb, nr) = (cfg.scenarios.len(), cfg.behaviours.len(), cfg.repetitions);
    let runs = (0..ns * nb * nr)
        .into_par_iter()
        .map(|i| {
            let (s, b, rep) = (i / (nb * nr), (i / nr) % nb, i % nr);
            let p = &prepared[&(s, slot_lens[b].to_bits())];
            let m = world::run(
                p,
                &cfg.scenarios[s],
                cfg,
                &bathy,
                &cfg.behaviours[b],
                run_seed(run_seed(cfg.seed, s as u64), rep as u64),
            );
            progress(1);
            m
        })
        .collect::<Result<Vec<RunMetrics>, WorldError>>()?;
    let cells = runs
        .chunks(nr)
        .enumerate()
        .map(|(j, chunk)| {
            let (s, b) = (j / nb, j % nb);
            let (mean, sd) = RunMetrics::mean_sd(chunk);
            let beh = &cfg.behaviours[b];
            Cell {
                scenario: cfg.scenarios[s].name.clone(),
                behaviour: beh.label(),
                control: beh.is_control(),
                slot_len: slot_lens[b],
                runs: nr,
                mean,
                sd,
            }
        })
        .collect();
    Ok(ExperimentResult { cells })
}
