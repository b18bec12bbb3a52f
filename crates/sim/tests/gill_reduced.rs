//! Reduced Gill reproductions (fewer runs; bands widened by the computed Monte Carlo standard
//! error), run in CI.

use coopnav_sim::experiments::{run, ReproOptions, Size};

fn check_all(id: &str) {
    let report = run(id, &ReproOptions::new(Size::Reduced, 1)).expect(id);
    for c in &report.checks {
        assert!(c.acceptable(), "{id}: {} failed: {}\n{}", c.name, c.detail, report.table);
    }
    assert!(!report.checks.is_empty());
}

#[test]
fn table_5_reduced() {
    check_all("gill-table-5");
}

#[test]
fn cycles_reduced() {
    check_all("gill-cycles");
}

#[test]
fn table_4_reduced() {
    check_all("gill-table-4");
}

#[test]
fn buoy_grid_reduced() {
    check_all("gill-buoy-grid");
}
