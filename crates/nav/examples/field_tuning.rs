//! The tuning table of docs/evaluation.md#post-processing-tuning: for field-like synthetic logs
//! and logs hard in the ways field logs are, the smoothed RMS error and mean NEES of the
//! defaults, `--tune`, the true-noise reference and the cross-validated truth-tuned reference,
//! the share of the squared error in the first 120 s, and the tuned values.
//!
//! `cargo run --release -p coopnav-nav --example field_tuning -- [--no-ceiling] LOG...` where LOG
//! is `seed:N` (field-like) or one of `silence`, `clock`, `compass`, `echoes`, `start`.

use coopnav_nav::fieldlog::LogRow;
use coopnav_nav::post::{postprocess_rows, PostConfig, PostResult};
use coopnav_nav::post_quality::Quality;
use coopnav_nav::post_reference::{true_noise, truth_tuned_cross_validated};
use coopnav_nav::post_tune::{tune, TuneOptions};
use coopnav_nav::synthetic::{synthetic_log, with_clock_jump, with_echoes, with_start_off, SyntheticSpec};
use std::time::Instant;

/// The log named `name`: its spec (for the true noise) and rows.
fn log(name: &str) -> (SyntheticSpec, Vec<LogRow>) {
    let f = SyntheticSpec::field_like;
    match name {
        "silence" => {
            let s = SyntheticSpec { range_silence_s: Some([300.0, 600.0]), ..f(23) };
            (s.clone(), synthetic_log(&s))
        }
        "clock" => (f(24), with_clock_jump(&synthetic_log(&f(24)), 500.0, 30.0)),
        "compass" => {
            let s = SyntheticSpec { heading_bias_deg: 8.0, ..f(25) };
            (s.clone(), synthetic_log(&s))
        }
        "echoes" => (f(26), with_echoes(&synthetic_log(&f(26)), 10, 25.0)),
        "start" => (f(27), with_start_off(&synthetic_log(&f(27)), 25.0)),
        other => {
            let seed: u64 = other.strip_prefix("seed:").and_then(|s| s.parse().ok()).expect("seed:N or a hard log");
            (f(seed), synthetic_log(&f(seed)))
        }
    }
}

/// RMS (m), mean NEES, the share of the squared error at t ≤ 120 s and the initial E/N variance.
fn figures(r: &PostResult) -> String {
    let sq: Vec<(f64, f64)> = r
        .samples
        .iter()
        .filter_map(|s| s.truth.map(|t| (s.t, (s.smoothed[0] - t[0]).powi(2) + (s.smoothed[1] - t[1]).powi(2))))
        .collect();
    let total: f64 = sq.iter().map(|x| x.1).sum();
    let early: f64 = sq.iter().filter(|x| x.0 <= 120.0).map(|x| x.1).sum();
    format!(
        "{:.2} / {:.2} ({:.0} %, p0 {:.0})",
        r.summary.rms_smoothed_error.unwrap_or(f64::NAN),
        r.summary.mean_smoothed_nees.unwrap_or(f64::NAN),
        100.0 * early / total,
        r.summary.initial_en_variance_m2[0]
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ceiling = !args.iter().any(|a| a == "--no-ceiling");
    let base = PostConfig::default();
    println!("| log | defaults | `--tune` | true noise | truth-tuned (cross-validated) | range σ | compass bias | guard | summary without truth |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for name in args.iter().filter(|a| !a.starts_with("--")) {
        let (spec, rows) = log(name);
        let clock = Instant::now();
        let defaults = postprocess_rows(&rows, &base).unwrap();
        let report = tune(&rows, &base, &TuneOptions::default()).unwrap();
        let tuned = postprocess_rows(&rows, &report.config).unwrap();
        let tune_s = clock.elapsed().as_secs_f64();
        let truth_noise = postprocess_rows(&rows, &true_noise(&spec, &base)).unwrap();
        let ceiling = if ceiling {
            let c = truth_tuned_cross_validated(&rows, &base, 300).unwrap();
            format!(
                "{:.2} / {:.2} (in-sample {:.2}, {:.2})",
                c.rms_m, c.mean_nees, c.halves[0].rms_in_sample_m, c.halves[1].rms_in_sample_m
            )
        } else {
            "–".into()
        };
        let a = &report.kept;
        let q = Quality::of(&tuned, Some(report.after.cross_validation));
        let nis = q.nis.map_or("–".into(), |n| format!("NIS {:.2} {:?}", n.mean, n.verdict));
        let claimed =
            q.claimed_accuracy.map_or("–".into(), |c| format!("σ {:.1} m (p95 {:.1})", c.mean_sd_m, c.p95_sd_m));
        let held = a.cross_validation.rms_smoothed_m.map_or("–".into(), |v| format!("held-out RMS {v:.2} m"));
        println!(
            "| {name} | {} | {} | {} | {ceiling} | {:.2} ± {} (true {:.2}) | {:.2} (true {:.2}) | {:?}{} | {nis}, {claimed}, {held}; tune {tune_s:.0} s |",
            figures(&defaults),
            figures(&tuned),
            figures(&truth_noise),
            report.chosen.range_sd_m,
            report.sd.range_sd_m.map_or("–".into(), |s| format!("{s:.2}")),
            spec.range_sd_m,
            report.kept.compass_bias_deg,
            spec.heading_bias_deg,
            report.guard.kept,
            report.guard.warning.as_deref().map_or(String::new(), |w| format!(": {w}")),
        );
    }
}
