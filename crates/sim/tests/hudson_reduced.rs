//! CI form of the Hudson reproductions: every reduced reproduction runs and all its property
//! checks (trends, floors, bands) hold.

use coopnav_sim::experiments::{registry, ReproOptions, Size};

#[test]
fn hudson_reductions_pass_their_checks() {
    let opts = ReproOptions::new(Size::Reduced, 1);
    let hudson: Vec<_> = registry().into_iter().filter(|e| e.id.starts_with("hudson-")).collect();
    assert_eq!(hudson.len(), 9, "5.3-5.9, 6.1 and the penalty cases");
    for e in hudson {
        let r = (e.run)(&opts).unwrap_or_else(|err| panic!("{}: {err}", e.id));
        assert!(!r.checks.is_empty(), "{} has no checks", e.id);
        for c in &r.checks {
            assert!(c.acceptable(), "{}: check '{}' failed: {}\n{}", e.id, c.name, c.detail, r.table);
        }
    }
}
