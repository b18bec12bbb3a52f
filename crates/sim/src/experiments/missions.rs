//! Generated missions as an experiment's cells ([`crate::scenario::generate`]): the generator
//! file's missions for a study's size, the seeds no evaluation may fly (settings were chosen on
//! them), and the measured account of one policy against another on one mission.

use super::closed_loop::TUNING_SEED;
use super::{ExperimentError, ReproOptions, Size};
use crate::batch::mc::{paired_per_auv, Comparison};
use crate::scenario::generate::{Mission, Ranges};
use coopnav_core::run_seed;
use std::path::Path;

/// Base seeds whose runs chose a setting, with how many runs and what they chose.
pub struct ChosenOn {
    pub base: u64,
    pub runs: u64,
    pub what: &'static str,
}

/// Every base seed a setting was chosen on: no generated mission may use it, nor any of its runs'
/// seeds.
pub const CHOSEN_ON: [ChosenOn; 2] = [
    ChosenOn {
        base: TUNING_SEED,
        runs: 40,
        what: "planner-estimator's settings (closed-loop-vs-baselines' tuning runs, examples/closed_loop_tune.rs)",
    },
    ChosenOn {
        base: 1,
        runs: 100,
        what: "the default mission's seed, on which the closed-loop filters' process noise was set \
               (scenario::world::CLOSED_LOOP_Q_EN) and every reproduction's default",
    },
];

/// A study's seeds meet seeds a setting was chosen on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChosenSeedError {
    #[error("mission seed {base} chose {what}; generate from a seed range without it")]
    Base { base: u64, what: &'static str },
    #[error("run {run} of mission seed {seed} has a run seed of base {base}, which chose {what}")]
    Run { run: u64, seed: u64, base: u64, what: &'static str },
}

/// Err naming the seed when a mission of `ranges` has a base seed a setting was chosen on, or one
/// of its first `runs` run seeds is one of those runs' seeds.
pub fn refuse_chosen(ranges: &Ranges, runs: usize) -> Result<(), ChosenSeedError> {
    for chosen in &CHOSEN_ON {
        if ranges.seeds().contains(&chosen.base) {
            return Err(ChosenSeedError::Base { base: chosen.base, what: chosen.what });
        }
        let taken: std::collections::HashSet<u64> = (0..chosen.runs).map(|j| run_seed(chosen.base, j)).collect();
        for seed in ranges.seeds() {
            if let Some(run) = (0..runs as u64).find(|&j| taken.contains(&run_seed(seed, j))) {
                return Err(ChosenSeedError::Run { run, seed, base: chosen.base, what: chosen.what });
            }
        }
    }
    Ok(())
}

/// A study's missions and runs per policy.
pub struct Study {
    pub file: &'static str,
    pub ranges: Ranges,
    pub missions: Vec<Mission>,
    pub runs: usize,
}

/// How big a study is: missions and runs per policy and mission.
#[derive(Debug, Clone, Copy)]
pub struct StudySize {
    pub missions: Option<usize>,
    pub runs: usize,
}

/// The missions of generator file `text` (named `file`) for `opts`: `full` or `reduced` (None
/// missions: the file's count). `--seed` other than the default replaces the file's seed. Refuses
/// a seed range that meets [`CHOSEN_ON`].
pub fn study(
    id: &str,
    file: &'static str,
    text: &str,
    opts: &ReproOptions,
    full: StudySize,
    reduced: StudySize,
) -> Result<Study, ExperimentError> {
    let fail = |message: String| ExperimentError::Failed { id: id.into(), message };
    let path = Path::new(file);
    let mut ranges = Ranges::parse(text, path).map_err(|e| fail(e.to_string()))?;
    if opts.seed != ReproOptions::default().seed {
        ranges.seed = opts.seed;
    }
    let size = match opts.size {
        Size::Full => full,
        Size::Reduced => reduced,
    };
    ranges.missions = size.missions.unwrap_or(ranges.missions);
    ranges.validate(path).map_err(|e| fail(e.to_string()))?;
    refuse_chosen(&ranges, size.runs).map_err(|e| fail(e.to_string()))?;
    let missions = ranges.generate(path).map_err(|e| fail(e.to_string()))?;
    Ok(Study { file, ranges, missions, runs: size.runs })
}

/// What the runs measured of policies `a` and `b` (indices into `c.policies`) on one mission: mean
/// true error, the fraction of pings each AUV received, the mean CNA–AUV distance (the fleet's,
/// and per AUV: where each CNA path kept the CNA), the filters' mean NEES, and the paired
/// difference per AUV (a minus b).
pub fn measured(c: &Comparison, a: usize, b: usize) -> String {
    let (pa, pb) = (&c.policies[a], &c.policies[b]);
    let (ua, ub) = (&c.auvs[a], &c.auvs[b]);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let list = |v: Vec<f64>, digits: usize| v.iter().map(|x| format!("{x:.digits$}")).collect::<Vec<_>>().join(" ");
    let dist = |u: &[crate::batch::mc::AuvSummary]| u.iter().map(|s| s.distance_mean).collect::<Vec<_>>();
    let down = |u: &[crate::batch::mc::AuvSummary]| u.iter().map(|s| 100.0 * s.downlink_success).collect::<Vec<_>>();
    let nees = |u: &[crate::batch::mc::AuvSummary]| u.iter().map(|s| s.nees_mean).collect::<Vec<_>>();
    let per_auv: Vec<f64> = paired_per_auv(pa, pb).iter().map(|d| d.mean).collect();
    format!(
        "{} {:.2} m vs {} {:.2} m; mean CNA-AUV distance {:.0} vs {:.0} m (per AUV {} | {}); pings received % \
         (per AUV) {} | {}; filter NEES {:.2} vs {:.2} (per AUV {} | {}); paired difference per AUV, m: {}",
        pa.policy,
        pa.mean_error.mean,
        pb.policy,
        pb.mean_error.mean,
        mean(&dist(ua)),
        mean(&dist(ub)),
        list(dist(ua), 0),
        list(dist(ub), 0),
        list(down(ua), 0),
        list(down(ub), 0),
        pa.nees_mean,
        pb.nees_mean,
        list(nees(ua), 2),
        list(nees(ub), 2),
        list(per_auv, 2)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGES: &str = include_str!("../../../../scenarios/generators/generalization.toml");

    #[test]
    fn a_seed_range_meeting_a_chosen_seed_is_refused() {
        let mut r = Ranges::parse(RANGES, Path::new("g.toml")).unwrap();
        assert!(refuse_chosen(&r, 10).is_ok());
        r.seed = TUNING_SEED - 5;
        let e = refuse_chosen(&r, 10).unwrap_err();
        assert!(matches!(e, ChosenSeedError::Base { base: TUNING_SEED, .. }), "{e}");
        assert!(e.to_string().contains(&format!("mission seed {TUNING_SEED} chose")), "{e}");
        r.seed = 0;
        assert!(matches!(refuse_chosen(&r, 10).unwrap_err(), ChosenSeedError::Base { base: 1, .. }));
        r.seed = 2;
        assert!(refuse_chosen(&r, 10).is_ok());
    }
}
