//! Geodetic field logs end to end (Gill 2013, §3.3; docs/models.md#gill-geodesy): a simulated log written in
//! latitude/longitude post-processes like the same log in metres, and buoy fixes carrying the
//! UI AUV's float32 storage artefact cost a measurable (small) amount of accuracy.

use coopnav_core::{run_seed, Geodetic, LatLon, LatLonStorage};
use coopnav_nav::cycle::Configuration;
use coopnav_nav::post::{postprocess, read_log, write_log, Entry, PostConfig, PostResult, Record};
use coopnav_sim::observe::zone::ZoneSpec;
use coopnav_sim::output::log_format::LogFormat;
use coopnav_sim::output::record::record_pass;
use coopnav_sim::scenario::hbl::table5_scenario;

fn pend_oreille() -> Geodetic {
    Geodetic::new(LatLon::new(47.97, -116.5).unwrap(), 630.0).unwrap()
}

fn scenario(origin: Option<Geodetic>, storage: LatLonStorage) -> LogFormat {
    let format = LogFormat { geodetic_origin: origin, buoy_fix_storage: storage };
    format.validate().unwrap();
    format
}

/// Simulates run `i` of Table 5's HBL Two file, writes its log as the cli does (in format `format`),
/// reads it back with the matching config.
fn simulate_and_postprocess(format: &LogFormat, i: u64) -> (String, Vec<Entry>, PostResult) {
    let sc = table5_scenario(Configuration::HblTwo).unwrap();
    let log = record_pass(&sc, ZoneSpec::table5(), format.clone(), run_seed(5, i)).unwrap().0.sorted_log();
    let frame = format.frame();
    let mut csv = Vec::new();
    write_log(&mut csv, &log, frame.as_ref()).unwrap();
    let cfg = PostConfig { origin: format.geodetic_origin, ..PostConfig::default() };
    let entries = read_log(csv.as_slice(), cfg.frame().as_ref()).unwrap();
    let r = postprocess(&entries, &cfg).unwrap();
    (String::from_utf8(csv).unwrap(), log, r)
}

#[test]
fn latlon_logs_postprocess_like_metric_logs() {
    for i in 0..2 {
        let (m_text, m_log, m) = simulate_and_postprocess(&scenario(None, LatLonStorage::F64), i);
        let (g_text, g_log, g) = simulate_and_postprocess(&scenario(Some(pend_oreille()), LatLonStorage::F64), i);
        assert_eq!(m_log, g_log, "the geodetic option changed the simulation");
        assert!(!m_text.contains("_ll") && g_text.contains(",buoy_fix_ll,") && g_text.contains(",truth_ll,"));
        assert!(!g_text.contains(",truth,") && !g_text.contains(",ship_fix,"));
        assert_eq!(m.samples.len(), g.samples.len());
        let close = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
        for (a, b) in m.samples.iter().zip(&g.samples) {
            assert!(close(&a.filtered, &b.filtered) && close(&a.smoothed, &b.smoothed), "t = {}: {a:?} vs {b:?}", a.t);
        }
        let (ms, gs) = (m.summary, g.summary);
        assert_eq!((ms.ranges_applied, ms.truth_points), (gs.ranges_applied, gs.truth_points));
        assert!((ms.mean_filtered_error.unwrap() - gs.mean_filtered_error.unwrap()).abs() < 1e-6);
        assert!((ms.mean_smoothed_error.unwrap() - gs.mean_smoothed_error.unwrap()).abs() < 1e-6);
    }
}

/// The logged buoy latitudes/longitudes of a geodetic log text.
fn buoy_latlons(text: &str) -> Vec<(f64, f64)> {
    text.lines()
        .filter(|l| l.contains(",buoy_fix_ll,"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[3].parse().unwrap(), f[4].parse().unwrap())
        })
        .collect()
}

/// Whether `deg` is (to round-off) a float32 value, with its lowest significand bit clear if `even`.
fn on_f32_grid(deg: f64, even: bool) -> bool {
    let s = deg as f32;
    (deg - f64::from(s)).abs() < 1e-11 && (!even || s.to_bits() & 1 == 0)
}

#[test]
fn float32_buoy_fixes_land_on_the_grid_and_cost_little_accuracy() {
    let runs = 24;
    let mut means = Vec::new();
    for storage in [LatLonStorage::F64, LatLonStorage::F32, LatLonStorage::F32LostBit] {
        let sc = scenario(Some(pend_oreille()), storage);
        let (mut filt, mut smooth, mut moved) = (0.0, 0.0, 0usize);
        for i in 0..runs {
            let (text, log, r) = simulate_and_postprocess(&sc, i);
            let fixes = buoy_latlons(&text);
            assert!(fixes.len() > 5, "{} buoy fixes", fixes.len());
            if storage != LatLonStorage::F64 {
                let even = storage == LatLonStorage::F32LostBit;
                assert!(fixes.iter().all(|&(la, lo)| on_f32_grid(la, even) && on_f32_grid(lo, even)), "{fixes:?}");
            }
            let (_, reference, _) = simulate_and_postprocess(&scenario(Some(pend_oreille()), LatLonStorage::F64), i);
            moved += log
                .iter()
                .zip(&reference)
                .filter(|(a, b)| matches!(a.record, Record::BuoyFix { .. }) && a != b)
                .count();
            filt += r.summary.mean_filtered_error.unwrap() / runs as f64;
            smooth += r.summary.mean_smoothed_error.unwrap() / runs as f64;
        }
        assert_eq!(moved > 0, storage != LatLonStorage::F64, "{storage:?}: {moved} buoy fixes moved");
        eprintln!(
            "buoy fixes stored as {storage:?}: mean filtered error {filt:.4} m, smoothed {smooth:.4} m ({runs} runs)"
        );
        means.push((filt, smooth));
    }
    // A float32 step here is 0.57 m E × 0.42 m N. Rounding moves each buoy fix by up to half a
    // step (uniform: 0.2 m RMS over both axes), the lost bit by up to a whole one (0.41 m RMS).
    // A fix misplaced by d moves the ranges it anchors by at most d, and the post-processed
    // error is a mean over many ranges and 24 runs: it moves by at most half the fixes' RMS
    // displacement, 0.1 m and 0.2 m.
    for (&(f, s), most) in means[1..].iter().zip([0.1, 0.2]) {
        assert!((f - means[0].0).abs() < most && (s - means[0].1).abs() < most, "{means:?}");
    }
}
