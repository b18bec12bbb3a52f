//! The batch runner: builds every (scenario, behaviour) cell's engine scenario once
//! ([`super::nams_setup`]), then runs cells × runs on the engine in parallel (rayon), merging
//! results in index order so the output is bit-identical on any thread count. Repetition i of
//! scenario s uses seed run_seed(run_seed(base, s), i) for every behaviour (common random numbers).

use super::nams_setup::{engine_scenario, slot_length};
use crate::engine::Faults;
use crate::models::tl_spec::TlModel;
use crate::observe::link_tally::{LinkTally, RunMetrics};
use crate::observe::metrics::{run, run_with_tl};
use crate::policy::{PolicyError, PolicySpec};
use crate::scenario::nams::ExperimentConfig;
use crate::scenario::world::{Scenario as EngineScenario, ScenarioError};
use coopnav_acomms::selector::RatePolicyError;
use coopnav_acomms::TransmissionLoss;
use coopnav_core::run_seed;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum BatchError {
    #[error("{0}")]
    Config(ScenarioError),
    #[error("experiment configuration: a behaviour: {0}")]
    Behaviour(#[from] RatePolicyError),
    #[error("a cell's engine scenario: {0}")]
    Scenario(#[from] ScenarioError),
    #[error("the silent CNA: {0}")]
    Policy(#[from] PolicyError),
}

/// The transmission loss an experiment's runs see.
#[derive(Clone)]
pub enum ExperimentTl {
    /// One model the caller built, shared by every run (analytic, or a grid of its own layout).
    Shared(Arc<dyn TransmissionLoss>),
    /// The model each cell's engine scenario builds over its own layout: a BELLHOP grid over the
    /// cell's square, shelf and sound-speed profile, computed once per layout (then read from the
    /// disk cache) when the cell is built.
    PerCell(TlModel),
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

/// Runs the whole experiment on `tl`; `progress(1)` after every run.
pub fn run_experiment(
    cfg: &ExperimentConfig,
    tl: &ExperimentTl,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ExperimentResult, BatchError> {
    cfg.validate().map_err(BatchError::Config)?;
    let slot_lens = cfg.behaviours.iter().map(|b| slot_length(cfg, b)).collect::<Result<Vec<f64>, _>>()?;
    let (ns, nb, nr) = (cfg.scenarios.len(), cfg.behaviours.len(), cfg.runs);
    // In parallel: the cells of one square share their BELLHOP grid, built once (`models::tl`).
    let cells: Vec<EngineScenario> = (0..ns * nb)
        .into_par_iter()
        .map(|j| {
            let own_tl = match tl {
                ExperimentTl::Shared(_) => None,
                ExperimentTl::PerCell(model) => Some(model),
            };
            engine_scenario(&cfg.scenarios[j / nb], cfg, &cfg.behaviours[j % nb], slot_lens[j % nb], own_tl)
        })
        .collect::<Result<_, _>>()?;
    let runs = (0..ns * nb * nr)
        .into_par_iter()
        .map(|i| {
            let (s, rep) = (i / (nb * nr), i % nr);
            let sc = &cells[i / nr];
            let silent = PolicySpec::new("none", sc).and_then(|p| p.build(sc));
            let mut policy = silent?;
            let mut tally = LinkTally::new(sc.fleet.n_auvs);
            let seed = run_seed(run_seed(cfg.seed, s as u64), rep as u64);
            match tl {
                ExperimentTl::Shared(shared) => run_with_tl(sc, &mut policy, seed, shared.clone(), &mut tally),
                ExperimentTl::PerCell(_) => run(sc, &mut policy, seed, &Faults::default(), &mut tally),
            };
            progress(1);
            Ok(tally.metrics())
        })
        .collect::<Result<Vec<RunMetrics>, BatchError>>()?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::nams::{table_6, Behaviour, EstimatorMode};
    use coopnav_acomms::{Rate, TlError};
    use coopnav_core::Vec3;

    /// A channel with the same TL everywhere.
    struct Flat(f64);
    impl TransmissionLoss for Flat {
        fn tl(&self, _: &Vec3, _: &Vec3) -> Result<f64, TlError> {
            Ok(self.0)
        }
    }

    fn mean_with(cfg: ExperimentConfig, behaviour: Behaviour, tl_db: f64) -> RunMetrics {
        let cfg =
            ExperimentConfig { scenarios: vec![table_6()[0].clone()], behaviours: vec![behaviour], runs: 8, ..cfg };
        run_experiment(&cfg, &ExperimentTl::Shared(Arc::new(Flat(tl_db))), &|_| {}).unwrap().cells[0].mean
    }

    fn mean_bw(behaviour: Behaviour, tl_db: f64) -> RunMetrics {
        mean_with(ExperimentConfig::default(), behaviour, tl_db)
    }

    #[test]
    fn fixed_rate_1_on_a_quiet_channel_delivers_the_expected_bytes() {
        // p = 0.9; 8 % of received packets lose 1 or 2 of 3 frames: E[frames] = 0.9·(0.92·3 + 0.08·1.5).
        let m = mean_bw(Behaviour::Fixed { rate: Rate::R1 }, 30.0);
        let want = 0.9 * (0.92 * 3.0 + 0.08 * 1.5) * 64.0 / 10.0;
        assert!((m.bandwidth - want).abs() < 0.03 * want, "{} vs {want}", m.bandwidth);
        assert_eq!(m.duty_cycle, 1.0);
        assert!(m.bandwidth_net < m.bandwidth, "frame 0 carries header and status");
        assert!(m.header_bytes_mean > 1.0 && m.header_bytes_mean < 4.0, "header {} B", m.header_bytes_mean);
    }

    #[test]
    fn preplanned_shadows_track_the_peer_within_its_own_navigation_error() {
        // The shadow extrapolates the peer's last reported estimate along its known plan, so its
        // error against the peer's truth is the peer's navigation error plus the extrapolation's.
        // With perfect dead reckoning only the extrapolation is left: a metre, not the 13 m mean
        // the IVER2's sensors give (the old loop reported truth and held 5 m mean / 25 m max).
        let cfg = ExperimentConfig::default();
        let (scenario, behaviour) = (table_6()[0].clone(), Behaviour::Fixed { rate: Rate::R1 });
        let slot_s = slot_length(&cfg, &behaviour).unwrap();
        let mut sc = engine_scenario(&scenario, &cfg, &behaviour, slot_s, None).unwrap();
        let run_once = |sc: &EngineScenario| {
            let mut policy = PolicySpec::new("none", sc).and_then(|p| p.build(sc)).unwrap();
            let mut tally = LinkTally::new(sc.fleet.n_auvs);
            run_with_tl(sc, &mut policy, 7, Arc::new(Flat(30.0)), &mut tally);
            tally.metrics()
        };
        let noisy = run_once(&sc);
        sc.fleet.init_position_sd = 0.0;
        sc.sensors = crate::scenario::world::AuvSensors {
            speed_sd: 0.0,
            compass_bias_step_deg: 0.0,
            compass_bias_iid: false,
            compass_white_deg: 0.0,
            yaw_rate_white_deg_s: 0.0,
        };
        let perfect = run_once(&sc);
        eprintln!(
            "shadow error mean/max: sensors {:.2}/{:.1} m, perfect {:.2}/{:.1} m",
            noisy.estimate_error_mean,
            noisy.estimate_error_max,
            perfect.estimate_error_mean,
            perfect.estimate_error_max
        );
        assert!(perfect.estimate_error_mean < 1.0 && perfect.estimate_error_max < 5.0, "{perfect:?}");
        assert!(noisy.estimate_error_mean > 2.0 * perfect.estimate_error_mean, "navigation error must show");
    }

    #[test]
    fn dynamic_estimates_are_worse_than_preplanned_but_bounded() {
        // Without the plan, the shadow stops at the reported next waypoint: errors grow during
        // droughts (rate 1 at 60 dB: p = 0.6) but a report resets them.
        let dynamic = ExperimentConfig { estimator: EstimatorMode::Dynamic, ..ExperimentConfig::default() };
        let d = mean_with(dynamic, Behaviour::Fixed { rate: Rate::R1 }, 60.0);
        let p = mean_bw(Behaviour::Fixed { rate: Rate::R1 }, 60.0);
        eprintln!(
            "estimate error mean/max: pre-planned {:.2}/{:.1} m, dynamic {:.2}/{:.1} m",
            p.estimate_error_mean, p.estimate_error_max, d.estimate_error_mean, d.estimate_error_max
        );
        assert!(d.estimate_error_mean > p.estimate_error_mean);
        assert!(d.estimate_error_mean < 30.0, "{}", d.estimate_error_mean);
        assert!(d.header_bytes_mean > 0.0 && d.bandwidth_net < p.bandwidth_net, "lat/lon costs frame-0 bytes");
    }

    #[test]
    fn adaptive_learns_to_use_rate_4_where_it_beats_its_target() {
        // Rate 4 succeeds 80 % > Π4 + τ everywhere: its bin grows from 400 m by Δ = 5 m per own
        // slot until it covers the whole mission (≤ 707 m), so after a transient of ~60 own slots
        // (of ~195) every packet goes at rate 4. Rate 1 throughout would give 16.6 B/s.
        let m = mean_bw(Behaviour::Adaptive(Default::default()), 30.0);
        let rate4 = 0.8 * (0.96 * 2.0 + 0.04 * 1.0) * 256.0 / 10.0;
        assert!(m.bandwidth > 0.8 * rate4 && m.bandwidth < rate4, "{} vs {rate4}", m.bandwidth);
        // On a dead channel nothing is ever resolved (no header gets through), so no bin moves
        // (bins adapt on resolved outcomes only) and the drought keeps the vehicles in status
        // mode, still trying at rate 1 within the 2500 m status bin.
        let dead = mean_bw(Behaviour::Adaptive(Default::default()), 90.0);
        assert_eq!(dead.bandwidth, 0.0);
        assert_eq!(dead.duty_cycle, 1.0);
    }
}
