//! The live navigator without a socket, against post-processing's batch forward filter.
//!
//! The expected values come from `coopnav_nav::post::postprocess_rows`, a separate code path
//! over the same model: post sorts a whole log, matches each range to its beacon's logged fix
//! and runs `AuvEkf` over the rows; the navigator decodes LCM payloads one at a time, buffers
//! them, and calls `AuvEkf` itself. The rows post gets are built here from the synthetic log with
//! the quantisation the messages impose (µs times, f32 speed, compass through radians), not from
//! the navigator's decoding. Post's samples carry position and its SDs, so x, y and √P_EE, √P_NN
//! are compared bit for bit.

use coopnav_lcm::messages::{AuvSensors, Message, OwttRange};
use coopnav_lcm::Schema;
use coopnav_live::synthetic::{stream, utime, Stream, StreamMessage};
use coopnav_live::{AuvNavigator, LiveConfig, Published};
use coopnav_nav::fieldlog::{LogRow, Observation};
use coopnav_nav::post::{postprocess_rows, PostSample};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use std::collections::BTreeMap;

const AUV: i16 = 3;

fn spec(duration_s: f64) -> SyntheticSpec {
    SyntheticSpec { duration_s, ..SyntheticSpec::default() }
}

/// Post-processing's rows for the same inputs as the stream: the log's speed and compass rows as
/// the messages carry them (no yaw-rate rows), each range with its beacon's fix at its transmit
/// time, and an `init` at the first step at the navigator's start (0, 0).
fn post_rows(spec: &SyntheticSpec, drop_range: Option<usize>) -> Vec<LogRow> {
    let row = |t: f64, obs| LogRow { t, obs, sigma: None };
    let mut rows = Vec::new();
    let mut fixes = BTreeMap::new();
    let mut speed = None;
    let mut ranges = 0;
    for r in synthetic_log(spec) {
        let t = utime(r.t) as f64 / 1e6;
        match r.obs {
            Observation::Speed(s) => speed = Some(f64::from(s as f32)),
            Observation::Heading { compass_deg } => {
                let s = speed.take().unwrap();
                let compass = compass_deg.to_radians().to_degrees();
                if rows.is_empty() {
                    rows.push(row(t, Observation::Init { e: 0.0, n: 0.0, speed: s, compass_deg: compass }));
                }
                rows.push(row(t, Observation::Speed(s)));
                rows.push(row(t, Observation::Heading { compass_deg: compass }));
                rows.push(row(t, Observation::Depth(0.0)));
            }
            Observation::BeaconFix { beacon, e, n, depth, .. } => {
                fixes.insert(beacon, (e, n, depth));
            }
            Observation::Range { beacon, travel_time } => {
                ranges += 1;
                if drop_range == Some(ranges - 1) {
                    continue;
                }
                let (e, n, depth) = fixes[&beacon];
                // The fix at exactly the transmit time post recovers (receive − travel time).
                rows.push(row(r.t - travel_time, Observation::BeaconFix { beacon, e, n, depth, fixed: false }));
                rows.push(row(r.t, Observation::Range { beacon, travel_time }));
            }
            _ => {}
        }
    }
    rows
}

fn run(messages: &[StreamMessage]) -> (Vec<Published>, AuvNavigator) {
    run_with(messages, LiveConfig::default())
}

fn run_with(messages: &[StreamMessage], cfg: LiveConfig) -> (Vec<Published>, AuvNavigator) {
    let mut nav = AuvNavigator::new(AUV, cfg).unwrap();
    let mut out = Vec::new();
    for m in messages {
        out.extend(nav.handle(&m.channel, &m.payload).unwrap());
    }
    out.extend(nav.flush().unwrap());
    (out, nav)
}

/// The last value at each time (by the time's bits).
fn last_at<T: Clone>(items: impl Iterator<Item = (f64, T)>) -> BTreeMap<u64, T> {
    items.map(|(t, v)| (t.to_bits(), v)).collect()
}

fn assert_same_as_post(live: &[Published], post: &[PostSample]) {
    let post = last_at(post.iter().map(|s| (s.t, *s)));
    let live_last = last_at(live.iter().map(|p| (p.t, p.clone())));
    assert!(!live_last.is_empty());
    for (bits, p) in &live_last {
        let s = post.get(bits).unwrap_or_else(|| panic!("post has no step at t = {} s", f64::from_bits(*bits)));
        let e = &p.estimate;
        assert_eq!(
            [e.x.to_bits(), e.y.to_bits(), e.cov[0][0].sqrt().to_bits(), e.cov[1][1].sqrt().to_bits()],
            [s.filtered[0].to_bits(), s.filtered[1].to_bits(), s.filtered_sd[0].to_bits(), s.filtered_sd[1].to_bits()],
            "t = {} s: live {e:?}, post {s:?}",
            p.t
        );
    }
}

fn estimates(live: &[Published]) -> Vec<(u64, [u64; 6])> {
    live.iter()
        .map(|p| {
            let e = &p.estimate;
            let c = e.cov;
            (p.t.to_bits(), [e.x, e.y, c[0][0], c[0][1], c[1][0], c[1][1]].map(f64::to_bits))
        })
        .collect()
}

/// The filter's config for the synthetic mission: Gill's Q_E = Q_N = 0.255 m² a step absorbs a
/// field AUV's unmodelled motion (currents); the synthetic AUV has none (no current, its errors
/// are its speed and compass noise, which the filter has states for), so with it the covariance
/// is ~6 times too large (mean NEES 0.25–0.31 over seeds 1–3). 1e-4 m² a step is the synthetic
/// mission's own model.
fn synthetic_config() -> LiveConfig {
    let mut cfg = LiveConfig::default();
    cfg.filter.auv.q[0] = 1e-4;
    cfg.filter.auv.q[1] = 1e-4;
    cfg
}

/// 2-D NEES of every truth point against the estimate published at its time.
fn nees(live: &[Published], truth: &[(f64, f64, f64)]) -> Vec<f64> {
    let by_utime: BTreeMap<i64, &Published> = live.iter().map(|p| (p.estimate.utime, p)).collect();
    truth
        .iter()
        .map(|&(t, e, n)| {
            let p = by_utime[&utime(t)];
            let c = p.estimate.cov;
            let (dx, dy) = (p.estimate.x - e, p.estimate.y - n);
            let det = c[0][0] * c[1][1] - c[0][1] * c[1][0];
            (c[1][1] * dx * dx - 2.0 * c[0][1] * dx * dy + c[0][0] * dy * dy) / det
        })
        .collect()
}

/// [`synthetic_config`] with the sigma-point range update and the range health check, and its
/// position process noise cut to 10⁻⁸ m² a step, so over-confident that its ranges leave their
/// bounds and it recovers.
fn recovering_config() -> LiveConfig {
    let mut cfg = synthetic_config();
    cfg.filter.auv.range_update = coopnav_nav::RangeLinearisation::Unscented;
    cfg.filter.auv.range_health = Some(coopnav_nav::consistency::RangeHealth::default());
    cfg.filter.auv.q[0] = 1e-8;
    cfg.filter.auv.q[1] = 1e-8;
    cfg.filter.auv.q[3] = 1e-12;
    cfg
}

#[test]
fn estimates_equal_post_processings_forward_filter_bit_for_bit() {
    let spec = spec(3600.0);
    for cfg in [LiveConfig::default(), synthetic_config(), recovering_config()] {
        let Stream { messages, .. } = stream(&spec, AUV);
        let (live, nav) = run_with(&messages, cfg.clone());
        let counts = nav.counts();
        let post = postprocess_rows(&post_rows(&spec, None), &cfg.post_equivalent()).unwrap();
        assert_same_as_post(&live, &post.samples);
        assert_eq!(counts.ranges_applied as usize, post.summary.ranges_applied);
        assert_eq!(counts.ranges_gated as usize, post.summary.ranges_gated);
        let recovering = cfg.filter.auv.range_health.is_some();
        eprintln!("recoveries {} (health check {recovering})", counts.recoveries);
        assert_eq!(counts.recoveries > 0, recovering, "{counts:?}");
        assert_eq!(counts.sensors_applied, 36_000);
        assert_eq!(counts.estimates_published as usize, live.len());
        assert_eq!((counts.malformed, counts.duplicates, counts.stale), (0, 0, 0));
        // One ping every 15 s; the last one arrives after the log ends.
        assert_eq!(counts.ranges_applied + counts.ranges_gated, 239, "{counts:?}");
        // Every published payload decodes to the estimate beside it.
        let schema = Schema::coopnav();
        for p in live.iter().step_by(997) {
            assert_eq!(coopnav_lcm::messages::AuvEstimate::decode(&schema, &p.payload).unwrap(), p.estimate);
        }
    }
}

/// The error against the truth is bounded by the covariance: the 2-D NEES at the truth points is
/// χ² with 2 degrees of freedom (mean 2, SD 2) when the covariance is right. The 4 × 360 points,
/// 10 s apart, are far from independent: the error decorrelates over a few 15 s ping intervals,
/// and one seed's mean ranges 1.4–2.3 over seeds 1–3, the spread of ~30 independent samples
/// (2/√30 ≈ 0.37). So 4 seeds are worth ~120 samples, the pooled mean's SD is 2/√120 ≈ 0.18, and
/// the band [1.45, 2.55] is ±3 of those SDs. Seeds 1–4 give 2.29, 1.58, 1.44, 1.05, pooled
/// 1.59: the covariance is consistent within the band, on its conservative side.
#[test]
fn the_error_against_the_truth_is_bounded_by_the_covariance() {
    let mut all = Vec::new();
    for seed in 1..=4 {
        let spec = SyntheticSpec { seed, ..spec(3600.0) };
        let Stream { messages, truth } = stream(&spec, AUV);
        let (live, _) = run_with(&messages, synthetic_config());
        let n = nees(&live, &truth);
        assert_eq!(n.len(), 360);
        println!("seed {seed}: mean NEES {:.3}", n.iter().sum::<f64>() / n.len() as f64);
        all.extend(n);
    }
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    println!("mean NEES over {} truth points: {mean:.3}", all.len());
    assert!((1.45..=2.55).contains(&mean), "mean NEES {mean}");
}

/// A range message, by its index among the stream's ranges.
fn range_index(messages: &[StreamMessage], k: usize) -> usize {
    messages.iter().enumerate().filter(|(_, m)| m.channel.ends_with("_RANGE")).nth(k).unwrap().0
}

#[test]
fn a_duplicated_or_reordered_message_changes_nothing_and_is_counted() {
    let spec = spec(600.0);
    let clean = stream(&spec, AUV).messages;
    let (expected, _) = run(&clean);
    // Duplicates: a range and a sensors message sent twice, once at once and once a second later.
    let mut dup = clean.clone();
    let r = range_index(&dup, 5);
    dup.insert(r + 1, dup[r].clone());
    let s = r + 20;
    dup.insert(s + 10, dup[s].clone());
    // Reordered: a range and the sensors message after it swapped; a sensors message 1 s late.
    let r2 = range_index(&dup, 12);
    dup.swap(r2, r2 + 1);
    let late = r2 + 100;
    let m = dup.remove(late);
    dup.insert(late + 10, m);
    let (live, nav) = run(&dup);
    assert_eq!(estimates(&live), estimates(&expected));
    let c = nav.counts();
    assert_eq!((c.duplicates, c.stale, c.malformed), (2, 0, 0), "{c:?}");
}

#[test]
fn a_dropped_message_costs_only_its_update() {
    let spec = spec(600.0);
    let mut messages = stream(&spec, AUV).messages;
    messages.remove(range_index(&messages, 7));
    let (live, nav) = run(&messages);
    let post = postprocess_rows(&post_rows(&spec, Some(7)), &LiveConfig::default().post_equivalent()).unwrap();
    assert_same_as_post(&live, &post.samples);
    let ranges = stream(&spec, AUV).messages.iter().filter(|m| m.channel.ends_with("_RANGE")).count() as u64;
    assert_eq!(nav.counts().messages["COOPNAV_AUV3_RANGE"], ranges - 1);
}

#[test]
fn malformed_stale_and_foreign_messages_are_counted_and_change_nothing() {
    let spec = spec(600.0);
    let clean = stream(&spec, AUV).messages;
    let (expected, _) = run(&clean);
    let schema = Schema::coopnav();
    let mut bad = clean.clone();
    let r = range_index(&bad, 4);
    let range = OwttRange::decode(&schema, &bad[r].payload).unwrap();
    let sensors_at = r + 3;
    let sensors = AuvSensors::decode(&schema, &bad[sensors_at].payload).unwrap();
    let at = |t: f64, channel: &str, payload: Vec<u8>| StreamMessage { t, channel: channel.into(), payload };
    let injected = vec![
        // Garbage, a truncated payload, and a payload of the wrong type.
        at(0.0, "COOPNAV_AUV3_RANGE", vec![0xde, 0xad, 0xbe, 0xef]),
        at(0.0, "COOPNAV_AUV3_SENSORS", bad[sensors_at].payload[..20].to_vec()),
        at(0.0, "COOPNAV_AUV3_SENSORS", bad[r].payload.clone()),
        // Values that cannot be a measurement.
        at(0.0, "COOPNAV_AUV3_RANGE", OwttRange { travel_time: f64::NAN, ..range }.encode(&schema).unwrap()),
        at(0.0, "COOPNAV_AUV3_RANGE", OwttRange { travel_time: -0.5, ..range }.encode(&schema).unwrap()),
        at(
            0.0,
            "COOPNAV_AUV3_RANGE",
            OwttRange { transmit_time: range.transmit_time - 1.0, ..range }.encode(&schema).unwrap(),
        ),
        at(
            0.0,
            "COOPNAV_AUV3_SENSORS",
            AuvSensors { speed: f32::INFINITY, ..sensors.clone() }.encode(&schema).unwrap(),
        ),
        // A time a day ahead (a corrupt clock).
        at(
            0.0,
            "COOPNAV_AUV3_SENSORS",
            AuvSensors { utime: sensors.utime + 86_400_000_000, ..sensors.clone() }.encode(&schema).unwrap(),
        ),
        // Another AUV's sensors, and a channel the navigator does not read.
        at(
            0.0,
            "COOPNAV_AUV3_SENSORS",
            AuvSensors { auv: 4, utime: sensors.utime + 1, ..sensors.clone() }.encode(&schema).unwrap(),
        ),
        at(0.0, "COOPNAV_AUV3_CLOCK", vec![1, 2, 3]),
    ];
    for (i, m) in injected.into_iter().enumerate() {
        bad.insert(sensors_at + 2 * i, m);
    }
    // A stale message: a sensors message replayed 30 s (past the 2 s window) later, changed so
    // that it is not a duplicate.
    let old = AuvSensors::decode(&schema, &clean[100].payload).unwrap();
    let stale = AuvSensors { speed: old.speed + 0.5, ..old };
    bad.insert(400, at(0.0, "COOPNAV_AUV3_SENSORS", stale.encode(&schema).unwrap()));
    let (live, nav) = run(&bad);
    assert_eq!(estimates(&live), estimates(&expected));
    let c = nav.counts();
    assert_eq!((c.malformed, c.wrong_auv, c.other_channel, c.stale, c.duplicates), (7, 1, 1, 1, 0), "{c:?}");
    assert_eq!((c.implausible_time, c.clock_jumps), (1, 0), "{c:?}");
}

#[test]
fn a_clock_jump_seen_in_several_messages_in_a_row_is_taken() {
    let spec = spec(120.0);
    let mut messages = stream(&spec, AUV).messages;
    let schema = Schema::coopnav();
    // From message 500 on, every sensors message an hour later (ranges dropped: they keep the old
    // clock and would be stale).
    messages.retain(|m| m.channel.ends_with("_SENSORS"));
    for m in &mut messages[500..] {
        let s = AuvSensors::decode(&schema, &m.payload).unwrap();
        m.payload = AuvSensors { utime: s.utime + 3_600_000_000, ..s }.encode(&schema).unwrap();
    }
    let (live, nav) = run(&messages);
    let c = nav.counts();
    assert_eq!((c.implausible_time, c.clock_jumps, c.gaps), (3, 1, 1), "{c:?}");
    assert_eq!(c.sensors_applied as usize, messages.len() - 3);
    assert!(live.last().unwrap().t > 3600.0);
}

#[test]
fn a_full_reorder_buffer_applies_its_oldest_message_early_and_counts_it() {
    let messages = stream(&spec(300.0), AUV).messages;
    let (expected, _) = run(&messages);
    // A window longer than the stream: only the buffer's bound releases messages before the end.
    let cfg = LiveConfig { reorder_window_s: 600.0, ..LiveConfig::default() };
    let (live, nav) = run_with(&messages, cfg);
    assert_eq!(estimates(&live), estimates(&expected));
    let c = nav.counts();
    assert_eq!(c.released_early as usize, messages.len() - coopnav_live::auv::MAX_BUFFERED, "{c:?}");
}
