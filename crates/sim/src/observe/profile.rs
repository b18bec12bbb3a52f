//! The Monte Carlo error profile against along-path position x_rel (Gill 2013, §3.2, the thesis's
//! Figs. 16, 19 and 21): per x_rel bin, the mean total, |along-path| and |across-path| AUV error
//! over every sample of every run that fell in the bin. The bins are filled by the zone observer
//! itself ([`super::zone::GillZone`]), so a profile describes the very runs it summarises.

use serde::Serialize;
use std::collections::BTreeMap;

/// One x_rel bin of the profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfileBin {
    /// Centre of the bin (m of x_rel, + = behind the ship).
    pub x_rel: f64,
    /// Samples (over all runs) that fell in the bin.
    pub samples: usize,
    pub error: f64,
    pub parallel: f64,
    pub perpendicular: f64,
}

/// Sums of [count, error, |parallel|, |perpendicular|] per bin index.
pub(crate) type BinSums = BTreeMap<i64, [f64; 4]>;

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
