//! The `hbl postprocess` run's self-contained report.html: the counts and error
//! figures of the summary, the track on the local plane with the transponder fixes, range
//! residuals before and after smoothing against time, the NIS with its χ² bounds, and the smoothed
//! error inside its ±2σ band when the log has truth rows.

use anyhow::Result;
use coopnav_nav::fieldlog::{LogRow, Observation};
use coopnav_nav::post::PostResult;
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

/// The report of one post-processing run over the log's `rows`.
pub fn render(log_rows: &[LogRow], result: &PostResult) -> Result<String> {
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
    for w in s.warnings() {
        r.paragraph(&format!("Warning: {w}."));
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
            Series::new("95 % bounds", vec![(t0, NIS_95.1), (t1, NIS_95.1)]),
            Series::new("lower", vec![(t0, NIS_95.0), (t1, NIS_95.0)]),
        ];
        let labels = Labels { title: "Normalised innovation squared", x: "time (s)", y: "NIS" };
        r.figure("nis", "NIS of every range with the two-sided 95 % χ²(1) bounds.", &line_svg(labels, &series)?);
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
    }
    Ok(r.render())
}
