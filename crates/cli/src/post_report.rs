//! The `hbl postprocess` run's self-contained report.html: the counts and error
//! figures of the summary, what the run says about its accuracy without truth (mean NIS and its
//! χ² verdict, claimed σ, held-out range residuals, per-beacon statistics), the tuning's values
//! with their SDs and the guard's choice, the track on the local plane with the transponder fixes,
//! range residuals before and after smoothing against time (all and per beacon), the NIS with its
//! χ² bounds, and the smoothed east and north errors inside their ±2σ bands when the log has
//! truth rows.

use anyhow::Result;
use coopnav_nav::fieldlog::{LogRow, Observation};
use coopnav_nav::post::PostResult;
use coopnav_nav::post_quality::Quality;
use coopnav_nav::post_tune::{Kept, TuneReport};
use coopnav_sim::output::plot::{line_svg, track_svg, Labels, Series};
use coopnav_sim::output::report::HtmlReport;
use std::collections::BTreeMap;

/// Points drawn per series at most: a day at 10 Hz would make a plot of megabytes.
const MAX_POINTS: usize = 4000;

/// Two-sided 95 % interval of χ² with one degree of freedom.
const NIS_95: (f64, f64) = (0.000_982, 5.024);

fn thin(points: impl Iterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let all: Vec<(f64, f64)> = points.collect();
    let every = all.len().div_ceil(MAX_POINTS).max(1);
    all.into_iter().step_by(every).collect()
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{x:.3}"))
}

/// The rows of the figures that need no truth.
fn quality_rows(q: &Quality) -> Vec<[String; 2]> {
    let mut rows = Vec::new();
    if let Some(n) = &q.nis {
        rows.push([
            format!("mean NIS of {} ranges (95 % bounds of χ²(n)/n)", n.ranges),
            format!("{:.3} [{:.3}, {:.3}]: {}", n.mean, n.bounds_95.0, n.bounds_95.1, verdict(n.verdict)),
        ]);
    }
    if let Some(c) = &q.claimed_accuracy {
        rows.push([
            "claimed horizontal σ of the smoothed track: mean / p95 / max (m)".into(),
            format!("{:.3} / {:.3} / {:.3}", c.mean_sd_m, c.p95_sd_m, c.max_sd_m),
        ]);
    }
    if let Some(h) = &q.held_out {
        rows.push([
            format!("held-out ranges ({} folds, {} ranges): RMS residual filter / smoothed (m)", h.folds, h.ranges),
            format!("{} / {}", opt(h.rms_filter_m), opt(h.rms_smoothed_m)),
        ]);
        rows.push(["held-out ranges: mean r²/(R + hPˢhᵀ) (1 when consistent)".into(), opt(h.mean_nis_smoothed)]);
    }
    rows
}

fn verdict(v: coopnav_nav::post_quality::NisVerdict) -> &'static str {
    match v {
        coopnav_nav::post_quality::NisVerdict::Consistent => "consistent",
        coopnav_nav::post_quality::NisVerdict::Overconfident => "overconfident (innovations larger than claimed)",
        coopnav_nav::post_quality::NisVerdict::Underconfident => "underconfident (innovations smaller than claimed)",
    }
}

/// The tuning's table: each value before, searched (± SD) and kept.
fn tuning_rows(t: &TuneReport) -> Vec<[String; 4]> {
    let (b, a, c, sd) = (&t.before.values, &t.after.values, &t.chosen, &t.sd);
    let pm = |v: f64, s: Option<f64>| s.map_or(format!("{v:.4}"), |s| format!("{v:.4} ± {s:.4}"));
    vec![
        [
            "range σ (m)".into(),
            format!("{:.4}", b.range_sd_m),
            pm(a.range_sd_m, sd.range_sd_m),
            format!("{:.4}", c.range_sd_m),
        ],
        [
            "E/N process noise (m² per step)".into(),
            format!("{:.3e}", b.q_en),
            sd.q_en.map_or(format!("{:.3e}", a.q_en), |s| format!("{:.3e} ± {s:.3e}", a.q_en)),
            format!("{:.3e}", c.q_en),
        ],
        [
            "speed scale".into(),
            format!("{:.4}", b.speed_scale),
            pm(a.speed_scale, sd.speed_scale),
            format!("{:.4}", c.speed_scale),
        ],
        [
            "compass bias (deg)".into(),
            format!("{:.3}", b.heading_bias_deg),
            pm(a.heading_bias_deg, sd.heading_bias_deg),
            format!("{:.3}", c.heading_bias_deg),
        ],
        [
            "whole compass bias, with the smoothed bias state (deg)".into(),
            format!("{:.3}", t.before.compass_bias_deg),
            format!("{:.3}", t.after.compass_bias_deg),
            format!("{:.3}", t.kept.compass_bias_deg),
        ],
        [
            "initial E/N variance (m²)".into(),
            format!("{:.2}", b.p0_en),
            pm(a.p0_en, sd.p0_en),
            format!("{:.2}", c.p0_en),
        ],
        [
            "held-out log predictive density".into(),
            format!("{:.2}", t.before.held_out_log_predictive),
            format!("{:.2}", t.after.held_out_log_predictive),
            format!("{:.2}", t.kept.held_out_log_predictive),
        ],
        [
            "ranges gated (full run)".into(),
            t.before.ranges_gated.to_string(),
            t.after.ranges_gated.to_string(),
            t.kept.ranges_gated.to_string(),
        ],
    ]
}

/// The report of one post-processing run over the log's `rows`.
pub fn render(
    log_rows: &[LogRow],
    result: &PostResult,
    quality: &Quality,
    tuning: Option<&TuneReport>,
) -> Result<String> {
    let s = &result.summary;
    let mut r = HtmlReport::new("coopnav hbl postprocess");
    r.heading("Summary");
    let rows = [
        ["ranges".to_string(), s.ranges.to_string()],
        [
            "applied / gated / without a fix / unusable".into(),
            format!("{} / {} / {} / {}", s.ranges_applied, s.ranges_gated, s.ranges_without_fix, s.ranges_unusable),
        ],
        [
            "residual RMS before / after smoothing (m)".into(),
            format!("{} / {}", opt(s.residual_rms_filter_m), opt(s.residual_rms_smoothed_m)),
        ],
        ["truth points".into(), s.truth_points.to_string()],
        [
            "smoothed error mean / RMS / max / final (m)".into(),
            format!(
                "{} / {} / {} / {}",
                opt(s.mean_smoothed_error),
                opt(s.rms_smoothed_error),
                opt(s.max_smoothed_error),
                opt(s.final_smoothed_error)
            ),
        ],
        [
            "mean NEES filtered / smoothed (2 when consistent)".into(),
            format!("{} / {}", opt(s.mean_filtered_nees), opt(s.mean_smoothed_nees)),
        ],
    ];
    r.table(&["", "value"], &rows);
    for w in s.warnings().into_iter().chain(quality.warnings()) {
        r.paragraph(&format!("Warning: {w}."));
    }
    r.heading("Accuracy without truth");
    r.table(&["", "value"], &quality_rows(quality));
    if !quality.beacons.is_empty() {
        let o = |v: Option<f64>| opt(v);
        let rows: Vec<[String; 8]> = quality
            .beacons
            .iter()
            .map(|b| {
                [
                    b.beacon.to_string(),
                    format!("{} / {}", b.applied, b.gated),
                    o(b.mean_innovation_m),
                    o(b.rms_innovation_m),
                    o(b.mean_smoothed_m),
                    o(b.rms_smoothed_m),
                    o(b.mean_nis),
                    b.ranges.to_string(),
                ]
            })
            .collect();
        let header = [
            "beacon",
            "applied / gated",
            "mean innov. (m)",
            "RMS innov. (m)",
            "mean smoothed (m)",
            "RMS smoothed (m)",
            "mean NIS",
            "ranges",
        ];
        r.table(&header, &rows);
    }
    if let Some(t) = tuning {
        r.heading("Tuning");
        let kept = match t.guard.kept {
            Kept::Tuned => "the tuned values",
            Kept::BestCandidate => "the search's best valid candidate",
            Kept::Start => "the starting values",
        };
        r.paragraph(&format!(
            "{} iterations, {} evaluations of {} cross-validation folds; the run keeps {kept}.",
            t.iterations, t.evaluations, t.hold_out_every
        ));
        if let Some(w) = &t.guard.warning {
            r.paragraph(&format!("Warning: {w}."));
        }
        r.table(&["", "start", "searched (± SD)", "kept"], &tuning_rows(t));
    }
    // Each beacon's fixes (the version-1 ship under its own name).
    let mut fixes: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for row in log_rows {
        let (name, e, n) = match row.obs {
            Observation::BeaconFix { beacon, e, n, .. } => (format!("beacon {beacon} fixes"), e, n),
            Observation::ShipFix { e, n, .. } => ("ship fixes".to_string(), e, n),
            _ => continue,
        };
        fixes.entry(name).or_default().push((e, n));
    }
    let mut track = vec![
        Series::new("smoothed", thin(result.samples.iter().map(|p| (p.smoothed[0], p.smoothed[1])))),
        Series::new("filtered", thin(result.samples.iter().map(|p| (p.filtered[0], p.filtered[1])))),
    ];
    track.extend(fixes.into_iter().map(|(name, points)| Series::new(name, thin(points.into_iter()))));
    track.push(Series::new("truth", thin(result.samples.iter().filter_map(|p| p.truth.map(|t| (t[0], t[1]))))));
    track.retain(|t| !t.points.is_empty());
    let labels = Labels { title: "AUV track and transponder fixes", x: "east (m)", y: "north (m)" };
    r.figure(
        "track",
        "Filtered and smoothed AUV track with the logged transponder fixes.",
        &track_svg(labels, &track)?,
    );
    if !result.residuals.is_empty() {
        let residual =
            |f: fn(&coopnav_nav::post::RangeResidual) -> f64| thin(result.residuals.iter().map(|x| (x.t, f(x))));
        let series = [
            Series::new("before update", residual(|x| x.innovation)),
            Series::new("smoothed", residual(|x| x.smoothed)),
        ];
        let labels = Labels { title: "Range residuals", x: "time (s)", y: "measured − predicted (m)" };
        r.figure(
            "residuals",
            "Range residuals before each update and against the smoothed track.",
            &line_svg(labels, &series)?,
        );
        let (t0, t1) = (result.residuals[0].t, result.residuals[result.residuals.len() - 1].t);
        let series = [
            Series::new("NIS", residual(|x| x.nis)),
            Series::new("95 % bounds", vec![(t0, NIS_95.1), (t1, NIS_95.1)]).reference(),
            Series::new("lower", vec![(t0, NIS_95.0), (t1, NIS_95.0)]).reference(),
        ];
        let labels = Labels { title: "Normalised innovation squared", x: "time (s)", y: "NIS" };
        r.figure("nis", "NIS of every range with the two-sided 95 % χ²(1) bounds.", &line_svg(labels, &series)?);
        let mut by_beacon: BTreeMap<_, Vec<(f64, f64)>> = BTreeMap::new();
        for x in result.residuals.iter().filter(|x| x.applied && !x.smoothed.is_nan()) {
            by_beacon.entry(x.beacon).or_default().push((x.t, x.smoothed));
        }
        let series: Vec<Series> = by_beacon
            .into_iter()
            .map(|(b, points)| Series::new(format!("beacon {b}"), thin(points.into_iter())))
            .collect();
        if !series.is_empty() {
            let labels =
                Labels { title: "Smoothed range residuals per beacon", x: "time (s)", y: "measured − smoothed (m)" };
            r.figure(
                "beacon-residuals",
                "Each beacon's applied ranges against the smoothed track: a beacon whose residuals sit off zero has a biased fix or clock.",
                &line_svg(labels, &series)?,
            );
        }
    }
    let truthful: Vec<_> = result.samples.iter().filter_map(|p| p.truth.map(|t| (p, t))).collect();
    if !truthful.is_empty() {
        let series = [
            Series::new("east error", thin(truthful.iter().map(|(p, t)| (p.t, p.smoothed[0] - t[0])))),
            Series::new("+2σ", thin(truthful.iter().map(|(p, _)| (p.t, 2.0 * p.smoothed_sd[0])))),
            Series::new("−2σ", thin(truthful.iter().map(|(p, _)| (p.t, -2.0 * p.smoothed_sd[0])))),
        ];
        let labels = Labels { title: "Smoothed east error and its ±2σ band", x: "time (s)", y: "m" };
        r.figure(
            "sigma",
            "Smoothed east error against truth inside the filter's ±2σ band.",
            &line_svg(labels, &series)?,
        );
        let series = [
            Series::new("north error", thin(truthful.iter().map(|(p, t)| (p.t, p.smoothed[1] - t[1])))),
            Series::new("+2σ", thin(truthful.iter().map(|(p, _)| (p.t, 2.0 * p.smoothed_sd[1])))),
            Series::new("−2σ", thin(truthful.iter().map(|(p, _)| (p.t, -2.0 * p.smoothed_sd[1])))),
        ];
        let labels = Labels { title: "Smoothed north error and its ±2σ band", x: "time (s)", y: "m" };
        r.figure(
            "north-error",
            "Smoothed north error against truth inside the filter's ±2σ band.",
            &line_svg(labels, &series)?,
        );
    }
    Ok(r.render())
}
