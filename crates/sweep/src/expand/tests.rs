use super::*;

fn sweep(text: &str) -> SweepFile {
    SweepFile::parse(text, Path::new("s.toml")).unwrap()
}

fn problems(text: &str) -> Vec<String> {
    match expand(&sweep(text), Path::new("s.toml"), false) {
        Err(SweepError::Invalid { file, problems }) => {
            assert_eq!(file, Path::new("s.toml"));
            problems
        }
        other => panic!("expected the file to be refused, got {other:?}"),
    }
}

const HEAD: &str = "scenarios = [\"default\"]\npolicies = [\"racetrack\", \"zigzag\"]\nruns = 2\n";

#[test]
fn cells_follow_the_documented_order_the_last_axis_fastest() {
    let text = format!(
        "{HEAD}[[axis]]\npath = \"fleet.n_auvs\"\nvalues = [2, 3]\n[[axis]]\noverlays = [\"a\", \"b\"]\n\
         [overlay.a]\n[overlay.b]\ncomms = {{ tau = 20.0 }}\n"
    );
    let e = expand(&sweep(&text), Path::new("s.toml"), false).unwrap();
    let got: Vec<(usize, f64)> = e.cells.iter().map(|c| (c.scenario.fleet.n_auvs, c.scenario.comms.tau)).collect();
    let base = Scenario::parse(EXAMPLE, Path::new("x")).unwrap().comms.tau;
    assert_eq!(got, [(2, base), (2, 20.0), (3, base), (3, 20.0)]);
    assert_eq!(e.axes, ["fleet.n_auvs", "overlay"]);
    assert_eq!(e.cells[1].label(), "default, fleet.n_auvs = 2, overlay = \"b\"");
}

#[test]
fn every_bad_axis_path_value_overlay_and_policy_is_named_at_once() {
    let text = "scenarios = [\"default\", \"missing.toml\"]\npolicies = [\"racetrack\", \"warp\"]\nruns = 0\n\
                [[axis]]\npath = \"comms.tauu\"\nvalues = [1]\n\
                [[axis]]\npath = \"fleet.n_auvs\"\nvalues = [\"three\"]\n\
                [[axis]]\noverlays = [\"nope\"]\n\
                [[axis]]\npath = \"seed\"\n\
                [overlay.unused]\nfleet = { wheels = 4 }\n";
    let p = problems(text);
    let has = |needle: &str| assert!(p.iter().any(|x| x.contains(needle)), "no problem mentions {needle:?}: {p:#?}");
    has("runs = 0: allowed at least 1");
    has("policies[1] = \"warp\": allowed planner");
    has("scenarios[1] = \"missing.toml\": cannot read scenario missing.toml");
    has("axis[0].path = \"comms.tauu\": no field `tauu` in [comms] (allowed: ");
    has("axis[1].values[0] = \"three\"");
    has("axis[2].overlays[0] = \"nope\": no [overlay.nope] (allowed: unused)");
    has("axis[3]: path needs its values");
    has("overlay.unused: no axis uses it");
    has("overlay.unused: unknown field `wheels`");
    assert_eq!(p.len(), 9, "{p:#?}");
}

#[test]
fn an_unset_optional_field_is_a_valid_path_and_a_bad_cell_names_its_axis_values() {
    let ok = format!("{HEAD}[[axis]]\npath = \"policy.planner-estimator.tree.look_ahead\"\nvalues = [3]\n");
    let e = expand(&sweep(&ok), Path::new("s.toml"), false).unwrap();
    assert_eq!(e.cells[0].scenario.policy.planner_estimator.tree.look_ahead, Some(3));
    let bad = format!("{HEAD}[[axis]]\npath = \"fleet.n_auvs\"\nvalues = [2, 0]\n");
    let p = problems(&bad);
    assert_eq!(p.len(), 1, "{p:#?}");
    assert!(
        p[0].starts_with("cell default, fleet.n_auvs = 0: scenario default, fleet.n_auvs = 0: field fleet.n_auvs"),
        "{}",
        p[0]
    );
    let table = format!("{HEAD}[[axis]]\npath = \"comms\"\nvalues = [1]\n");
    assert!(problems(&table)[0].contains("comms is a table, not a value"));
}

#[test]
fn the_cell_count_is_held_to_the_limit_before_expansion() {
    let values = (0..4000).map(|v| v.to_string()).collect::<Vec<_>>().join(", ");
    let text =
        format!("{HEAD}[[axis]]\npath = \"seed\"\nvalues = [{values}]\n[[axis]]\npath = \"dt\"\nvalues = [{values}]\n");
    let e = expand(&sweep(&text), Path::new("s.toml"), false).unwrap_err().to_string();
    assert!(e.contains("sweep cells ≈ 1.600e7") && e.contains("--allow-large"), "{e}");
}
