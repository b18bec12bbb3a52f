//! Faults of a log as logged: a clock that jumps back and rows logged twice are counted, the
//! first named by its data row, and reach `--strict` through `log_faults`; a repeated row is
//! applied once.

use coopnav_nav::post::{postprocess_rows, PostConfig};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};

fn clean() -> Vec<coopnav_nav::fieldlog::LogRow> {
    synthetic_log(&SyntheticSpec { duration_s: 600.0, ..SyntheticSpec::default() })
}

#[test]
fn a_clean_log_has_no_faults() {
    let r = postprocess_rows(&clean(), &PostConfig::default()).unwrap();
    assert_eq!((r.summary.time_reversals, r.summary.duplicate_rows), (0, 0));
    assert!(r.summary.log_faults().is_empty(), "{:?}", r.summary.log_faults());
}

/// From the middle on, every time is 300 s earlier: one reversal, at the first shifted row.
#[test]
fn a_clock_that_jumps_back_is_named_with_its_first_row() {
    let mut rows = clean();
    let half = rows.len() / 2;
    for r in &mut rows[half..] {
        r.t -= 300.0;
    }
    let s = postprocess_rows(&rows, &PostConfig::default()).unwrap().summary;
    assert_eq!((s.time_reversals, s.first_time_reversal), (1, Some(half + 1)));
    let faults = s.log_faults().join("; ");
    assert!(faults.contains("jumped back") && faults.contains(&format!("data row {}", half + 1)), "{faults}");
}

/// Every range logged twice: the duplicates are counted and the filter sees each range once, so
/// the estimate is the clean log's, bit for bit.
#[test]
fn rows_logged_twice_are_counted_and_applied_once() {
    let rows = clean();
    let mut doubled = Vec::with_capacity(rows.len() * 2);
    let mut ranges = 0;
    let mut first = None;
    for r in &rows {
        doubled.push(*r);
        if matches!(r.obs, coopnav_nav::fieldlog::Observation::Range { .. }) {
            doubled.push(*r);
            ranges += 1;
            first.get_or_insert(doubled.len());
        }
    }
    assert!(ranges > 5, "{ranges} ranges");
    let cfg = PostConfig::default();
    let (once, twice) = (postprocess_rows(&rows, &cfg).unwrap(), postprocess_rows(&doubled, &cfg).unwrap());
    assert_eq!((twice.summary.duplicate_rows, twice.summary.first_duplicate), (ranges, first));
    assert_eq!(twice.summary.ranges, once.summary.ranges, "each range reaches the filter once");
    assert_eq!(twice.samples, once.samples, "the same estimate as the clean log");
    assert!(twice.summary.log_faults().join("; ").contains("applied once"));
}
