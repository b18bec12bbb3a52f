//! The error plot's explained jumps: every one-second rise of a survey AUV's true error that
//! stands out on the plot (at least [`MIN_RISE_M`] and [`RISE_SHARE`] of the largest error shown),
//! with what that AUV's filter did in that second, read from the trace: a range applied (how far
//! off the range was against the truth, its NIS, the filter's σ before it, a long silence before
//! it), a recovery, or no range at all (dead reckoning, or GPS fixes at the surface).

use crate::engine::{RangeUpdate, Trace, TraceRow};
use coopnav_nav::UpdateOutcome;

/// The smallest one-second rise marked, m.
pub const MIN_RISE_M: f64 = 5.0;
/// The smallest one-second rise marked, as a share of the largest true error in the trace.
pub const RISE_SHARE: f64 = 0.25;
/// A range applied this long after the AUV's previous applied one is said to end a silence, s.
pub const SILENCE_S: f64 = 60.0;
/// An AUV this shallow is at the surface (where a surfacing finish takes GPS fixes), m.
const SURFACE_DEPTH_M: f64 = 0.5;

/// One marked rise of survey AUV `auv`'s true error, from `before` at `t − 1` s to `after` at `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Jump {
    pub auv: usize,
    pub t: f64,
    pub before: f64,
    pub after: f64,
    /// What the filter did in that second, in words.
    pub cause: String,
}

/// The smallest rise [`jumps`] marks in `trace`, m.
pub fn threshold(trace: &Trace) -> f64 {
    let top = trace.rows.iter().map(|r| r.error).filter(|e| e.is_finite()).fold(0.0, f64::max);
    MIN_RISE_M.max(RISE_SHARE * top)
}

/// Every marked rise of `trace`, in time order.
pub fn jumps(trace: &Trace) -> Vec<Jump> {
    let rise = threshold(trace);
    let n = trace.rows.iter().map(|r| r.auv + 1).max().unwrap_or(0);
    let mut out = Vec::new();
    for k in 0..n {
        let rows: Vec<&TraceRow> = trace.rows.iter().filter(|r| r.auv == k).collect();
        for w in rows.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b.error - a.error >= rise {
                let cause = cause(&trace.ranges, k, (Some(a), b));
                out.push(Jump { auv: k, t: b.t, before: a.error, after: b.error, cause });
            }
        }
    }
    out.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.auv.cmp(&b.auv)));
    out
}

/// What AUV `k`'s filter did between its samples `prior` (at `t0`, if any) and `row` (at `t1`).
fn cause(ranges: &[RangeUpdate], k: usize, (prior, row): (Option<&TraceRow>, &TraceRow)) -> String {
    let (t0, t1) = (prior.map_or(f64::NEG_INFINITY, |r| r.t), row.t);
    let mine = || ranges.iter().filter(|u| u.auv == k);
    let in_step: Vec<&RangeUpdate> = mine().filter(|u| u.t > t0 && u.t <= t1).collect();
    let recovered = if in_step.iter().any(|u| u.recovered) { "; the filter recovered" } else { "" };
    let applied = in_step.iter().rev().find_map(|u| match u.outcome {
        UpdateOutcome::Applied { nis } => Some((u, nis)),
        _ => None,
    });
    if let Some((u, nis)) = applied {
        let off = if u.error_m.abs() < 0.05 {
            "within 0.1 m".to_string()
        } else if u.error_m > 0.0 {
            format!("{:.1} m long", u.error_m)
        } else {
            format!("{:.1} m short", -u.error_m)
        };
        let sd = prior.map_or(String::new(), |r| format!(", σ {:.1} m before", r.est_sd));
        let previous = mine().filter(|p| p.t < u.t && p.outcome.applied()).last();
        let silence = match previous {
            Some(p) if u.t - p.t >= SILENCE_S => format!(", {:.0} s after the last", u.t - p.t),
            None => ", the first".to_string(),
            Some(_) => String::new(),
        };
        format!("range {off} applied, NIS {nis:.1}{sd}{silence}{recovered}")
    } else if !recovered.is_empty() {
        "the filter recovered".to_string()
    } else if row.true_z < SURFACE_DEPTH_M {
        "at the surface (GPS fixes)".to_string()
    } else {
        "no range applied: dead reckoning".to_string()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A trace row of AUV `auv` at `t` with `error` at depth `z` (the other fields neutral).
    pub(crate) fn row(t: f64, auv: usize, error: f64, z: f64) -> TraceRow {
        TraceRow {
            t,
            auv,
            true_x: 0.0,
            true_y: 0.0,
            true_z: z,
            est_x: 0.0,
            est_y: 0.0,
            error,
            est_sd: 1.0,
            p_ee: 1.0,
            p_en: 0.0,
            p_nn: 1.0,
            nees: 1.0,
            modelled: None,
            cna_x: 0.0,
            cna_y: 0.0,
            cna_z: 0.0,
            distance: 100.0,
        }
    }

    fn range(t: f64, auv: usize, outcome: UpdateOutcome, error_m: f64) -> RangeUpdate {
        RangeUpdate { t, auv, outcome, error_m, recovered: false }
    }

    #[test]
    fn each_rise_is_told_by_what_the_filter_did_in_its_second() {
        let mut trace = Trace::default();
        // AUV 0 rises 2 -> 12 m at 101 s (a range 9.5 m long applied at 100.4 s, 90 s after the
        // previous one), 12 -> 13 m at 102 s (too small); AUV 1 rises 1 -> 9 m at 111 s with no
        // range (gated only) and 9 -> 16 m at 121 s at the surface.
        for (t, e0, e1, z1) in [
            (100.0, 2.0, 1.0, 20.0),
            (101.0, 12.0, 1.0, 20.0),
            (102.0, 13.0, 1.0, 20.0),
            (110.0, 13.0, 1.0, 20.0),
            (111.0, 13.0, 9.0, 20.0),
            (120.0, 13.0, 9.0, 0.0),
            (121.0, 13.0, 16.0, 0.0),
        ] {
            trace.rows.extend([row(t, 0, e0, 20.0), row(t, 1, e1, z1)]);
        }
        trace.ranges = vec![
            range(10.4, 0, UpdateOutcome::Applied { nis: 0.5 }, 0.1),
            range(100.4, 0, UpdateOutcome::Applied { nis: 9.87 }, 9.46),
            range(110.5, 1, UpdateOutcome::Gated { nis: 30.0 }, -7.0),
        ];
        let mut within = trace.clone();
        within.ranges[1].error_m = -0.04;
        assert!(jumps(&within)[0].cause.starts_with("range within 0.1 m applied, NIS 9.9"));
        within.ranges[1].error_m = -0.06;
        assert!(jumps(&within)[0].cause.starts_with("range 0.1 m short applied"));
        // The largest error is 16 m: a quarter is 4 m, below the 5 m floor.
        assert_eq!(threshold(&trace), 5.0);
        let j = jumps(&trace);
        let told: Vec<(usize, f64, &str)> = j.iter().map(|j| (j.auv, j.t, j.cause.as_str())).collect();
        assert_eq!(
            told,
            [
                (0, 101.0, "range 9.5 m long applied, NIS 9.9, σ 1.0 m before, 90 s after the last"),
                (1, 111.0, "no range applied: dead reckoning"),
                (1, 121.0, "at the surface (GPS fixes)"),
            ]
        );
        assert_eq!((j[0].before, j[0].after), (2.0, 12.0));
    }

    #[test]
    fn the_threshold_follows_the_largest_error() {
        let mut trace = Trace::default();
        trace.rows = vec![row(0.0, 0, 1.0, 20.0), row(1.0, 0, 30.0, 20.0), row(2.0, 0, 100.0, 20.0)];
        assert_eq!(threshold(&trace), 25.0);
        let j = jumps(&trace);
        assert_eq!(j.iter().map(|j| j.t).collect::<Vec<_>>(), [1.0, 2.0]);
        assert_eq!(j[0].cause, "no range applied: dead reckoning");
    }
}
