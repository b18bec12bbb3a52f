//! One run: both vehicles' policies, trackers and shadow estimators over a prepared scenario.
//! Every packet's frame 0 is really encoded and, when it arrives, decoded — the receiver learns
//! only what the bits carry.

use super::metrics::{RunMetrics, Tally};
use super::prepare::Prepared;
use super::scenario::{Behaviour, EstimatorMode, ExperimentConfig, Scenario};
use coopnav_acomms::estimator::{Knowledge, ShadowEstimator};
use coopnav_acomms::selector::{Choice, Outcome, RatePolicy};
use coopnav_acomms::status::{Frame0, LocalOrigin, NextWaypoint, StatusMessage};
use coopnav_acomms::tracker::{Delivery, MaskWidth, Tracker};
use coopnav_acomms::{Rate, SuccessModel, Tdma};
use coopnav_core::geometry::horizontal_distance;
use coopnav_core::{Bathymetry, DepthTarget, SeedStream};
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum WorldError {
    #[error("behaviour: {0}")]
    Behaviour(String),
    #[error("slot {slot}: frame 0 does not encode: {message}")]
    Encode { slot: u64, message: String },
    #[error("slot {slot}: frame 0 does not decode: {message}")]
    Decode { slot: u64, message: String },
}

/// One vehicle's comms stack.
struct Node {
    policy: Box<dyn RatePolicy>,
    tracker: Tracker,
    estimator: ShadowEstimator,
    outcomes: Vec<Outcome>,
    heard: bool,
    rng: ChaCha8Rng,
}

fn status(p: &Prepared, k: usize, v: usize, mode: EstimatorMode, origin: &LocalOrigin) -> StatusMessage {
    let s = p.samples[k][v];
    let next = match mode {
        EstimatorMode::PrePlanned => NextWaypoint::Id(s.next_wp.min(254) as u8),
        EstimatorMode::Dynamic => {
            let plan = &p.plans[v];
            let wp = plan[s.next_wp.min(plan.len() - 1)];
            let (lat, lon) = origin.to_latlon(wp.x, wp.y);
            NextWaypoint::LatLon { lat, lon }
        }
    };
    StatusMessage { pos: s.pos, heading: s.heading, speed: s.speed, next }
}

fn node(
    v: usize,
    p: &Prepared,
    scenario: &Scenario,
    cfg: &ExperimentConfig,
    behaviour: &Behaviour,
    seeds: &SeedStream,
    origin: LocalOrigin,
) -> Result<Node, WorldError> {
    let policy = behaviour.build().map_err(WorldError::Behaviour)?;
    let rates = policy.rates();
    let width = MaskWidth::for_rates(rates.iter().copied());
    let min_frame = rates.iter().map(|r| r.spec().frame_bytes).min().unwrap_or(32);
    let status_bits = status(p, 0, v, cfg.estimator, &origin).bits();
    let tracker = Tracker::new(v, 2, width, Frame0::max_header_entries(min_frame, status_bits, width));
    let peer = 1 - v;
    let estimator = match cfg.estimator {
        EstimatorMode::PrePlanned => ShadowEstimator::new(
            Knowledge::PrePlanned { plan: p.plans[peer].clone() },
            cfg.vehicle,
            Some(p.starts[peer]),
        ),
        EstimatorMode::Dynamic => ShadowEstimator::new(
            Knowledge::Dynamic {
                target: DepthTarget::Altitude { altitude: scenario.altitude },
                speed: scenario.speed,
                origin,
            },
            cfg.vehicle,
            None,
        ),
    };
    Ok(Node { policy, tracker, estimator, outcomes: Vec::new(), heard: false, rng: seeds.rng(1 + v as u64) })
}

/// Slot length the behaviour forces on the network (15 s if it may use rate 5).
pub fn slot_length(cfg: &ExperimentConfig, behaviour: &Behaviour) -> Result<f64, WorldError> {
    let rates: Vec<Rate> = behaviour.rates().map_err(WorldError::Behaviour)?;
    Ok(cfg.tdma.slot_length(rates, cfg.ack))
}

/// Runs one repetition.
pub fn run(
    p: &Prepared,
    scenario: &Scenario,
    cfg: &ExperimentConfig,
    bathy: &Bathymetry,
    behaviour: &Behaviour,
    seed: u64,
) -> Result<RunMetrics, WorldError> {
    let origin = LocalOrigin::default();
    let seeds = SeedStream::new(seed);
    let mut nodes =
        [node(0, p, scenario, cfg, behaviour, &seeds, origin)?, node(1, p, scenario, cfg, behaviour, &seeds, origin)?];
    let success = SuccessModel { noise_db: scenario.noise_db, ..cfg.success.clone() };
    let mut tally = Tally::for_vehicles(2);
    for k in 0..p.samples.len() {
        let slot = k as u64;
        let t = k as f64 * p.slot_len;
        let s = Tdma::owner(slot, 2);
        let r = 1 - s;
        let own_pos = p.samples[k][s].pos;
        let tx = &mut nodes[s];
        let outcomes = std::mem::take(&mut tx.outcomes);
        tx.policy.feedback(&outcomes, std::mem::take(&mut tx.heard));
        let estimate = tx.estimator.estimate(t, bathy);
        if let Some(e) = estimate {
            let err = horizontal_distance(&e, &p.samples[k][r].pos);
            tally.estimate_error_sum += err;
            tally.estimate_error_max = tally.estimate_error_max.max(err);
            tally.decisions += 1;
        }
        let distance = estimate.map(|e| horizontal_distance(&own_pos, &e));
        tally.opportunities += 1;
        let Choice::Transmit(rate) = tx.policy.choose(slot, distance) else { continue };
        let header = tx.tracker.on_transmit(slot, rate);
        let width = tx.tracker.width();
        tally.transmissions += 1;
        tally.rate_use[rate.index() as usize] += 1;
        tally.queue_len_sum += header.entries.len() as u64;
        tally.queue_len_max = tally.queue_len_max.max(header.entries.len() as u64);
        tally.header_bits += header.bits(width) as u64;
        let frame = Frame0 { header, status: status(p, k, s, cfg.estimator, &origin) };
        let spec = rate.spec();
        let bytes =
            frame.encode(width, spec.frame_bytes).map_err(|e| WorldError::Encode { slot, message: e.to_string() })?;
        let reception = success.draw(rate, p.tl[k], scenario.receiver, &mut tx.rng);
        if !reception.received() {
            continue;
        }
        let decoded = if reception.frame0() {
            Some(Frame0::decode(&bytes, width).map_err(|e| WorldError::Decode { slot, message: e.to_string() })?)
        } else {
            None
        };
        let rx = &mut nodes[r];
        rx.heard = true;
        let resolved = rx.tracker.on_receive(slot, s, reception, decoded.as_ref().map(|f| &f.header));
        rx.outcomes.extend(
            resolved
                .iter()
                .map(|res| Outcome { slot: res.slot, success: matches!(res.delivery, Delivery::Received { .. }) }),
        );
        let gross = reception.count() as u64 * spec.frame_bytes as u64;
        tally.bytes_gross += gross;
        tally.bytes_net += gross - if decoded.is_some() { bytes.len() as u64 } else { 0 };
        if let Some(f) = decoded {
            rx.estimator.on_status(&f.status, t);
            tally.status_received(r, t);
        }
    }
    Ok(RunMetrics::from_tally(&tally, p.duration, p.mean_distance))
}

#[cfg(test)]
mod tests {
    use super::super::prepare::prepare;
    use super::*;
    use coopnav_acomms::{TlError, TransmissionLoss};
    use coopnav_core::{run_seed, Shelf, Vec3};

    /// A channel with the same TL everywhere.
    struct Flat(f64);
    impl TransmissionLoss for Flat {
        fn tl(&self, _: &Vec3, _: &Vec3) -> Result<f64, TlError> {
            Ok(self.0)
        }
    }

    fn mean_bw(behaviour: Behaviour, tl_db: f64) -> RunMetrics {
        mean_with(ExperimentConfig::default(), behaviour, tl_db)
    }

    fn mean_with(cfg: ExperimentConfig, behaviour: Behaviour, tl_db: f64) -> RunMetrics {
        let scenario = Scenario::thesis(1);
        let bathy = Bathymetry::shelf(&Shelf::default()).unwrap();
        let p = prepare(&scenario, &cfg, &bathy, &Flat(tl_db), slot_length(&cfg, &behaviour).unwrap()).unwrap();
        let runs: Vec<RunMetrics> =
            (0..8).map(|i| run(&p, &scenario, &cfg, &bathy, &behaviour, run_seed(9, i)).unwrap()).collect();
        RunMetrics::mean_sd(&runs).0
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
        // Pre-planned shadows, a status every ~11 s: the estimate stays within a few metres.
        assert!(
            m.estimate_error_mean < 5.0 && m.estimate_error_max < 25.0,
            "{} / {}",
            m.estimate_error_mean,
            m.estimate_error_max
        );
    }

    #[test]
    fn dynamic_estimates_are_worse_than_preplanned_but_bounded() {
        // Without the plan, the shadow stops at the reported next waypoint: errors grow during
        // droughts (rate 1 at 60 dB: p = 0.6) but a report resets them.
        let dynamic = ExperimentConfig {
            estimator: super::super::scenario::EstimatorMode::Dynamic,
            ..ExperimentConfig::default()
        };
        let d = mean_with(dynamic, Behaviour::Fixed { rate: Rate::R1 }, 60.0);
        let p = mean_bw(Behaviour::Fixed { rate: Rate::R1 }, 60.0);
        println!(
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
