//! The Monte Carlo error profile against along-path position x_rel (digest §5.6, the thesis's
//! Figs. 16, 19 and 21): per x_rel bin, the mean total, |along-path| and |across-path| AUV error
//! over every step of every run that fell in the bin. Runs use the Monte Carlo's seeds
//! (`run_seed(base, i)`), so a profile and a `monte_carlo` with one base seed describe the same runs.

use super::config::Scenario;
use super::mc::McError;
use super::world::run;
use coopnav_core::run_seed;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// One x_rel bin of the profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfileBin {
    /// Centre of the bin (m of x_rel, + = behind the ship).
    pub x_rel: f64,
    /// Filter steps (over all runs) that fell in the bin.
    pub samples: usize,
    pub error: f64,
    pub parallel: f64,
    pub perpendicular: f64,
}

/// Sums of [count, error, |parallel|, |perpendicular|] per bin index.
type BinSums = BTreeMap<i64, [f64; 4]>;

/// Mean error profile of `runs` runs of `sc` in bins of `bin_m` metres of x_rel.
pub fn error_profile(sc: &Scenario, runs: usize, base_seed: u64, bin_m: f64) -> Result<Vec<ProfileBin>, McError> {
    sc.validate()?;
    if runs < 2 {
        return Err(McError::TooFewRuns);
    }
    if !(bin_m.is_finite() && bin_m > 0.0) {
        return Err(McError::BadBin(bin_m));
    }
    let cycle = sc.resolved_cycle()?;
    let per_run: Vec<BinSums> = (0..runs)
        .into_par_iter()
        .map(|i| {
            let (_, trace) = run(sc, &cycle, run_seed(base_seed, i as u64), true);
            let mut sums = BinSums::new();
            for r in trace.map(|t| t.rows).unwrap_or_default() {
                let s = sums.entry((r.x_rel / bin_m).floor() as i64).or_default();
                let (de, dn) = (r.auv_est[0] - r.auv_true[0], r.auv_est[1] - r.auv_true[1]);
                for (acc, v) in s.iter_mut().zip([1.0, r.error, de.abs(), dn.abs()]) {
                    *acc += v;
                }
            }
            sums
        })
        .collect();
    // Merged in run order, so the sums do not depend on the thread count.
    let mut total = BinSums::new();
    for sums in per_run {
        for (k, v) in sums {
            let t = total.entry(k).or_default();
            for (acc, x) in t.iter_mut().zip(v) {
                *acc += x;
            }
        }
    }
    Ok(total
        .into_iter()
        .map(|(k, [n, e, pa, pe])| ProfileBin { x_rel: (k as f64 + 0.5) * bin_m, samples: n as usize, error: e / n, parallel: pa / n, perpendicular: pe / n })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_nav::cycle::Configuration;

    #[test]
    fn profile_shows_msbl_keeps_its_across_path_error_longer_than_hbl() {
        let profile = |c| error_profile(&Scenario::table5(c), 24, 7, 25.0).unwrap();
        let (msbl, hbl) = (profile(Configuration::Msbl), profile(Configuration::HblTwo));
        let at = |p: &[ProfileBin], x: f64| p.iter().find(|b| (b.x_rel - x).abs() < 1.0).copied().unwrap();
        // 50–75 m before the zone starts (x_rel −87.5 bin centre): HBL has corrected, MSBL not.
        assert!(at(&hbl, -87.5).perpendicular < 0.6 * at(&msbl, -87.5).perpendicular);
        for b in hbl.iter().chain(&msbl) {
            assert!(b.samples > 0 && b.error.is_finite() && b.error + 1e-12 >= b.parallel.max(b.perpendicular));
        }
    }

    #[test]
    fn profile_is_identical_on_one_and_two_threads() {
        let sc = Scenario::default();
        let on = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| error_profile(&sc, 6, 3, 10.0).unwrap());
        assert_eq!(on(1), on(2));
    }

    #[test]
    fn bad_bins_and_too_few_runs_are_refused() {
        let sc = Scenario::default();
        assert!(matches!(error_profile(&sc, 6, 1, 0.0), Err(McError::BadBin(_))));
        assert!(matches!(error_profile(&sc, 1, 1, 10.0), Err(McError::TooFewRuns)));
    }
}
