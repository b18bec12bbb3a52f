//! Table 7 metrics of one run (Nams 2014, §4.4 and Table 7, with our reading of its accounting: one
//! transmission opportunity per slot network-wide, bytes summed over both directions).
//!
//! score = 0.5·BW/19.2 + 0.3·(1 − duty) + 0.2·mean f(P), f(P) = 1 if P ≤ Th else Th/P ("half
//! score per doubling", continuous form), Th = 60·(1 + floor(d̄/500)) s. Reconstructed:
//! docs/models.md#nams-metrics.
//!
//! [`LinkTally`] collects the same counts from the one engine (a Nams scenario file run with
//! `comms.status_format = "nams_frame0"` and `comms.status_to = "cna_and_auvs"`).

use crate::engine::{Observer, ShadowSample, StatusChoice, StatusFrames, StatusSent, TraceRow};
use coopnav_acomms::selector::Choice;
use coopnav_core::Vec3;
use serde::Serialize;

/// Bandwidth ceiling of Table 7: rate 1 (192 B) every 10 s at 100 % success, B/s.
pub const BW_CEILING: f64 = 19.2;

/// Raw counts a run accumulates.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    pub opportunities: u64,
    pub transmissions: u64,
    /// Payload bytes of every frame received.
    pub bytes_gross: u64,
    /// The same, less the frame-0 bytes spent on the tracking header and status message.
    pub bytes_net: u64,
    /// Times of status receptions (frame 0 arrived), both directions, in order.
    pub status_times: Vec<f64>,
    /// Per-direction status receptions (receiver index).
    pub status_times_by_rx: Vec<Vec<f64>>,
    pub header_bits: u64,
    pub queue_len_sum: u64,
    pub queue_len_max: u64,
    /// Transmissions at rates 0..=5.
    pub rate_use: [u64; 6],
    /// Horizontal error of the shadow estimate of the collaborator at each decision, m.
    pub estimate_error_sum: f64,
    pub estimate_error_max: f64,
    pub decisions: u64,
}

impl Tally {
    /// Nothing yet, among `n` vehicles (a direction never heard counts the whole mission as one
    /// period).
    pub fn for_vehicles(n: usize) -> Self {
        Tally { status_times_by_rx: vec![Vec::new(); n], ..Tally::default() }
    }

    /// A status (frame 0) sent at `t` was received by vehicle `rx`.
    pub fn status_received(&mut self, rx: usize, t: f64) {
        self.status_times.push(t);
        if self.status_times_by_rx.len() <= rx {
            self.status_times_by_rx.resize(rx + 1, Vec::new());
        }
        self.status_times_by_rx[rx].push(t);
    }
}

/// Nams's counts from an engine run: every survey AUV's status slots, the frames its statuses
/// deliver to the other survey AUVs, its shadow estimates, and the vehicles' mean distance apart.
#[derive(Debug, Clone)]
pub struct LinkTally {
    pub tally: Tally,
    distance_sum: f64,
    distance_samples: u64,
    last_t: f64,
}

impl LinkTally {
    /// A tally of a run with `n_auvs` survey AUVs.
    pub fn new(n_auvs: usize) -> Self {
        LinkTally { tally: Tally::for_vehicles(n_auvs), distance_sum: 0.0, distance_samples: 0, last_t: 0.0 }
    }

    /// Table 7's metrics over the run so far.
    pub fn metrics(&self) -> RunMetrics {
        let mean_distance = self.distance_sum / self.distance_samples.max(1) as f64;
        RunMetrics::from_tally(&self.tally, self.last_t, mean_distance)
    }
}

impl Observer for LinkTally {
    fn on_status_choice(&mut self, choice: &StatusChoice) {
        let t = &mut self.tally;
        t.opportunities += 1;
        if let Choice::Transmit(rate) = choice.choice {
            t.transmissions += 1;
            t.rate_use[rate.index() as usize] += 1;
        }
    }
    fn on_status_sent(&mut self, sent: &StatusSent) {
        let t = &mut self.tally;
        t.header_bits += sent.header_bits as u64;
        t.queue_len_sum += sent.header_entries as u64;
        t.queue_len_max = t.queue_len_max.max(sent.header_entries as u64);
    }
    fn on_status_frames(&mut self, f: &StatusFrames) {
        let gross = u64::from(f.frames_received) * f.frame_bytes as u64;
        self.tally.bytes_gross += gross;
        self.tally.bytes_net += gross - f.frame0_bytes.unwrap_or(0) as u64;
        if f.frame0_bytes.is_some() {
            self.tally.status_received(f.to, f.t);
        }
    }
    fn on_shadow(&mut self, sample: &ShadowSample) {
        let t = &mut self.tally;
        t.estimate_error_sum += sample.error;
        t.estimate_error_max = t.estimate_error_max.max(sample.error);
        t.decisions += 1;
    }
    /// Every pair of survey AUVs' true horizontal distance, once a second.
    fn on_sample(&mut self, t: f64, _cna: Vec3, rows: &[TraceRow]) {
        for (i, a) in rows.iter().enumerate() {
            for b in &rows[i + 1..] {
                self.distance_sum += (a.true_x - b.true_x).hypot(a.true_y - b.true_y);
                self.distance_samples += 1;
            }
        }
        self.last_t = t;
    }
}

/// Metrics of one run.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct RunMetrics {
    pub bandwidth: f64,
    pub bandwidth_net: f64,
    pub duty_cycle: f64,
    pub status_period: f64,
    pub status_period_per_direction: f64,
    pub frequency_score: f64,
    pub score: f64,
    pub header_bytes_mean: f64,
    pub queue_len_mean: f64,
    pub queue_len_max: f64,
    pub mean_distance: f64,
    pub duration: f64,
    pub transmissions: f64,
    pub estimate_error_mean: f64,
    pub estimate_error_max: f64,
}

/// Intervals between consecutive receptions; with fewer than 2, the whole mission counts as one.
fn intervals(times: &[f64], duration: f64) -> Vec<f64> {
    if times.len() < 2 {
        return vec![duration];
    }
    times.windows(2).map(|w| w[1] - w[0]).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

impl RunMetrics {
    pub fn from_tally(t: &Tally, duration: f64, mean_distance: f64) -> Self {
        let periods = intervals(&t.status_times, duration);
        let th = 60.0 * (1.0 + (mean_distance / 500.0).floor());
        let frequency_score = mean(&periods.iter().map(|&p| if p <= th { 1.0 } else { th / p }).collect::<Vec<_>>());
        let bandwidth = t.bytes_gross as f64 / duration;
        let duty_cycle = t.transmissions as f64 / t.opportunities.max(1) as f64;
        let per_dir: Vec<f64> = t.status_times_by_rx.iter().map(|ts| mean(&intervals(ts, duration))).collect();
        RunMetrics {
            bandwidth,
            bandwidth_net: t.bytes_net as f64 / duration,
            duty_cycle,
            status_period: mean(&periods),
            status_period_per_direction: mean(&per_dir),
            frequency_score,
            score: 0.5 * bandwidth / BW_CEILING + 0.3 * (1.0 - duty_cycle) + 0.2 * frequency_score,
            header_bytes_mean: t.header_bits as f64 / 8.0 / t.transmissions.max(1) as f64,
            queue_len_mean: t.queue_len_sum as f64 / t.transmissions.max(1) as f64,
            queue_len_max: t.queue_len_max as f64,
            mean_distance,
            duration,
            transmissions: t.transmissions as f64,
            estimate_error_mean: t.estimate_error_sum / t.decisions.max(1) as f64,
            estimate_error_max: t.estimate_error_max,
        }
    }
}

impl RunMetrics {
    fn fields(&self) -> [f64; 15] {
        [
            self.bandwidth,
            self.bandwidth_net,
            self.duty_cycle,
            self.status_period,
            self.status_period_per_direction,
            self.frequency_score,
            self.score,
            self.header_bytes_mean,
            self.queue_len_mean,
            self.queue_len_max,
            self.mean_distance,
            self.duration,
            self.transmissions,
            self.estimate_error_mean,
            self.estimate_error_max,
        ]
    }
    fn from_fields(f: [f64; 15]) -> Self {
        let [bandwidth, bandwidth_net, duty_cycle, status_period, status_period_per_direction, frequency_score, score, header_bytes_mean, queue_len_mean, queue_len_max, mean_distance, duration, transmissions, estimate_error_mean, estimate_error_max] =
            f;
        RunMetrics {
            bandwidth,
            bandwidth_net,
            duty_cycle,
            status_period,
            status_period_per_direction,
            frequency_score,
            score,
            header_bytes_mean,
            queue_len_mean,
            queue_len_max,
            mean_distance,
            duration,
            transmissions,
            estimate_error_mean,
            estimate_error_max,
        }
    }
    /// Field-wise mean and sample standard deviation over runs.
    pub fn mean_sd(runs: &[RunMetrics]) -> (RunMetrics, RunMetrics) {
        let n = runs.len().max(1) as f64;
        let mut m = [0.0; 15];
        for r in runs {
            for (a, v) in m.iter_mut().zip(r.fields()) {
                *a += v / n;
            }
        }
        let mut sd = [0.0; 15];
        if runs.len() > 1 {
            for r in runs {
                for ((a, v), mu) in sd.iter_mut().zip(r.fields()).zip(m) {
                    *a += (v - mu).powi(2) / (n - 1.0);
                }
            }
        }
        (RunMetrics::from_fields(m), RunMetrics::from_fields(sd.map(f64::sqrt)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceiling_run_scores_its_parts() {
        // Rate 1 every 10 s, all received, 100 s: BW = ceiling, duty 1, every period 10 s.
        let t = Tally {
            opportunities: 10,
            transmissions: 10,
            bytes_gross: 1920,
            bytes_net: 1800,
            status_times: (0..10).map(|k| k as f64 * 10.0).collect(),
            ..Tally::default()
        };
        let m = RunMetrics::from_tally(&t, 100.0, 300.0);
        assert!((m.bandwidth - BW_CEILING).abs() < 1e-12);
        assert_eq!(m.duty_cycle, 1.0);
        assert_eq!(m.status_period, 10.0);
        assert!((m.score - (0.5 + 0.0 + 0.2)).abs() < 1e-12);
    }

    #[test]
    fn long_periods_lose_half_per_doubling() {
        let t = Tally { opportunities: 4, transmissions: 2, status_times: vec![0.0, 240.0], ..Tally::default() };
        // d̄ = 600 m → Th = 120 s; one period of 240 s → f = 0.5.
        let m = RunMetrics::from_tally(&t, 1000.0, 600.0);
        assert!((m.frequency_score - 0.5).abs() < 1e-12);
        assert!((m.score - (0.3 * 0.5 + 0.2 * 0.5)).abs() < 1e-12);
        let (mu, sd) = RunMetrics::mean_sd(&[m, RunMetrics { bandwidth: 2.0, ..m }]);
        assert!((mu.bandwidth - (m.bandwidth + 2.0) / 2.0).abs() < 1e-12 && mu.duty_cycle == m.duty_cycle);
        assert!((sd.bandwidth - (2.0 - m.bandwidth).abs() / 2f64.sqrt()).abs() < 1e-12 && sd.duty_cycle == 0.0);
        let none = RunMetrics::from_tally(&Tally { opportunities: 5, ..Tally::default() }, 1000.0, 100.0);
        assert_eq!(none.status_period, 1000.0);
    }
}
