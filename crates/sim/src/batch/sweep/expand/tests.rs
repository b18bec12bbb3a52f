use super::*;

fn sweep(text: &str) -> SweepFile {
    SweepFile::parse(text, Path::new("s.toml")).unwrap()
}

fn problems(text: &str) -> Vec<String> {
    match expand(&sweep(text), Path::new("s.toml"), false) {
        Err(SweepFileError::Invalid { file, problems }) => {
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
        format!("{HEAD}[[axis]]\nname = \"base_seed\"\npath = \"seed\"\nvalues = [{values}]\n[[axis]]\npath = \"dt\"\nvalues = [{values}]\n");
    let e = expand(&sweep(&text), Path::new("s.toml"), false).unwrap_err().to_string();
    assert!(e.contains("sweep cells ≈ 1.600e7") && e.contains("--allow-large"), "{e}");
}

fn expand_form(text: &str, form: Form) -> Result<Expansion, SweepFileError> {
    let file = Path::new("s.toml");
    expand_with(&sweep(text), file, form, false, &from_disk(file))
}

fn form_problems(text: &str, form: Form) -> Vec<String> {
    match expand_form(text, form) {
        Err(SweepFileError::Invalid { problems, .. }) => problems,
        other => panic!("expected the file to be refused, got {other:?}"),
    }
}

/// The fleet-size axis given per scenario, and the schedule sized for the fleet from 6 AUVs on:
/// at the default mission's 30 s period 6 AUVs' slots cannot hold a 1 km range (the cell is
/// invalid without the overlay).
const SIZED: &str = "policies = [\"racetrack\"]\nruns = 1\n\
                     [[axis]]\nname = \"size\"\npath = \"fleet.n_auvs\"\n\
                     [[scenario]]\nfile = \"default\"\nvalues = { size = [5, 6] }\n\
                     [[conditional]]\noverlay = \"sized\"\nwhen = { size = { min = 6 } }\n\
                     [overlay.sized]\ncomms = { tau = 44.0, cna_rate = 1, status_rate = 1, max_range_m = 2500.0 }\n";

#[test]
fn a_conditional_overlay_applies_exactly_from_its_minimum_on() {
    let e = expand_form(SIZED, Form::Full).unwrap();
    let base = Scenario::parse(EXAMPLE, Path::new("x")).unwrap().comms;
    let got: Vec<(usize, f64, f64)> =
        e.cells.iter().map(|c| (c.scenario.fleet.n_auvs, c.scenario.comms.tau, c.scenario.comms.max_range_m)).collect();
    assert_eq!(got, [(5, base.tau, base.max_range_m), (6, 44.0, 2500.0)]);
    assert_eq!(e.axes, ["size"]);
    assert_eq!(e.cells[1].label(), "default, size = 6");
    // The rules make the cell of any value the same way: 7 is sized, 1 is not.
    let of = |n: i64| e.rules.scenario(&e.bases[0].scenario, &[toml::Value::Integer(n)]).unwrap().comms.tau;
    assert_eq!((of(1), of(5), of(6), of(7)), (base.tau, base.tau, 44.0, 44.0));
    assert_eq!(e.rules.scenario(&e.bases[0].scenario, &[toml::Value::Integer(6)]).unwrap(), e.cells[1].scenario);
    // From 7 on, the 6-AUV cell keeps the 30 s period its slots cannot hold: refused, named.
    let p = form_problems(&SIZED.replace("min = 6", "min = 7"), Form::Full);
    assert_eq!(p.len(), 1, "{p:#?}");
    assert!(p[0].starts_with("cell default, size = 6: "), "{}", p[0]);
    // max and in: up to 5 (only the first cell), and one of [6].
    let e = expand_form(
        &SIZED.replace("min = 6", "max = 5").replace("values = { size = [5, 6] }", "values = { size = [4, 5] }"),
        Form::Full,
    )
    .unwrap();
    assert_eq!(e.cells.iter().map(|c| c.scenario.comms.tau).collect::<Vec<_>>(), [44.0, 44.0]);
    let e = expand_form(&SIZED.replace("min = 6", "in = [6]"), Form::Full).unwrap();
    assert_eq!(e.cells.iter().map(|c| c.scenario.comms.tau).collect::<Vec<_>>(), [base.tau, 44.0]);
}

#[test]
fn a_malformed_condition_names_its_field() {
    let bad = |from: &str, to: &str| {
        let text = SIZED.replace(from, to);
        assert_ne!(text, SIZED);
        form_problems(&text, Form::Full)
    };
    let p = bad("min = 6", "minimum = 6");
    assert_eq!(p.len(), 1, "{p:#?}");
    assert!(p[0].starts_with("conditional[0].when.size = { minimum = 6 }: unknown field `minimum`"), "{}", p[0]);
    assert!(p[0].contains("allowed: a table of min, max and in"), "{}", p[0]);
    let p = bad("when = { size", "when = { siz");
    assert_eq!(p, ["conditional[0].when.siz: no axis named siz (axes: size)"]);
    let p = bad("{ min = 6 }", "6");
    assert!(p[0].starts_with("conditional[0].when.size = 6: invalid type: integer `6`"), "{}", p[0]);
    let p = bad("{ min = 6 }", "{}");
    assert_eq!(p, ["conditional[0].when.size = {}: give min, max or in"]);
    let p = bad("min = 6", "min = 7, max = 6");
    assert_eq!(p, ["conditional[0].when.size: min = 7 is above max = 6: no value meets it"]);
    let p = bad("overlay = \"sized\"", "overlay = \"size\"");
    assert!(p.iter().any(|x| x == "conditional[0].overlay = \"size\": no [overlay.size] (allowed: sized)"), "{p:#?}");
    let p = bad("[5, 6]", "[\"five\"]");
    assert!(p.iter().any(|x| x.starts_with("scenario[0].values.size[0] = \"five\": ")), "{p:#?}");
    assert!(
        p.iter().any(|x| x.contains("min and max compare numbers, and axis size has the value \"five\"")),
        "{p:#?}"
    );
}

/// Two base scenarios (both the default mission, named apart) each with its own fleet sizes,
/// crossed with an overlay axis; the reduced form keeps some, in its own order, with its runs
/// and its overlay last.
const PER_SCENARIO: &str = "policies = [\"racetrack\", \"zigzag\"]\nruns = 4\n\
                            [[axis]]\nname = \"n\"\npath = \"fleet.n_auvs\"\n\
                            [[axis]]\noverlays = [\"x\", \"y\"]\n\
                            [[scenario]]\nname = \"a\"\nfile = \"default\"\nvalues = { n = [2, 3] }\n\
                            [[scenario]]\nname = \"b\"\nfile = \"default\"\nvalues = { n = [4], overlay = [\"y\"] }\n\
                            [overlay.x]\n[overlay.y]\ncomms = { tau = 40.0 }\n[overlay.short]\nduration_s = 900.0\n\
                            [reduced]\nruns = 1\noverlay = \"short\"\n\
                            scenario = [{ name = \"b\" }, { name = \"a\", values = { n = [3] } }]\n";

#[test]
fn each_scenario_flies_its_own_values_and_the_reduced_form_its_own_cells() {
    let label = |e: &Expansion| e.cells.iter().map(Cell::label).collect::<Vec<_>>();
    let full = expand_form(PER_SCENARIO, Form::Full).unwrap();
    assert_eq!(
        label(&full),
        [
            "a, n = 2, overlay = \"x\"",
            "a, n = 2, overlay = \"y\"",
            "a, n = 3, overlay = \"x\"",
            "a, n = 3, overlay = \"y\"",
            "b, n = 4, overlay = \"y\""
        ]
    );
    assert_eq!((full.runs, full.cells[4].scenario.comms.tau, full.cells[4].scenario.duration_s), (4, 40.0, 3600.0));
    let reduced = expand_form(PER_SCENARIO, Form::Reduced).unwrap();
    assert_eq!(
        label(&reduced),
        ["b, n = 4, overlay = \"y\"", "a, n = 3, overlay = \"x\"", "a, n = 3, overlay = \"y\""]
    );
    assert_eq!(reduced.runs, 1);
    assert!(reduced.cells.iter().all(|c| c.scenario.duration_s == 900.0));
    assert_eq!(reduced.form, Form::Reduced);
    // The short form has no per-scenario values, nor a reduced form unless it has a [reduced].
    let p = form_problems(HEAD, Form::Reduced);
    assert_eq!(p, ["no [reduced] table: the file has no reduced form"]);
}

#[test]
fn bad_per_scenario_and_reduced_values_are_named() {
    let bad = |from: &str, to: &str| {
        let text = PER_SCENARIO.replace(from, to);
        assert_ne!(text, PER_SCENARIO);
        form_problems(&text, Form::Full)
    };
    let has = |p: &[String], needle: &str| assert!(p.iter().any(|x| x.contains(needle)), "no {needle:?}: {p:#?}");
    has(
        &bad("values = { n = [4], ", "values = { "),
        "axis[0]: path needs its values (values = [...], or values.n in every [[scenario]])",
    );
    has(
        &bad("values = { n = [2, 3] }", "values = { n = [2, 3], m = [1] }"),
        "scenario[0].values.m: no axis named m (axes: n, overlay)",
    );
    has(
        &bad("overlay = [\"y\"]", "overlay = [\"z\"]"),
        "scenario[1].values.overlay[0] = \"z\": no [overlay.z] (allowed: short, x, y)",
    );
    has(&bad("n = [4]", "n = []"), "scenario[1].values.n = []: give at least one value");
    has(&bad("name = \"b\"\n", "name = \"a\"\n"), "scenario[1]: a second base scenario named \"a\"");
    has(
        &bad("{ name = \"b\" }", "{ name = \"c\" }"),
        "reduced.scenario[0].name = \"c\": no such base scenario (allowed: a, b)",
    );
    has(&bad("values = { n = [3] } }", "values = { n = [0.5] } }"), "reduced.scenario[1].values.n[0] = 0.5: ");
    has(&bad("overlay = \"short\"", "overlay = \"shorter\""), "reduced.overlay = \"shorter\": no [overlay.shorter]");
    has(&bad("runs = 1\n", "runs = 0\n"), "reduced.runs = 0: allowed at least 1");
    let both = PER_SCENARIO.replace("runs = 4\n", "runs = 4\nscenarios = [\"default\"]\n");
    has(&form_problems(&both, Form::Full), "give either scenarios = [...] or [[scenario]] tables, not both");
}

#[test]
fn a_path_indexes_an_array_entry_and_keeps_the_others() {
    let text = format!("{HEAD}[[axis]]\npath = \"comms.success.curves[1].p_a\"\nvalues = [0.5, 0.7]\n");
    let e = expand(&sweep(&text), Path::new("s.toml"), false).unwrap();
    let base = Scenario::parse(EXAMPLE, Path::new("x")).unwrap();
    let curves = |s: &Scenario| toml::Value::try_from(s).unwrap()["comms"]["success"]["curves"].clone();
    let (before, first) = (curves(&base), curves(&e.cells[0].scenario));
    let entries = before.as_array().unwrap().len();
    assert!(entries >= 2, "{before}");
    for k in (0..entries).filter(|&k| k != 1) {
        assert_eq!(first[k], before[k], "entry {k} kept");
    }
    assert_eq!((first[1]["p_a"].as_float(), curves(&e.cells[1].scenario)[1]["p_a"].as_float()), (Some(0.5), Some(0.7)));
    assert_eq!(first[1]["tl_ab"], before[1]["tl_ab"]);
    assert_eq!(e.cells[1].label(), "default, comms.success.curves[1].p_a = 0.7");
    let bad = |path: &str| problems(&format!("{HEAD}[[axis]]\npath = \"{path}\"\nvalues = [0.5]\n"));
    let p = bad("comms.success.curves[9].p_a");
    assert_eq!(p, [format!("axis[0].path = \"comms.success.curves[9].p_a\": comms.success.curves has {entries} entries, none at [9] in scenario default")]);
    let p = bad("comms.tau[0]");
    assert!(p[0].contains("comms.tau is not an array (an index [0] needs one)"), "{p:#?}");
    let p = bad("comms.success.curves[x].p_a");
    assert!(p[0].contains("`curves[x]`: an index is written [N], N a whole number from 0"), "{p:#?}");
    let p = bad("comms.success.curves[1].p_b");
    assert!(p[0].contains("no field `p_b` in [comms.success.curves[1]]"), "{p:#?}");
}

#[test]
fn an_axis_named_like_a_results_column_is_refused_given_or_by_its_path() {
    let named = format!("{HEAD}[[axis]]\nname = \"n_auvs\"\npath = \"fleet.n_auvs\"\nvalues = [2, 3]\n");
    let p = problems(&named);
    assert_eq!(p, ["axis[0].name = \"n_auvs\": a column of the results tables already has that name (give another)"]);
    let by_path = format!("{HEAD}[[axis]]\npath = \"seed\"\nvalues = [1, 2]\n");
    let p = problems(&by_path);
    assert_eq!(
        p,
        ["axis[0].path = \"seed\": a column of the results tables already has that name (give the axis a name)"]
    );
    let renamed = format!("{HEAD}[[axis]]\nname = \"base_seed\"\npath = \"seed\"\nvalues = [1, 2]\n");
    assert_eq!(expand(&sweep(&renamed), Path::new("s.toml"), false).unwrap().axes, ["base_seed"]);
}
