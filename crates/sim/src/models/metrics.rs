//! Per-run metrics of the closed loop: each survey AUV's *true* navigation error statistics
//! (mean, RMS, max, 95th percentile, CEP50 over time) beside the planner's modelled error,
//! ranges and packets per link, CNA–AUV distances and limit violations, and filter health.

use serde::{Deserialize, Serialize};

/// Summary statistics of a sampled error series, m.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    pub mean: f64,
    pub rms: f64,
    pub max: f64,
    pub p95: f64,
    /// Median radial error (circular error probable, 50 %).
    pub cep50: f64,
}

impl ErrorStats {
    /// Statistics of `samples` (all zero when empty).
    pub fn of(samples: &[f64]) -> Self {
        if samples.is_empty() {
            return ErrorStats::default();
        }
        let n = samples.len() as f64;
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        ErrorStats {
            mean: samples.iter().sum::<f64>() / n,
            rms: (samples.iter().map(|e| e * e).sum::<f64>() / n).sqrt(),
            max: sorted[sorted.len() - 1],
            p95: quantile(&sorted, 0.95),
            cep50: quantile(&sorted, 0.5),
        }
    }
}

/// Linear-interpolated quantile of sorted data.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + f * (next - sorted[i])
}

/// Sent and received packets of one directed link, in total and per WHOI rate 0..=5.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkStats {
    pub sent: u64,
    pub received: u64,
    pub sent_by_rate: [u64; 6],
    pub received_by_rate: [u64; 6],
    /// Packets the channel decoded that were lost to a collision or half-duplex (the receiver
    /// transmitting during the arrival).
    #[serde(default)]
    pub lost_in_air: u64,
}

impl LinkStats {
    /// Counts one packet sent at `rate` (0..=5), received or not.
    pub fn record(&mut self, rate: u8, received: bool) {
        let r = usize::from(rate.min(5));
        self.sent += 1;
        self.sent_by_rate[r] += 1;
        if received {
            self.received += 1;
            self.received_by_rate[r] += 1;
        }
    }

    /// Counts one packet sent at `rate` that the channel `decoded` and that `survived` the air
    /// (no collision, no half-duplex); `received`: it was also read.
    pub fn record_arrival(&mut self, rate: u8, (decoded, survived): (bool, bool), received: bool) {
        self.record(rate, received);
        if decoded && !survived {
            self.lost_in_air += 1;
        }
    }

    /// Nothing was sent (a scenario without that link, e.g. without buoys).
    pub fn is_unused(&self) -> bool {
        self.sent == 0
    }

    pub fn success(&self) -> f64 {
        if self.sent == 0 {
            0.0
        } else {
            self.received as f64 / self.sent as f64
        }
    }
}

/// Everything measured about one survey AUV.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AuvMetrics {
    pub name: String,
    /// True EKF position error (horizontal), sampled every second.
    pub error: ErrorStats,
    /// Mean of the modelled error √(σ² + ε²) at the decision times (None before any model).
    pub modelled_mean: Option<f64>,
    /// CNA broadcasts (ranges): sent towards this AUV and received by it.
    pub downlink: LinkStats,
    /// Buoy position broadcasts (ranges, all buoys together): sent towards this AUV and received
    /// (left out of the summary when the scenario has no buoys).
    #[serde(default, skip_serializing_if = "LinkStats::is_unused")]
    pub buoy_link: LinkStats,
    /// Ranges the EKF applied (the CNA's and the buoys').
    pub ranges_applied: u64,
    /// Status messages from this AUV to the CNA.
    pub uplink: LinkStats,
    /// True horizontal CNA–AUV distance, m, sampled every second.
    pub distance_mean: f64,
    pub distance_min: f64,
    pub distance_max: f64,
    /// Fraction of samples outside the planner's [min, max] distance limits.
    pub limit_violation: f64,
    /// The filter's consistency against the truth.
    pub health: FilterHealth,
}

/// One filter's consistency over a run: its own σ beside the true error, NEES (horizontal
/// position, every second) and NIS (every range update) against their χ² bounds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FilterHealth {
    /// Mean of the filter's horizontal 1-σ, m.
    pub sigma_mean: f64,
    /// RMS true error over RMS σ (about 1 for a consistent filter; ≫ 1 when overconfident).
    pub error_to_sigma: f64,
    /// Mean NEES (2 degrees of freedom: 2 for a consistent filter).
    pub nees_mean: f64,
    /// Fraction of seconds with NEES inside its 95 % bound (0.95 for a consistent filter).
    pub nees_in_95: f64,
    pub nis_mean: Option<f64>,
    pub nis_in_95: Option<f64>,
    /// When the NEES had stayed above its 99.9 % bound for the divergence window, if it did.
    pub diverged_at_s: Option<f64>,
    /// How often the filter's own check on its ranges (`filter.range_health`, NIS only, no
    /// truth) found it out of its bounds and recovered it, and when first (s).
    #[serde(default)]
    pub recoveries: u32,
    #[serde(default)]
    pub recovered_first_s: Option<f64>,
}

/// Summary of the whole fleet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FleetMetrics {
    /// Statistics of all AUVs' samples pooled.
    pub error: ErrorStats,
    pub modelled_mean: Option<f64>,
    /// Every filter state finite throughout.
    pub healthy: bool,
    /// AUVs whose filter the NEES check flagged as diverged.
    pub diverged: usize,
}
