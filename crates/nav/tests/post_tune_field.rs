//! Tuning on field-like logs whose noise the test knows (`SyntheticSpec::field_like`: 16.5
//! minutes, about 50 one-way ranges to one moving beacon, truth at 1 Hz, a minute of silence
//! during the first turn), against the references of docs/models.md#post-tuning (the true noise,
//! and values tuned on one half of the truth and scored on the other), and on logs hard in the
//! ways field logs are: a long silence, a clock jump, a badly biased compass, acoustic outliers
//! and a start several metres off.

use coopnav_nav::fieldlog::LogRow;
use coopnav_nav::post::{postprocess_rows, PostConfig, PostResult, StartVariance};
use coopnav_nav::post_quality::Quality;
use coopnav_nav::post_reference::{true_noise, truth_tuned_cross_validated};
use coopnav_nav::post_tune::{tune, Kept, TuneOptions, TuneReport};
use coopnav_nav::synthetic::{synthetic_log, with_clock_jump, with_echoes, with_start_off, SyntheticSpec};

/// The noise `field_like` writes: range σ 0.8 m at zero range, compass 3° off, speed log 3 % slow.
const RANGE_SD_M: f64 = 0.8;
const COMPASS_BIAS_DEG: f64 = 3.0;

/// The tuned run and its report.
fn tuned(rows: &[LogRow]) -> (TuneReport, PostResult) {
    let r = tune(rows, &PostConfig::default(), &TuneOptions::default()).unwrap();
    let run = postprocess_rows(rows, &r.config).unwrap();
    (r, run)
}

fn rms(r: &PostResult) -> f64 {
    r.summary.rms_smoothed_error.unwrap()
}

fn nees(r: &PostResult) -> f64 {
    r.summary.mean_smoothed_nees.unwrap()
}

#[test]
fn field_like_tuning_recovers_the_noise() {
    for seed in [21, 22] {
        let rows = synthetic_log(&SyntheticSpec::field_like(seed));
        let defaults = postprocess_rows(&rows, &PostConfig::default()).unwrap();
        let (r, run) = tuned(&rows);
        let a = &r.after;
        eprintln!(
            "seed {seed}: defaults RMS {:.3} NEES {:.3}; tuned RMS {:.3} NEES {:.3}; range σ {:.3} ± {:?}, compass bias {:.3}, {:?}",
            rms(&defaults),
            nees(&defaults),
            rms(&run),
            nees(&run),
            a.values.range_sd_m,
            r.sd.range_sd_m,
            a.compass_bias_deg,
            r.guard
        );
        assert_ne!(r.guard.kept, Kept::Start, "{:?}", r.guard);
        // Stated bands (the issue's): range σ and compass bias within 30 %.
        let off = |v: f64, truth: f64| (v / truth - 1.0).abs();
        assert!(off(a.values.range_sd_m, RANGE_SD_M) < 0.3, "range σ {}", a.values.range_sd_m);
        assert!(off(a.compass_bias_deg, COMPASS_BIAS_DEG) < 0.3, "compass bias {}", a.compass_bias_deg);
        assert!(a.held_out_log_predictive > r.before.held_out_log_predictive);
        assert!(rms(&run) < 0.25 * rms(&defaults), "RMS {} vs defaults {}", rms(&run), rms(&defaults));
        // Without truth the run says it is consistent: mean NIS inside its bounds, and the
        // held-out ranges' smoothed NIS near 1.
        let q = Quality::of(&run, Some(a.cross_validation));
        assert!(q.warnings().is_empty(), "{:?}", q.warnings());
        let h = a.cross_validation.mean_nis_smoothed.unwrap();
        assert!((0.5..2.0).contains(&h), "held-out NIS {h}");
    }
}

/// The targets on field-like logs of seeds used for nothing else: range σ and compass
/// bias within 30 % of the noise the log was written with, and the smoothed RMS within 10 % of
/// each reference (docs/models.md#post-tuning). Every miss is listed before the test fails.
#[test]
#[ignore = "target not met: the smoothed RMS is not within 10 % of the references (docs/evaluation.md#post-processing-tuning)"]
fn field_like_tuning_meets_the_targets_against_both_references() {
    let mut misses = Vec::new();
    for seed in [31, 32, 33] {
        let spec = SyntheticSpec::field_like(seed);
        let rows = synthetic_log(&spec);
        let (r, run) = tuned(&rows);
        let truth_noise = postprocess_rows(&rows, &true_noise(&spec, &PostConfig::default())).unwrap();
        let ceiling = truth_tuned_cross_validated(&rows, &PostConfig::default(), 300).unwrap();
        let k = &r.kept;
        eprintln!(
            "seed {seed}: tuned RMS {:.3} NEES {:.3}; true noise {:.3} / {:.3}; truth-tuned (cross-validated) {:.3} / {:.3}; range σ {:.3}, compass bias {:.3}, {:?}",
            rms(&run),
            nees(&run),
            rms(&truth_noise),
            nees(&truth_noise),
            ceiling.rms_m,
            ceiling.mean_nees,
            k.values.range_sd_m,
            k.compass_bias_deg,
            r.guard.kept
        );
        let off = |v: f64, truth: f64| (v / truth - 1.0).abs();
        if off(k.values.range_sd_m, RANGE_SD_M) >= 0.3 {
            misses.push(format!("seed {seed}: range σ {:.3}", k.values.range_sd_m));
        }
        if off(k.compass_bias_deg, COMPASS_BIAS_DEG) >= 0.3 {
            misses.push(format!("seed {seed}: compass bias {:.3}", k.compass_bias_deg));
        }
        for (name, reference) in [("true noise", rms(&truth_noise)), ("truth-tuned", ceiling.rms_m)] {
            if rms(&run) > 1.1 * reference {
                misses.push(format!("seed {seed}: RMS {:.3} against {name} {reference:.3}", rms(&run)));
            }
        }
    }
    assert!(misses.is_empty(), "{misses:#?}");
}

/// A hard log: the tuned run keeps a value the guard accepts, is no worse than the defaults
/// against the truth, and its held-out ranges are better predicted than with the defaults.
fn hard(name: &str, rows: &[LogRow]) -> (TuneReport, PostResult, PostResult) {
    let defaults = postprocess_rows(rows, &PostConfig::default()).unwrap();
    let (r, run) = tuned(rows);
    eprintln!(
        "{name}: defaults RMS {:.3} NEES {:.3} gated {}; tuned RMS {:.3} NEES {:.3} gated {}; {:?}; values {:?}, compass {:.3}",
        rms(&defaults),
        nees(&defaults),
        defaults.summary.ranges_gated,
        rms(&run),
        nees(&run),
        run.summary.ranges_gated,
        r.guard,
        r.chosen,
        r.kept.compass_bias_deg
    );
    // What the run keeps is the start, or values that predict the held-out ranges better and
    // reject no more ranges.
    let k = &r.kept;
    assert!(
        r.guard.kept == Kept::Start
            || (k.held_out_log_predictive > r.before.held_out_log_predictive
                && k.ranges_gated <= r.before.ranges_gated),
        "{name}: {:?}",
        r.guard
    );
    assert!(rms(&run) <= rms(&defaults), "{name}: RMS {} vs defaults {}", rms(&run), rms(&defaults));
    (r, run, defaults)
}

#[test]
fn a_long_silence_and_a_clock_jump() {
    let silent =
        synthetic_log(&SyntheticSpec { range_silence_s: Some([300.0, 600.0]), ..SyntheticSpec::field_like(23) });
    hard("silence 300–600 s", &silent);
    let rows = synthetic_log(&SyntheticSpec::field_like(24));
    // The logger's clock jumps 30 s ahead: the filter dead-reckons through time the AUV never
    // spent, and the ranges after it must pull the track back.
    let (r, run, _) = hard("clock jump of 30 s", &with_clock_jump(&rows, 500.0, 30.0));
    assert_eq!((run.summary.gaps, run.summary.time_reversals), (0, 0));
    // The search's result rejects more ranges than the start; another candidate it searched
    // does not, predicts better, and is kept, with one warning naming it.
    assert!(r.after.ranges_gated > r.before.ranges_gated, "{:?}", r.guard);
    assert_eq!(r.guard.kept, Kept::BestCandidate, "{:?}", r.guard);
    assert_ne!(r.chosen, r.after.values);
    let w = r.guard.warning.as_deref().unwrap();
    assert!(w.contains("other candidate") && w.contains("compass offset"), "{w}");
}

#[test]
fn a_badly_biased_compass_and_outliers() {
    let biased = synthetic_log(&SyntheticSpec { heading_bias_deg: 8.0, ..SyntheticSpec::field_like(25) });
    let (r, _, _) = hard("compass 8° off", &biased);
    assert!((r.after.compass_bias_deg - 8.0).abs() < 0.3 * 8.0, "compass bias {}", r.after.compass_bias_deg);
    let rows = synthetic_log(&SyntheticSpec::field_like(26));
    let (r, run, defaults) = hard("an echo 25 m long every 10th range", &with_echoes(&rows, 10, 25.0));
    assert!(run.summary.ranges_gated <= defaults.summary.ranges_gated.max(r.before.ranges_gated));
}

#[test]
fn a_start_off_by_metres_gets_the_uncertainty_its_first_fixes_support() {
    let rows = with_start_off(&synthetic_log(&SyntheticSpec::field_like(27)), 25.0);
    let (_, run, defaults) = hard("start 25 m off", &rows);
    // The first ranges show the start about 25 m off: the initial E/N variance is widened from
    // the configured 16 m² to within a factor of 2 of 25² m², with the defaults and when tuned.
    for x in [&defaults, &run] {
        let p0 = x.summary.initial_en_variance_m2;
        assert!(p0[0] == p0[1] && (312.5..1250.0).contains(&p0[0]), "p0 {p0:?}");
        assert!(x.summary.start_ranges >= 3, "{}", x.summary.start_ranges);
    }
    // A start the ranges agree with keeps the configured variance; so does `window_s = 0`.
    let exact = synthetic_log(&SyntheticSpec::field_like(27));
    let p0 = |rows: &[LogRow], cfg: &PostConfig| postprocess_rows(rows, cfg).unwrap().summary.initial_en_variance_m2;
    assert_eq!(p0(&exact, &PostConfig::default()), [16.0, 16.0]);
    let off = PostConfig { start: StartVariance { window_s: 0.0 }, ..PostConfig::default() };
    assert_eq!(p0(&rows, &off), [16.0, 16.0]);
    // Every early range is used, and the first two minutes are closer to the truth.
    let early_gated = |x: &PostResult| x.residuals.iter().filter(|g| g.t < 300.0 && !g.applied).count();
    assert_eq!(early_gated(&run), 0);
    let early = |x: &PostResult| {
        let e: Vec<f64> = x
            .samples
            .iter()
            .filter(|s| s.t <= 120.0)
            .filter_map(|s| s.truth.map(|t| (s.smoothed[0] - t[0]).hypot(s.smoothed[1] - t[1])))
            .collect();
        (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt()
    };
    eprintln!(
        "first 120 s RMS: defaults {:.3}, tuned {:.3}; early gated defaults {}",
        early(&defaults),
        early(&run),
        early_gated(&defaults)
    );
    assert!(early(&run) < early(&defaults));
}

#[test]
fn a_search_stopped_at_its_cap_warns_and_keeps_a_valid_candidate_or_the_start() {
    let rows = synthetic_log(&SyntheticSpec::field_like(28));
    let opts = TuneOptions { max_iters: 2, ..TuneOptions::default() };
    let r = tune(&rows, &PostConfig::default(), &opts).unwrap();
    assert!(!r.guard.converged);
    let w = r.guard.warning.as_deref().unwrap();
    assert!(w.contains("cap of 2 iterations"), "{w}");
    match r.guard.kept {
        Kept::Start => assert_eq!(r.chosen, r.before.values),
        Kept::BestCandidate => {
            assert!(r.kept.held_out_log_predictive > r.before.held_out_log_predictive);
            assert!(r.kept.ranges_gated <= r.before.ranges_gated);
            assert_eq!(r.chosen, r.kept.values);
        }
        Kept::Tuned => panic!("a capped search is never reported as converged"),
    }
}
