//! Reduced Gill reproductions (fewer runs; bands widened by two computed Monte Carlo standard
//! errors), run in CI: every check and thesis table passed, undecided or failed with its measured
//! cause.

use coopnav_sim::experiments::{run, ReproOptions, Size};

fn check_all(id: &str) {
    let report = run(id, &ReproOptions::new(Size::Reduced, 1)).expect(id);
    for c in &report.checks {
        assert!(c.acceptable(), "{id}: {} failed: {}\n{}", c.name, c.detail, report.printed());
    }
    for t in &report.thesis_tables {
        assert!(!t.unexplained(), "{id}: table {} below its share\n{}", t.id, report.printed());
    }
    assert!(!report.thesis_tables.is_empty(), "{id} compares no thesis number");
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
