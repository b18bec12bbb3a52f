//! Tuning on field-like logs whose noise the test knows (`SyntheticSpec::field_like`: 16.5
//! minutes, about 50 one-way ranges to one moving beacon, truth at 1 Hz, a minute of silence
//! during the first turn), against the ceiling of values tuned on the truth itself, and on logs
//! hard in the ways field logs are: a long silence, a clock jump, a badly biased compass,
//! acoustic outliers and a start several metres off.

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use coopnav_nav::fieldlog::{LogRow, Observation};
use coopnav_nav::post::{postprocess_rows, PostConfig, PostResult};
use coopnav_nav::post_quality::Quality;
use coopnav_nav::post_tune::{tune, Kept, TuneOptions, TuneReport};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};

/// The noise `field_like` writes: range σ 0.8 m at zero range, compass 3° off, speed log 3 % slow.
const RANGE_SD_M: f64 = 0.8;
const COMPASS_BIAS_DEG: f64 = 3.0;

/// The post-processing config for search coordinates (ln range σ, ln q_en, speed scale, compass
/// bias, ln p0_en), as the tuner applies them.
fn config(u: &[f64]) -> PostConfig {
    let mut c = PostConfig::default();
    c.auv.range_noise.sigma_time = u[0].exp() / c.auv.range_noise.sound_speed;
    (c.auv.q[0], c.auv.q[1]) = (u[1].exp(), u[1].exp());
    (c.speed_scale, c.heading_bias_deg) = (u[2], u[3]);
    (c.auv.p0[0], c.auv.p0[1]) = (u[4].exp(), u[4].exp());
    c
}

/// The ceiling no user can reach: the same five values chosen to minimise the smoothed RMS error
/// against the log's truth rows (Nelder–Mead from the defaults).
struct TruthTuned<'a>(&'a [LogRow]);

impl CostFunction for TruthTuned<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let rms = postprocess_rows(self.0, &config(u)).ok().and_then(|r| r.summary.rms_smoothed_error);
        Ok(rms.unwrap_or(1e9))
    }
}

fn truth_tuned(rows: &[LogRow]) -> PostResult {
    let d = PostConfig::default();
    let origin = vec![(1500.0 * d.auv.range_noise.sigma_time).ln(), d.auv.q[0].ln(), 1.0, 0.0, d.auv.p0[0].ln()];
    let mut simplex = vec![origin.clone()];
    for (i, step) in [0.5, 1.5, 0.03, 2.0, 1.0].into_iter().enumerate() {
        let mut v = origin.clone();
        v[i] += step;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(1e-4).unwrap();
    let res = Executor::new(TruthTuned(rows), solver).configure(|s| s.max_iters(300)).run().unwrap();
    postprocess_rows(rows, &config(res.state().get_best_param().unwrap())).unwrap()
}

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
fn field_like_tuning_recovers_the_noise_and_nears_the_truth_tuned_ceiling() {
    for seed in [21, 22] {
        let rows = synthetic_log(&SyntheticSpec::field_like(seed));
        let defaults = postprocess_rows(&rows, &PostConfig::default()).unwrap();
        let (r, run) = tuned(&rows);
        let ceiling = truth_tuned(&rows);
        let a = &r.after;
        eprintln!(
            "seed {seed}: defaults RMS {:.3} NEES {:.3}; tuned RMS {:.3} NEES {:.3}; truth-tuned RMS {:.3} NEES {:.3}; \
             range σ {:.3} ± {:?}, compass bias {:.3}, {:?}",
            rms(&defaults),
            nees(&defaults),
            rms(&run),
            nees(&run),
            rms(&ceiling),
            nees(&ceiling),
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
        // The tuned run is far better than the defaults and no better than the ceiling.
        assert!(rms(&run) < 0.25 * rms(&defaults), "RMS {} vs defaults {}", rms(&run), rms(&defaults));
        assert!(rms(&ceiling) <= rms(&run) * 1.001, "ceiling {} vs tuned {}", rms(&ceiling), rms(&run));
        // Without truth the run says it is consistent: mean NIS inside its bounds, and the
        // held-out ranges' smoothed NIS near 1.
        let q = Quality::of(&run, Some(a.cross_validation));
        assert!(q.warnings().is_empty(), "{:?}", q.warnings());
        let h = a.cross_validation.mean_nis_smoothed.unwrap();
        assert!((0.5..2.0).contains(&h), "held-out NIS {h}");
    }
}

/// Every range's travel time plus `extra_m` of range on every `every`-th one (an echo).
fn with_outliers(rows: &[LogRow], every: usize, extra_m: f64) -> Vec<LogRow> {
    let mut k = 0;
    rows.iter()
        .map(|r| match r.obs {
            Observation::Range { beacon, travel_time } => {
                k += 1;
                let travel_time = if k % every == 0 { travel_time + extra_m / 1500.0 } else { travel_time };
                LogRow { obs: Observation::Range { beacon, travel_time }, ..*r }
            }
            _ => *r,
        })
        .collect()
}

/// The rows from `at` s on shifted `by` s later (a clock that jumped forward).
fn with_clock_jump(rows: &[LogRow], at: f64, by: f64) -> Vec<LogRow> {
    rows.iter().map(|r| if r.t >= at { LogRow { t: r.t + by, ..*r } } else { *r }).collect()
}

/// The start `offset` metres east of where the AUV is.
fn with_start_off(rows: &[LogRow], offset: f64) -> Vec<LogRow> {
    rows.iter()
        .map(|r| match r.obs {
            Observation::Init { e, n, speed, compass_deg } => {
                LogRow { obs: Observation::Init { e: e + offset, n, speed, compass_deg }, ..*r }
            }
            _ => *r,
        })
        .collect()
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
        r.after.compass_bias_deg
    );
    assert!(r.guard.kept == Kept::Start || r.after.held_out_log_predictive > r.before.held_out_log_predictive);
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
    let (_, run, _) = hard("clock jump of 30 s", &with_clock_jump(&rows, 500.0, 30.0));
    assert_eq!((run.summary.gaps, run.summary.time_reversals), (0, 0));
}

#[test]
fn a_badly_biased_compass_and_outliers() {
    let biased = synthetic_log(&SyntheticSpec { heading_bias_deg: 8.0, ..SyntheticSpec::field_like(25) });
    let (r, _, _) = hard("compass 8° off", &biased);
    assert!((r.after.compass_bias_deg - 8.0).abs() < 0.3 * 8.0, "compass bias {}", r.after.compass_bias_deg);
    let rows = synthetic_log(&SyntheticSpec::field_like(26));
    let (r, run, defaults) = hard("an echo 25 m long every 10th range", &with_outliers(&rows, 10, 25.0));
    assert!(run.summary.ranges_gated <= defaults.summary.ranges_gated.max(r.before.ranges_gated));
}

#[test]
fn a_start_off_by_metres_gets_the_uncertainty_its_first_fixes_support() {
    let rows = with_start_off(&synthetic_log(&SyntheticSpec::field_like(27)), 25.0);
    let (r, run, defaults) = hard("start 25 m off", &rows);
    assert!(r.chosen.p0_en > PostConfig::default().auv.p0[0], "p0 {}", r.chosen.p0_en);
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
            assert!(r.after.held_out_log_predictive > r.before.held_out_log_predictive);
            assert!(r.after.ranges_gated <= r.before.ranges_gated);
            assert_eq!(r.chosen, r.after.values);
        }
        Kept::Tuned => panic!("a capped search is never reported as converged"),
    }
}
