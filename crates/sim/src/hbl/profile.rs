//! The Monte Carlo error profile against along-path position x_rel (digest §5.6, the thesis's
//! Figs. 16, 19 and 21): per x_rel bin, the mean total, |along-path| and |across-path| AUV error
//! over every step of every run that fell in the bin. The bins are filled by the Monte Carlo
//! itself ([`super::mc::monte_carlo_profiled`]), so a profile describes the very runs it summarises.

use super::config::Scenario;
use super::mc::{monte_carlo_profiled, McError};
use super::world::TraceRow;
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
pub(crate) type BinSums = BTreeMap<i64, [f64; 4]>;

/// Mean error profile of `runs` runs of `sc` in bins of `bin_m` metres of x_rel.
pub fn error_profile(sc: &Scenario, runs: usize, base_seed: u64, bin_m: f64) -> Result<Vec<ProfileBin>, McError> {
    Ok(monte_carlo_profiled(sc, runs, base_seed, bin_m, &|_| {})?.profile.unwrap_or_default())
}

/// One run's steps summed per bin.
pub(crate) fn bin_rows(rows: &[TraceRow], bin_m: f64) -> BinSums {
    let mut sums = BinSums::new();
    for r in rows {
        let s = sums.entry((r.x_rel / bin_m).floor() as i64).or_default();
        let (de, dn) = (r.auv_est[0] - r.auv_true[0], r.auv_est[1] - r.auv_true[1]);
        add_to_bin(s, [1.0, r.error, de.abs(), dn.abs()]);
    }
    sums
}

/// Runs' sums merged in the order given (run order, so the result does not depend on the
/// thread count), as per-bin means.
pub(crate) fn merge_bins(per_run: impl Iterator<Item = BinSums>, bin_m: f64) -> Vec<ProfileBin> {
    let mut total = BinSums::new();
    for sums in per_run {
        for (k, v) in sums {
            add_to_bin(total.entry(k).or_default(), v);
        }
    }
    total
        .into_iter()
        .map(|(k, [n, e, pa, pe])| ProfileBin {
            x_rel: (k as f64 + 0.5) * bin_m,
            samples: n as usize,
            error: e / n,
            parallel: pa / n,
            perpendicular: pe / n,
        })
        .collect()
}

/// Adds one sample's (or one run's) [count, error, |parallel|, |perpendicular|] to a bin.
pub(crate) fn add_to_bin(acc: &mut [f64; 4], v: [f64; 4]) {
    for (a, x) in acc.iter_mut().zip(v) {
        *a += x;
    }
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
        let on = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| error_profile(&sc, 6, 3, 10.0).unwrap())
        };
        assert_eq!(on(1), on(2));
    }

    #[test]
    fn bad_bins_and_too_few_runs_are_refused() {
        let sc = Scenario::default();
        assert!(matches!(error_profile(&sc, 6, 1, 0.0), Err(McError::BadBin(_))));
        assert!(matches!(error_profile(&sc, 1, 1, 10.0), Err(McError::TooFewRuns)));
    }
}
