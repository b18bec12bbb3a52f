//! Tuning from the log and the general log format end to end: a synthetic
//! mission written with known noise is tuned back to it; a three-beacon mission with a current
//! post-processes from the version-2 file to a smoothed track better than the filter's.

use coopnav_nav::fieldlog::{read_field_log, write_field_log, FieldLog, TimeBase};
use coopnav_nav::post::{postprocess_rows, AuvModel, PostConfig};
use coopnav_nav::post_tune::{tune, TuneOptions};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use coopnav_nav::CurrentParams;

/// Known noise far from the defaults (range σ 1.8 m, scale 1, bias 0): range σ 4 m, the speed
/// log reading 4 % slow, the compass 3° off.
fn known_noise(seed: u64) -> SyntheticSpec {
    SyntheticSpec {
        duration_s: 3600.0,
        range_every_s: 10.0,
        range_sd_m: 4.0,
        speed_scale: 1.04,
        heading_bias_deg: 3.0,
        seed,
        ..SyntheticSpec::default()
    }
}

#[test]
fn tuning_recovers_the_noise_the_log_was_written_with() {
    let rows = synthetic_log(&known_noise(5));
    let r = tune(&rows, &PostConfig::default(), &TuneOptions::default()).unwrap();
    let (b, a) = (r.before, r.after);
    eprintln!("{}", serde_json_like(&r));
    // Stated bands: range σ within 25 %, speed scale within 0.02, compass bias (the fixed offset
    // with the smoothed bias state) within 1°.
    assert!((a.values.range_sd_m - 4.0).abs() < 1.0, "range σ {}", a.values.range_sd_m);
    assert!((a.values.speed_scale - 1.04).abs() < 0.02, "speed scale {}", a.values.speed_scale);
    assert!((a.compass_bias_deg - 3.0).abs() < 1.0, "compass bias {}", a.compass_bias_deg);
    assert!(a.held_out_log_predictive > b.held_out_log_predictive);
    // The held-out ranges (every 5th, never used by the filter) are predicted better.
    let (hb, ha) = (b.held_out_rms_smoothed_m.unwrap(), a.held_out_rms_smoothed_m.unwrap());
    assert!(ha < hb, "held-out RMS {hb} → {ha}");
    assert!(r.evaluations > 10 && r.hold_out_every == 5);
}

/// The search on 1-s block-averaged dead reckoning (the default) against the full-rate search on
/// the same 10 Hz log (20 minutes). Stated bands: range σ within 0.05 m, speed scale within
/// 0.001, compass offset within 0.15°, and the full-rate held-out log predictive density at both
/// results within 0.5 (the E/N process noise is near zero on this log, where the score is flat,
/// so it is compared through the score).
#[test]
fn block_averaged_search_agrees_with_the_full_rate_one() {
    let rows = synthetic_log(&SyntheticSpec { duration_s: 1200.0, ..known_noise(6) });
    let tuned = |block: f64| {
        let opts = TuneOptions { dead_reckoning_block_s: block, ..TuneOptions::default() };
        tune(&rows, &PostConfig::default(), &opts).unwrap().after
    };
    let (full, block) = (tuned(0.0), tuned(1.0));
    eprintln!("full rate {full:?}\nblocks {block:?}");
    let (f, b) = (full.values, block.values);
    assert!((f.range_sd_m - b.range_sd_m).abs() < 0.05, "range σ {} vs {}", f.range_sd_m, b.range_sd_m);
    assert!((f.speed_scale - b.speed_scale).abs() < 1e-3, "speed scale {} vs {}", f.speed_scale, b.speed_scale);
    assert!(
        (f.heading_bias_deg - b.heading_bias_deg).abs() < 0.15,
        "bias {} vs {}",
        f.heading_bias_deg,
        b.heading_bias_deg
    );
    assert!(
        (full.held_out_log_predictive - block.held_out_log_predictive).abs() < 0.5,
        "{} vs {}",
        full.held_out_log_predictive,
        block.held_out_log_predictive
    );
}

fn serde_json_like(r: &coopnav_nav::post_tune::TuneReport) -> String {
    format!("{:?}\n{:?}\niterations {} evaluations {}", r.before, r.after, r.iterations, r.evaluations)
}

/// Three moving beacons and a 0.15/−0.1 m/s current, through the version-2 file: the smoothed
/// track beats the forward filter against the truth, and the current is recovered.
#[test]
fn three_moving_beacons_and_a_current_through_the_v2_file() {
    let spec = SyntheticSpec { duration_s: 3600.0, current: [0.15, -0.1], seed: 9, ..SyntheticSpec::default() };
    let log = FieldLog { time: TimeBase::Unix { origin: 1_750_000_000.0 }, rows: synthetic_log(&spec) };
    let mut text = Vec::new();
    write_field_log(&mut text, &log, None).unwrap();
    let back = read_field_log(text.as_slice(), None).unwrap();
    let cfg = PostConfig { model: AuvModel::Current(CurrentParams::default()), ..PostConfig::default() };
    let r = postprocess_rows(&back.rows, &cfg).unwrap();
    let s = r.summary;
    assert_eq!(s.ranges, 239);
    assert_eq!(s.ranges_without_fix, 0);
    let (filtered, smoothed) = (s.rms_filtered_error.unwrap(), s.rms_smoothed_error.unwrap());
    assert!(smoothed < 0.9 * filtered, "RMS error filtered {filtered} m, smoothed {smoothed} m");
    let mid = &r.samples[r.samples.len() / 2];
    let c = mid.smoothed_current.unwrap();
    assert!((c[0] - 0.15).abs() < 0.03 && (c[1] + 0.1).abs() < 0.03, "current {c:?}");
    // The same rows straight from memory give the same estimates at every truth point, to the
    // file's time resolution (Unix times near 1.75e9 s keep 0.24 µs).
    let direct = postprocess_rows(&log.rows, &cfg).unwrap();
    let at_truth = |r: &coopnav_nav::post::PostResult| -> Vec<[f64; 2]> {
        r.samples.iter().filter(|p| p.truth.is_some()).map(|p| p.smoothed).collect()
    };
    let (a, b) = (at_truth(&direct), at_truth(&r));
    assert_eq!(a.len(), 360);
    assert_eq!(a.len(), b.len());
    let worst = a.iter().zip(&b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max);
    assert!(worst < 1e-3, "{worst} m");
}
