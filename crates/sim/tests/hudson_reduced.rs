//! CI form of the Hudson reproductions: every reduced reproduction runs, and every property
//! check and thesis table is passed, undecided (the reduced form does not reproduce what it
//! compares), or failed with its measured cause printed.

use coopnav_sim::experiments::{registry, ReproOptions, Size, Verdict};

#[test]
fn hudson_reductions_pass_their_checks() {
    let opts = ReproOptions::new(Size::Reduced, 1);
    let hudson: Vec<_> = registry().into_iter().filter(|e| e.id.starts_with("hudson-")).collect();
    assert_eq!(hudson.len(), 10, "5.3-5.9, 6.1, Appendix A and the penalty cases");
    for e in hudson {
        let r = (e.run)(&opts).unwrap_or_else(|err| panic!("{}: {err}", e.id));
        assert!(!r.checks.is_empty() || !r.thesis_tables.is_empty(), "{} has no checks", e.id);
        for c in &r.checks {
            assert!(c.acceptable(), "{}: check '{}' failed: {}\n{}", e.id, c.name, c.detail, r.printed());
        }
        for t in &r.thesis_tables {
            assert!(
                t.verdict != Verdict::Fail || t.cause.is_some(),
                "{}: table {} failed\n{}",
                e.id,
                t.id,
                r.printed()
            );
        }
    }
}
