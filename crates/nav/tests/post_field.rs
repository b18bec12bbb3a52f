//! Post-processing field logs: no stale transponder fixes (a log whose times are
//! rounded to the millisecond, as field loggers write them, gives the estimates of the exact log),
//! the current states and the default NIS gate.

use coopnav_core::{CompassDeg, Heading, SeedStream};
use coopnav_nav::cycle::Transmitter;
use coopnav_nav::post::{postprocess, AuvModel, Entry, FixMatching, FixUse, PostConfig, PostResult, Record};
use coopnav_nav::{CurrentParams, Gate, Side};
use rand::Rng;
use rand_distr::StandardNormal;

const SOUND_SPEED: f64 = 1500.0;

/// A 20-minute mission: the AUV runs north-east at 1.5 m/s through the water with a slow turn,
/// carried by a water `current` (m/s); a buoy drifts at 0.5 m/s and pings at the top of every 10th
/// second (its topside fix logged at that instant); a ship steaming north at 0.5 m/s 800 m to the
/// east pings from its port outrigger 5 s later (DGPS fixes every second); speed, heading and
/// truth rows at 10 Hz. Exact times, seeded noise on the sensors and ranges.
fn mission_in(seed: u64, current: [f64; 2]) -> Vec<Entry> {
    let mut rng = SeedStream::new(seed).rng(0);
    let mut normal = move || -> f64 { rng.sample(StandardNormal) };
    // Constant speed and turn rate: an arc, so the dead reckoning inputs match the truth exactly.
    let (speed, rate, psi_start) = (1.5, 2e-4, 0.6f64);
    let auv = |t: f64| {
        let psi = psi_start + rate * t;
        let r = speed / rate;
        let drift = [current[0] * t, current[1] * t];
        (
            100.0 + r * (psi.sin() - psi_start.sin()) + drift[0],
            -50.0 - r * (psi.cos() - psi_start.cos()) + drift[1],
            psi,
        )
    };
    let buoy = |t: f64| (400.0 + 0.5 * t * 0.3f64.cos(), 300.0 - 0.5 * t * 0.3f64.sin());
    let ship = |t: f64| (1000.0, -300.0 + 0.5 * t);
    let outriggers = PostConfig::default().outriggers;
    let north = std::f64::consts::FRAC_PI_2;
    let compass = |psi: f64| CompassDeg::from(Heading::from_radians(psi)).0;
    let (e0, n0, psi0) = auv(0.0);
    let mut log = vec![Entry { t: 0.0, record: Record::Init { e: e0, n: n0, speed: 1.5, compass_deg: compass(psi0) } }];
    for k in 1..=12_000 {
        let t = k as f64 * 0.1;
        let (e, n, psi) = auv(t);
        log.push(Entry { t, record: Record::Speed(speed + 0.05 * normal()) });
        log.push(Entry { t, record: Record::Heading { compass_deg: compass(psi) + 0.5 * normal() } });
        log.push(Entry { t, record: Record::YawRate { compass_deg_s: -rate.to_degrees() } });
        log.push(Entry { t, record: Record::Truth { e, n } });
        if k % 10 == 0 {
            let (se, sn) = ship(t);
            let fix = Record::ShipFix { e: se + 0.1 * normal(), n: sn + 0.1 * normal(), compass_deg: compass(north) };
            log.push(Entry { t, record: fix });
        }
        let (from, at) = match k % 100 {
            0 => (Transmitter::Buoy, buoy(t)),
            50 => {
                let p = outriggers.position(Side::Port, ship(t).0, ship(t).1, north);
                (Transmitter::Ship(Side::Port), (p.x, p.y))
            }
            _ => continue,
        };
        if from == Transmitter::Buoy {
            log.push(Entry { t, record: Record::BuoyFix { e: at.0 + 0.1 * normal(), n: at.1 + 0.1 * normal() } });
        }
        // OWTT to where the AUV is on arrival (one fixed-point iteration, as a modem sees it).
        let dist = |h: f64| {
            let (e, n, _) = auv(t + h);
            (e - at.0).hypot(n - at.1)
        };
        let tau = dist(dist(0.0) / SOUND_SPEED) / SOUND_SPEED + 1e-4 * normal();
        log.push(Entry { t: t + tau, record: Record::Range { src: from, travel_time: tau } });
    }
    log.sort_by(|a, b| a.t.total_cmp(&b.t));
    log
}

fn mission(seed: u64) -> Vec<Entry> {
    mission_in(seed, [0.0, 0.0])
}

/// The same log with every time rounded to the millisecond.
fn rounded(log: &[Entry]) -> Vec<Entry> {
    log.iter().map(|e| Entry { t: (e.t * 1e3).round() / 1e3, record: e.record }).collect()
}

/// Largest smoothed-position difference between two runs at their common truth points.
fn max_difference(a: &PostResult, b: &PostResult) -> f64 {
    let at_truth =
        |r: &PostResult| r.samples.iter().filter(|s| s.truth.is_some()).map(|s| s.smoothed).collect::<Vec<_>>();
    let (pa, pb) = (at_truth(a), at_truth(b));
    assert_eq!(pa.len(), pb.len());
    pa.iter().zip(&pb).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max)
}

#[test]
fn millisecond_rounded_log_gives_the_exact_logs_estimates() {
    let cfg = PostConfig::default();
    for seed in 0..3 {
        let exact_log = mission(seed);
        let exact = postprocess(&exact_log, &cfg).unwrap();
        let round = postprocess(&rounded(&exact_log), &cfg).unwrap();
        assert_eq!(exact.summary.ranges, 240);
        assert_eq!(round.summary.ranges_applied, exact.summary.ranges_applied, "{:?}", round.summary);
        assert_eq!(round.summary.ranges_without_fix, 0);
        // Rounding moves each row by ≤ 0.5 ms: ≤ 0.75 mm of AUV dead reckoning and ≤ 0.25 mm of
        // buoy motion per range. 1 cm leaves a margin of ten over a few such steps adding up, and
        // is 100 times below the error of using the previous fix (asserted below).
        let d = max_difference(&exact, &round);
        assert!(d < 0.01, "seed {seed}: rounded log moved the smoothed track by {d} m");
        let (ee, er) = (exact.summary.mean_smoothed_error.unwrap(), round.summary.mean_smoothed_error.unwrap());
        assert!((ee - er).abs() < 0.01, "seed {seed}: mean smoothed error {ee} exact vs {er} rounded");
    }
}

#[test]
fn the_old_hold_without_tolerance_used_stale_fixes_on_rounded_logs() {
    // Today's matching, switched back to the old rule, shows what the test above guards against:
    // about half the ranges get the previous fix, 5 m behind the drifting buoy.
    let old = PostConfig {
        fixes: FixMatching { between: FixUse::Hold, match_tolerance_s: 0.0, ..FixMatching::default() },
        ..PostConfig::default()
    };
    let exact_log = mission(0);
    let exact = postprocess(&exact_log, &PostConfig::default()).unwrap();
    let stale = postprocess(&rounded(&exact_log), &old).unwrap();
    let d = max_difference(&exact, &stale);
    assert!(d > 1.0, "stale fixes moved the smoothed track by only {d} m");
}

#[test]
fn ranges_without_a_fresh_fix_and_rows_before_init_are_counted() {
    let mut log = mission(1);
    // Drop the buoy fixes after 10 minutes: the last 60 ranges lose their fix after max_age_s.
    log.retain(|e| !(e.t > 600.5 && matches!(e.record, Record::BuoyFix { .. })));
    log.insert(0, Entry { t: -5.0, record: Record::Speed(1.5) });
    log.push(Entry { t: 700.0, record: Record::Init { e: 0.0, n: 0.0, speed: 1.0, compass_deg: 0.0 } });
    let r = postprocess(&log, &PostConfig::default()).unwrap();
    let s = r.summary;
    let max_age = FixMatching::default().max_age_s;
    // Ranges at 610 … 1200 s; those within max_age_s of the fix at 600 s are still held.
    let stale = (61..=120).filter(|k| (*k as f64 * 10.0 - 600.0) > max_age).count();
    assert_eq!((s.ranges_without_fix, s.rows_before_init, s.extra_inits), (stale, 1, 1), "{s:?}");
    assert_eq!(s.ranges_applied + s.ranges_gated + s.ranges_unusable + s.ranges_without_fix, s.ranges);
    let w = s.warnings().join("\n");
    assert!(
        w.contains(&format!("{stale} range(s) had no transponder fix")) && w.contains("1 row(s) timed before"),
        "{w}"
    );
    assert!(w.contains("'init' row(s) after the first"), "{w}");
    assert!(postprocess(&mission(1), &PostConfig::default()).unwrap().summary.warnings().is_empty());
}

fn smoothed_error(r: &PostResult) -> f64 {
    r.summary.mean_smoothed_error.unwrap()
}

#[test]
fn current_states_estimate_the_current_and_beat_the_thesis_model_in_one() {
    let current = [0.15, -0.1];
    // The log's current is not known before the dive: a wide prior, (0.3 m/s)² and (0.3 m/s per hour)².
    let unknown = CurrentParams { p0: 0.09, q: 2.5e-6, ..CurrentParams::default() };
    let with_current = PostConfig { model: AuvModel::Current(unknown), ..PostConfig::default() };
    for seed in 0..3 {
        let log = mission_in(seed, current);
        let thesis = postprocess(&log, &PostConfig::default()).unwrap();
        let field = postprocess(&log, &with_current).unwrap();
        let (et, ef) = (smoothed_error(&thesis), smoothed_error(&field));
        assert!(ef < 0.5 * et, "seed {seed}: smoothed error {ef} m with current states vs {et} m without");
        let c = field.samples[field.samples.len() / 2].smoothed_current.unwrap();
        assert!((c[0] - current[0]).hypot(c[1] - current[1]) < 0.03, "seed {seed}: current {c:?} vs {current:?}");
        assert!(thesis.samples[0].smoothed_current.is_none());
    }
    // With no current, the current model must not do worse than a few centimetres.
    let still = mission(0);
    let (et, ef) = (
        smoothed_error(&postprocess(&still, &PostConfig::default()).unwrap()),
        smoothed_error(&postprocess(&still, &with_current).unwrap()),
    );
    assert!(ef < et + 0.05, "no current: {ef} m with current states vs {et} m without");
}

#[test]
fn the_default_gate_counts_an_outlier_instead_of_following_it() {
    let mut log = mission(2);
    // One range 60 m long (a multipath arrival), half way through.
    let k = log.iter().position(|e| e.t > 600.0 && matches!(e.record, Record::Range { .. })).unwrap();
    if let Record::Range { src, travel_time } = log[k].record {
        log[k].record = Record::Range { src, travel_time: travel_time + 60.0 / SOUND_SPEED };
    }
    let gated = postprocess(&log, &PostConfig::default()).unwrap();
    let open = postprocess(&log, &PostConfig { range_gate: Gate::OFF, ..PostConfig::default() }).unwrap();
    let clean = postprocess(&mission(2), &PostConfig::default()).unwrap();
    assert_eq!((gated.summary.ranges_gated, open.summary.ranges_gated), (1, 0));
    assert!(gated.summary.warnings().iter().any(|w| w.contains("1 range(s) were rejected")));
    let outlier: Vec<_> = gated.residuals.iter().filter(|r| !r.applied).collect();
    assert!(outlier.len() == 1 && outlier[0].innovation > 50.0 && outlier[0].smoothed > 50.0, "{outlier:?}");
    let (eg, eo, ec) = (smoothed_error(&gated), smoothed_error(&open), smoothed_error(&clean));
    assert!(eg < ec + 0.05 && eo > eg + 0.5, "gated {eg} m, ungated {eo} m, clean log {ec} m");
}

#[test]
fn model_and_gate_read_from_toml() {
    let c = PostConfig::from_toml("model = { kind = \"current\", p0 = 0.04 }\n").unwrap();
    assert_eq!(c.model, AuvModel::Current(CurrentParams { p0: 0.04, ..CurrentParams::default() }));
    let e = PostConfig::from_toml("model = { kind = \"current\", p1 = 0.04 }\n").unwrap_err().to_string();
    assert!(e.contains("p1"), "{e}");
    let e = PostConfig::from_toml("model = { kind = \"current\", q = -1.0 }\n").unwrap_err().to_string();
    assert!(e.contains("model.q"), "{e}");
    let e = PostConfig::from_toml("[auv.range_gate]\nmax_nis = 9.0\n").unwrap_err().to_string();
    assert!(e.contains("auv.range_gate") && e.contains("top-level range_gate"), "{e}");
    assert_eq!(PostConfig::from_toml("").unwrap().range_gate.max_nis, Some(10.83));
    let e = PostConfig::from_toml("transponder_sd_m = -1.0\n").unwrap_err().to_string();
    assert!(e.contains("transponder_sd_m"), "{e}");
}

#[test]
fn one_row_at_unix_time_in_a_relative_log_costs_one_step_not_ten_billion() {
    let mut log = mission(0);
    let rows = log.len();
    log.push(Entry { t: 1e9, record: Record::Speed(1.5) });
    let r = postprocess(&log, &PostConfig::default()).unwrap();
    assert_eq!(r.summary.gaps, 1);
    assert!(r.samples.len() < rows, "{} filter steps for {rows} rows", r.samples.len());
    assert!(r.summary.warnings().iter().any(|w| w.contains("1 silence(s) longer than max_gap_s")));
    assert_eq!(postprocess(&mission(0), &PostConfig::default()).unwrap().summary.gaps, 0);
}

#[test]
fn summary_reports_residuals_before_and_after_smoothing_and_error_figures() {
    // Ranges carry 0.15 m of timing noise and the fixes 0.1 m: smoothed residuals must come down
    // to that scale, and below the innovations, which also carry the prior's uncertainty.
    let with_current = PostConfig { model: AuvModel::Current(CurrentParams::default()), ..PostConfig::default() };
    let r = postprocess(&mission_in(1, [0.15, -0.1]), &with_current).unwrap();
    let s = r.summary;
    let (before, after) = (s.residual_rms_filter_m.unwrap(), s.residual_rms_smoothed_m.unwrap());
    assert!(after < before && after < 0.5, "residual RMS {before} m before, {after} m after smoothing");
    assert_eq!(r.residuals.len(), s.ranges_applied + s.ranges_gated);
    assert!(r.residuals.iter().all(|x| x.beacon == 13 || x.beacon == 14));
    let (mean, rms, max) =
        (s.mean_smoothed_error.unwrap(), s.rms_smoothed_error.unwrap(), s.max_smoothed_error.unwrap());
    assert!(mean <= rms && rms <= max && s.final_smoothed_error.unwrap() <= max, "{s:?}");
    assert!(s.rms_filtered_error.unwrap() > 0.0);
    let bare = postprocess(&[mission(0)[0]], &PostConfig::default()).unwrap().summary;
    assert_eq!((bare.residual_rms_filter_m, bare.rms_smoothed_error, bare.max_smoothed_error), (None, None, None));
}
