//! A synthetic field log with known truth and known noise (for the tuning and three-beacon
//! tests and the 24-hour benchmark): one AUV and any number of moving beacons, written as general
//! log rows. Every number here is invented for testing, not taken from a thesis.
//!
//! [`SyntheticSpec::field_like`] is shaped like a short field run: one moving beacon, a ping every
//! 18 s for about 16 minutes, truth every second, and the pings of one early minute lost during
//! the first turn.
//!
//! The AUV runs at a constant speed through the water with heading ψ(t) = ψ₀ + A sin(2πt/T), with
//! A = 2.405 rad (the first zero of J₀), so its mean heading has no drift and it stays near the
//! start however long the log; a water current carries it. Beacon i circles a point 800 m from
//! the start at 0.5 m/s. Every `range_every_s` the next beacon (in turn) pings at that time, its
//! fix logged at the send time; the range is the horizontal distance to where the AUV is on
//! arrival, plus Gaussian noise of variance σ_r² + τ²σ_c² (the filter's range model).

use crate::fieldlog::{LogRow, Observation};
use coopnav_core::SeedStream;
use coopnav_core::{CompassDeg, Heading};
use rand::Rng;
use rand_distr::StandardNormal;

/// What the synthetic log holds and its noise.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSpec {
    pub duration_s: f64,
    /// Rate of the yaw_rate, speed and heading rows (Hz).
    pub rate_hz: f64,
    pub beacons: u32,
    pub range_every_s: f64,
    /// Water current (east, north, m/s).
    pub current: [f64; 2],
    /// σ_r: the range noise at zero range (m).
    pub range_sd_m: f64,
    /// σ_c of the range noise's τ-proportional part (m/s).
    pub sigma_sound_speed: f64,
    /// The speed log reads the true speed divided by this (a scale error a tuner should find).
    pub speed_scale: f64,
    /// Added to every compass reading (deg).
    pub heading_bias_deg: f64,
    pub speed_sd: f64,
    pub heading_sd_deg: f64,
    /// A truth row every this many seconds.
    pub truth_every_s: f64,
    /// Distance of each beacon's circle centre from the start (m).
    pub beacon_distance_m: f64,
    /// Pings sent within [from, to] s are lost (no fix, no range row): an acoustic silence. The
    /// noise is still drawn for them, so the other ranges are the same with or without it.
    pub range_silence_s: Option<[f64; 2]>,
    pub seed: u64,
}

impl Default for SyntheticSpec {
    fn default() -> Self {
        SyntheticSpec {
            duration_s: 3600.0,
            rate_hz: 10.0,
            beacons: 3,
            range_every_s: 15.0,
            current: [0.0, 0.0],
            range_sd_m: 1.8,
            sigma_sound_speed: 3.0,
            speed_scale: 1.0,
            heading_bias_deg: 0.0,
            speed_sd: 0.05,
            heading_sd_deg: 0.5,
            truth_every_s: 10.0,
            beacon_distance_m: 800.0,
            range_silence_s: None,
            seed: 1,
        }
    }
}

impl SyntheticSpec {
    /// A field-like run (invented, shaped like a 16.5-minute single-beacon OWTT run): 990 s, one
    /// beacon circling 300 m away, a ping every 18 s (51 ranges arrive), truth at 1 Hz, and the pings
    /// between 60 s and 120 s lost while the AUV turns (three ranges, then a minute of silence).
    /// The range noise is 0.8 m plus the τ-proportional part, the speed log 3 % slow and the
    /// compass 3° off: none of them the post-processing defaults.
    pub fn field_like(seed: u64) -> SyntheticSpec {
        SyntheticSpec {
            duration_s: 990.0,
            beacons: 1,
            range_every_s: 18.0,
            range_sd_m: 0.8,
            speed_scale: 1.03,
            heading_bias_deg: 3.0,
            truth_every_s: 1.0,
            beacon_distance_m: 300.0,
            range_silence_s: Some([60.0, 120.0]),
            seed,
            ..SyntheticSpec::default()
        }
    }
}

const SPEED: f64 = 1.5;
const SOUND_SPEED: f64 = 1500.0;
const TURN_PERIOD_S: f64 = 900.0;
const TURN_AMPLITUDE: f64 = 2.405;
const HEADING0: f64 = 0.3;

fn heading_at(t: f64) -> f64 {
    HEADING0 + TURN_AMPLITUDE * (std::f64::consts::TAU * t / TURN_PERIOD_S).sin()
}

fn yaw_rate_at(t: f64) -> f64 {
    let w = std::f64::consts::TAU / TURN_PERIOD_S;
    TURN_AMPLITUDE * w * (w * t).cos()
}

fn compass(psi: f64) -> f64 {
    CompassDeg::from(Heading::from_radians(psi)).0
}

/// Beacon `i` of `n` at time t: circling its centre, `distance` from the start, at 0.5 m/s on a
/// 100 m radius.
fn beacon_at(i: u32, n: u32, t: f64, distance: f64) -> (f64, f64) {
    let bearing = std::f64::consts::TAU * f64::from(i) / f64::from(n.max(1));
    let phase = 0.5 * t / 100.0 + bearing;
    (distance * bearing.cos() + 100.0 * phase.cos(), distance * bearing.sin() + 100.0 * phase.sin())
}

/// The true AUV track sampled every `dt` (midpoint integration, fine enough to be the truth).
fn track(spec: &SyntheticSpec, dt: f64, steps: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(steps + 1);
    let (mut e, mut n) = (0.0, 0.0);
    out.push((e, n));
    for k in 0..steps {
        let psi = heading_at((k as f64 + 0.5) * dt);
        e += dt * (SPEED * psi.cos() + spec.current[0]);
        n += dt * (SPEED * psi.sin() + spec.current[1]);
        out.push((e, n));
    }
    out
}

/// The log rows in time order, and the truth rows among them.
pub fn synthetic_log(spec: &SyntheticSpec) -> Vec<LogRow> {
    let streams = SeedStream::new(spec.seed);
    let (mut sensors, mut acoustic) = (streams.rng(1), streams.rng(2));
    let dt = 1.0 / spec.rate_hz;
    let steps = (spec.duration_s * spec.rate_hz).round() as usize;
    let truth = track(spec, dt, steps);
    let at = |t: f64| {
        let x = (t / dt).clamp(0.0, steps as f64);
        let k = (x.floor() as usize).min(steps.saturating_sub(1));
        let f = x - k as f64;
        let (a, b) = (truth[k], truth[(k + 1).min(steps)]);
        (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1))
    };
    let row = |t: f64, obs: Observation| LogRow { t, obs, sigma: None };
    let init = Observation::Init { e: 0.0, n: 0.0, speed: SPEED, compass_deg: compass(heading_at(0.0)) };
    let mut rows = vec![row(0.0, init)];
    let (truth_every, range_every) = (
        (spec.truth_every_s * spec.rate_hz).round().max(1.0) as usize,
        (spec.range_every_s * spec.rate_hz).round().max(1.0) as usize,
    );
    let mut pending_ranges: Vec<LogRow> = Vec::new();
    for k in 1..=steps {
        let t = k as f64 * dt;
        // Ranges arrive within a second or two: put each in time order as its time comes.
        while pending_ranges.first().is_some_and(|r| r.t <= t) {
            rows.push(pending_ranges.remove(0));
        }
        let mut normal = || -> f64 { sensors.sample(StandardNormal) };
        let rate = -yaw_rate_at(t).to_degrees() + 0.05 * normal();
        rows.push(row(t, Observation::YawRate { compass_deg_s: rate }));
        rows.push(row(t, Observation::Speed(SPEED / spec.speed_scale + spec.speed_sd * normal())));
        let heading = compass(heading_at(t)) + spec.heading_bias_deg + spec.heading_sd_deg * normal();
        rows.push(row(t, Observation::Heading { compass_deg: heading.rem_euclid(360.0) }));
        if k % truth_every == 0 {
            let (e, n) = truth[k];
            rows.push(row(t, Observation::Truth { e, n }));
        }
        if k % range_every == 0 && spec.beacons > 0 {
            let beacon = (k / range_every) as u32 % spec.beacons;
            let (be, bn) = beacon_at(beacon, spec.beacons, t, spec.beacon_distance_m);
            let lost = spec.range_silence_s.is_some_and(|[from, to]| (from..=to).contains(&t));
            if !lost {
                rows.push(row(t, Observation::BeaconFix { beacon, e: be, n: bn, depth: 0.0, fixed: false }));
            }
            // Distance to where the AUV is on arrival (two fixed-point iterations).
            let dist = |tau: f64| {
                let (e, n) = at(t + tau);
                (e - be).hypot(n - bn)
            };
            let tau = dist(dist(0.0) / SOUND_SPEED) / SOUND_SPEED;
            let sd = (spec.range_sd_m.powi(2) + (tau * spec.sigma_sound_speed).powi(2)).sqrt();
            let noise: f64 = acoustic.sample(StandardNormal);
            let travel_time = (dist(tau) + sd * noise).max(0.1) / SOUND_SPEED;
            if !lost {
                pending_ranges.push(row(t + travel_time, Observation::Range { beacon, travel_time }));
            }
        }
    }
    rows.extend(pending_ranges.into_iter().filter(|r| r.t <= spec.duration_s));
    rows
}

/// The rows with `extra_m` of range added to every `every`-th range (an echo: a longer path).
pub fn with_echoes(rows: &[LogRow], every: usize, extra_m: f64) -> Vec<LogRow> {
    let mut k = 0;
    rows.iter()
        .map(|r| match r.obs {
            Observation::Range { beacon, travel_time } => {
                k += 1;
                let travel_time = if k % every == 0 { travel_time + extra_m / SOUND_SPEED } else { travel_time };
                LogRow { obs: Observation::Range { beacon, travel_time }, ..*r }
            }
            _ => *r,
        })
        .collect()
}

/// The rows from `at` s on shifted `by` s later (a logger clock that jumped forward).
pub fn with_clock_jump(rows: &[LogRow], at: f64, by: f64) -> Vec<LogRow> {
    rows.iter().map(|r| if r.t >= at { LogRow { t: r.t + by, ..*r } } else { *r }).collect()
}

/// The rows with the `init` row's position `offset_e_m` east of where the AUV starts.
pub fn with_start_off(rows: &[LogRow], offset_e_m: f64) -> Vec<LogRow> {
    rows.iter()
        .map(|r| match r.obs {
            Observation::Init { e, n, speed, compass_deg } => {
                LogRow { obs: Observation::Init { e: e + offset_e_m, n, speed, compass_deg }, ..*r }
            }
            _ => *r,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_auv_stays_near_its_start_and_ranges_match_the_truth() {
        let spec = SyntheticSpec { duration_s: 7200.0, range_sd_m: 0.0, sigma_sound_speed: 0.0, ..Default::default() };
        let rows = synthetic_log(&spec);
        let truth: Vec<(f64, f64, f64)> = rows
            .iter()
            .filter_map(|r| match r.obs {
                Observation::Truth { e, n } => Some((r.t, e, n)),
                _ => None,
            })
            .collect();
        assert_eq!(truth.len(), 720);
        let far = truth.iter().map(|p| p.1.hypot(p.2)).fold(0.0, f64::max);
        assert!(far < 1000.0, "the AUV wandered {far} m away");
        let ranges = rows.iter().filter(|r| matches!(r.obs, Observation::Range { .. })).count();
        // One ping every 15 s; the last one (sent at the end) arrives after the log ends.
        assert_eq!(ranges, 479);
        assert!(rows.windows(2).all(|w| w[0].t <= w[1].t), "rows in time order");
    }

    #[test]
    fn the_field_like_run_has_three_pings_then_a_minute_of_silence() {
        let rows = synthetic_log(&SyntheticSpec::field_like(1));
        let sent: Vec<f64> = rows
            .iter()
            .filter_map(|r| match r.obs {
                Observation::Range { travel_time, .. } => Some(r.t - travel_time),
                _ => None,
            })
            .collect();
        assert_eq!(sent.len(), 51, "{sent:?}");
        assert!((sent[2] - 54.0).abs() < 1e-9 && (sent[3] - 126.0).abs() < 1e-9, "{sent:?}");
        let truth = rows.iter().filter(|r| matches!(r.obs, Observation::Truth { .. })).count();
        assert_eq!(truth, 990);
        // The same noise on the ranges after the silence as without it.
        let all = synthetic_log(&SyntheticSpec { range_silence_s: None, ..SyntheticSpec::field_like(1) });
        let tail = |rows: &[LogRow]| rows.iter().filter(|r| r.t > 130.0).copied().collect::<Vec<_>>();
        assert_eq!(tail(&rows), tail(&all));
    }
}
