//! `closed-loop-vs-baselines`'s cells are a sweep file: planned (its reduced form), run in two
//! shards and merged, they give the reproduction's own numbers bit for bit, and the merge writes
//! the reproduction's table, report.json and plots byte for byte as `coopnav reproduce` does.

use coopnav_sim::experiments::{self, ReproOptions, Size};
use coopnav_sweep::expand::Form;
use coopnav_sweep::plan::{plan_form, Plan};
use coopnav_sweep::{merge, shard};
use std::path::Path;

/// The experiment's sweep file, in the repository.
const FILE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/experiments/closed-loop-vs-baselines.toml");

#[test]
fn the_reduced_sweep_gives_the_reproductions_numbers_and_report() {
    let tmp = tempfile::tempdir().unwrap();
    let file = Path::new(FILE);
    let text = std::fs::read_to_string(file).unwrap();
    let (dir, e) = plan_form(file, &text, Form::Reduced, 2, &tmp.path().join("plan"), false, false, "test").unwrap();
    assert_eq!((e.cells.len(), e.runs), (3, 8));
    let plan = Plan::open(&dir).unwrap();
    for s in [1, 0] {
        shard::run_shards(&plan, &[s], &|_| {}).unwrap();
    }
    let m = merge::merge(&plan, None, false, "test").unwrap();
    assert!(m.failures.is_empty(), "{:?}", m.failures);

    let report = experiments::run("closed-loop-vs-baselines", &ReproOptions::new(Size::Reduced, 1)).unwrap();
    // Per cell and policy, the mean true error (and every other statistic) bit for bit.
    // (From the merged records themselves: JSON text read back need not round every f64 exactly.)
    let records = merge::collect(&plan).unwrap();
    let cells: Vec<serde_json::Value> = merge::comparisons(&plan, &records)
        .0
        .iter()
        .enumerate()
        .map(
            |(k, c)| serde_json::json!({ "cell": k, "comparison": serde_json::to_value(c.as_ref().unwrap()).unwrap() }),
        )
        .collect();
    let ours = report.data["comparisons"].as_array().unwrap();
    assert_eq!(cells.len(), ours.len());
    let mut compared = 0;
    for (cell, theirs) in cells.iter().zip(ours) {
        let (a, b) = (&cell["comparison"]["policies"], &theirs["policies"]);
        assert_eq!(a.as_array().unwrap().len(), experiments::closed_loop::policies().len());
        for (pa, pb) in a.as_array().unwrap().iter().zip(b.as_array().unwrap()) {
            assert_eq!(pa["policy"], pb["policy"]);
            let bits = |v: &serde_json::Value| v["mean_error"]["mean"].as_f64().unwrap().to_bits();
            assert_eq!(bits(pa), bits(pb), "cell {}, {}", cell["cell"], pa["policy"]);
            compared += 1;
        }
        assert_eq!(&cell["comparison"], theirs, "cell {}: the comparisons differ", cell["cell"]);
    }
    assert_eq!(compared, 3 * experiments::closed_loop::policies().len());

    // The reproduction's report from the merged runs: the same text, JSON and plots.
    let from_sweep = m.report.as_ref().expect("the sweep file names its reproduction");
    assert_eq!(from_sweep.printed(), report.printed());
    let read = |name: &str| std::fs::read_to_string(m.dir.join(merge::REPORT_DIR).join(name)).unwrap();
    assert_eq!(read("table.txt"), report.printed());
    assert_eq!(read("report.json"), serde_json::to_string_pretty(&report).unwrap() + "\n");
    assert_eq!(report.plots.len(), 2);
    for (name, svg) in &report.plots {
        assert_eq!(&read(name), svg, "{name}");
    }
}

#[test]
fn a_sweep_naming_no_such_reproduction_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("s.toml");
    let text = "scenarios = [\"default\"]\npolicies = [\"zigzag\"]\nruns = 1\nreport = \"hudson-table-9\"\n";
    std::fs::write(&file, text).unwrap();
    let e = plan_form(&file, text, Form::Full, 1, &tmp.path().join("p"), false, false, "t").unwrap_err().to_string();
    assert!(e.contains("report = \"hudson-table-9\": no reproduction reports from a sweep's runs (allowed: closed-loop-vs-baselines)"), "{e}");
}
