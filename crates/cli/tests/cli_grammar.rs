//! One grammar across commands: every command that writes a directory takes `-o/--output`, an
//! error prints once, as one cause chain, with no repeated text, and a file of another of
//! coopnav's formats is named as such.

mod common;

use common::coopnav;

#[test]
fn every_directory_writer_takes_dash_o_output() {
    let tmp = tempfile::tempdir().unwrap();
    let commands: &[&[&str]] = &[
        &["plan"],
        &["simulate"],
        &["channel"],
        &["nams"],
        &["hbl", "simulate"],
        &["hbl", "montecarlo"],
        &["hbl", "grid"],
        &["hbl", "tune"],
        &["hbl", "postprocess"],
        &["reproduce"],
        &["live", "import"],
    ];
    for command in commands {
        let help = coopnav(tmp.path(), &[command, &["--help"][..]].concat());
        let text = String::from_utf8_lossy(&help.stdout);
        assert!(text.contains("-o, --output <"), "{command:?} --help:\n{text}");
    }
}

#[test]
fn an_error_prints_once_as_a_cause_chain() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("bad.toml"), "no_such_field = 1\n").unwrap();
    let out = coopnav(tmp.path(), &["hbl", "simulate", "bad.toml", "-o", "run"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("unknown field `no_such_field`").count(), 1, "{err}");
    assert_eq!(err.matches("Error:").count(), 1, "{err}");
    assert!(err.contains("bad.toml"), "{err}");
    assert!(!tmp.path().join("run").exists());
}

#[test]
fn a_file_of_another_format_is_named_with_the_command_that_reads_it() {
    let tmp = tempfile::tempdir().unwrap();
    let printed = |args: &[&str], file: &str| {
        let out = coopnav(tmp.path(), args);
        assert!(out.status.success(), "{args:?}");
        std::fs::write(tmp.path().join(file), out.stdout).unwrap();
    };
    printed(&["plan", "--example"], "plan.toml");
    printed(&["simulate", "--example"], "mission.toml");
    let cases: [(&[&str], &str); 3] = [
        (&["simulate", "plan.toml", "-o", "run"], "plan.toml is a planning scenario (read by `coopnav plan FILE`"),
        (
            &["plan", "mission.toml", "-o", "run"],
            "mission.toml is a closed-loop mission (read by `coopnav simulate FILE`",
        ),
        (
            &["sweep", "plan", "mission.toml", "-o", "run"],
            "mission.toml is a closed-loop mission (read by `coopnav simulate FILE`",
        ),
    ];
    for (args, named) in cases {
        let out = coopnav(tmp.path(), args);
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.starts_with(&format!("Error: {named}")), "{args:?}: {err}");
        assert!(!tmp.path().join("run").exists());
    }
}

#[test]
fn summaries_print_no_rust_debug_structs() {
    let tmp = tempfile::tempdir().unwrap();
    assert!(coopnav(tmp.path(), &["hbl", "simulate", "-o", "sim"]).status.success());
    let out = coopnav(tmp.path(), &["hbl", "postprocess", "sim/log.csv", "-o", "post"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    let summary: &str = text.split("wrote").next().unwrap();
    let json: serde_json::Value = serde_json::from_str(summary).expect("the summary prints as JSON");
    assert!(json["ranges_applied"].as_u64().unwrap() > 0, "{text}");
    assert!(!text.contains("PostSummary"), "{text}");
}

/// A command's main input is positional: each usage line names it as an argument, and the old
/// `--config FILE` / `--log FILE` forms are refused, not reinterpreted, and write nothing.
#[test]
fn the_main_input_is_positional_and_the_old_flags_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let usages: &[(&[&str], &str)] = &[
        (&["simulate"], "Usage: coopnav simulate [OPTIONS] [SCENARIO]"),
        (&["nams"], "Usage: coopnav nams [OPTIONS] [FILE]"),
        (&["hbl", "simulate"], "Usage: coopnav hbl simulate [OPTIONS] [SCENARIO]"),
        (&["hbl", "montecarlo"], "Usage: coopnav hbl montecarlo [OPTIONS] [SCENARIO]"),
        (&["hbl", "grid"], "Usage: coopnav hbl grid [OPTIONS] [SCENARIO]"),
        (&["hbl", "tune"], "Usage: coopnav hbl tune [OPTIONS] "),
        (&["hbl", "postprocess"], "Usage: coopnav hbl postprocess [OPTIONS] "),
        (&["live", "auv"], "Usage: coopnav live auv [OPTIONS] --auv <AUV> [CONFIG]"),
        (&["live", "cna"], "Usage: coopnav live cna [OPTIONS] [SCENARIO]"),
    ];
    for (command, usage) in usages {
        let help = coopnav(tmp.path(), &[command, &["--help"][..]].concat());
        let text = String::from_utf8_lossy(&help.stdout);
        assert!(text.contains(usage), "{command:?} --help:\n{text}");
    }
    std::fs::write(tmp.path().join("x.toml"), "").unwrap();
    let old: &[&[&str]] = &[
        &["nams", "--config", "x.toml", "-o", "run"],
        &["hbl", "simulate", "--config", "x.toml", "-o", "run"],
        &["hbl", "postprocess", "--log", "x.toml", "-o", "run"],
        &["simulate", "x.toml", "--runs", "2", "--json", "c.json", "-o", "run"],
        &["bench", "planner", "--reps", "1"],
        &["channel", "--bearing-deg", "0", "-o", "run"],
        &["live", "auv", "--auv", "0", "--config", "x.toml", "--log", "run"],
    ];
    for args in old {
        let out = coopnav(tmp.path(), args);
        assert!(!out.status.success(), "{args:?} must be refused");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("unexpected argument"), "{args:?}: {err}");
        assert!(!tmp.path().join("run").exists() && !tmp.path().join("c.json").exists(), "{args:?} wrote");
    }
}

/// `-o` is optional under `hbl` as everywhere (a fresh `runs/hbl-<command>`), and `--example`
/// prints the scenario the command reads back as its positional file.
#[test]
fn hbl_writes_a_fresh_run_directory_without_dash_o_and_reads_its_own_example() {
    let tmp = tempfile::tempdir().unwrap();
    let example = coopnav(tmp.path(), &["hbl", "simulate", "--example"]);
    assert!(example.status.success());
    assert_eq!(
        example.stdout,
        coopnav(tmp.path(), &["hbl", "example", "scenario"]).stdout,
        "--example prints what `hbl example scenario` does"
    );
    std::fs::write(tmp.path().join("h.toml"), &example.stdout).unwrap();
    for _ in 0..2 {
        let out = coopnav(tmp.path(), &["hbl", "simulate", "h.toml"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let runs = tmp.path().join("runs");
    assert!(runs.join("hbl-simulate/summary.json").is_file() && runs.join("hbl-simulate-2/summary.json").is_file());
    let post = coopnav(tmp.path(), &["hbl", "postprocess", "runs/hbl-simulate/log.csv"]);
    assert!(post.status.success(), "{}", String::from_utf8_lossy(&post.stderr));
    assert!(runs.join("hbl-postprocess/estimates.csv").is_file());
    let config = coopnav(tmp.path(), &["hbl", "postprocess", "--example"]);
    assert!(config.status.success() && String::from_utf8_lossy(&config.stdout).contains("[auv]"));
}
