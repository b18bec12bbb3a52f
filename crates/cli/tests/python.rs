//! The Python package's pytest suite (python/tests), run in the venv scripts/install-python.sh
//! builds, against this build's `coopnav` binary: every Python API must give the CLI's numbers.
//! Ignored, with the reason, when the package is not installed.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::SystemTime;

/// The newest modification time of any Rust source or manifest under `dir`.
fn newest_source(dir: &Path) -> Option<(SystemTime, PathBuf)> {
    let mut newest: Option<(SystemTime, PathBuf)> = None;
    for entry in std::fs::read_dir(dir).ok()?.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let candidate = if path.is_dir() {
            if name == "target" {
                continue;
            }
            newest_source(&path)
        } else if path.extension().is_some_and(|e| e == "rs") || name == "Cargo.toml" {
            entry.metadata().ok()?.modified().ok().map(|t| (t, path))
        } else {
            None
        };
        if let Some(c) = candidate {
            if newest.as_ref().is_none_or(|n| c.0 > n.0) {
                newest = Some(c);
            }
        }
    }
    newest
}

/// Runs the pytest suite, restricted by the `-k` expression `select`, against this build's CLI;
/// fails unless pytest passes with no test skipped (a skip inside a passing Rust test would hide
/// it: the tests that need a tool are selected only where the tool is).
fn run_pytest(select: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repository root");
    let python = option_env!("COOPNAV_PYENV_FOUND").expect("build.rs sets it with cfg python_package_installed");
    // A package built from older sources would test old code and could pass where this checkout
    // fails (it did once: CI caught a changed error message a stale local build hid).
    let module = Command::new(python)
        .args(["-c", "import coopnav._coopnav as m; print(m.__file__)"])
        .output()
        .expect("ask the venv where the compiled module is");
    let module = PathBuf::from(String::from_utf8_lossy(&module.stdout).trim());
    let built = std::fs::metadata(&module)
        .and_then(|m| m.modified())
        .unwrap_or_else(|e| panic!("cannot read the compiled module {}: {e}", module.display()));
    // The library crates the package links (the CLI crate and its tests are not part of it).
    let library_sources = std::fs::read_dir(root.join("crates"))
        .expect("list crates/")
        .flatten()
        .filter(|crate_dir| crate_dir.file_name() != "cli")
        .flat_map(|crate_dir| [crate_dir.path().join("src"), crate_dir.path().join("Cargo.toml")]);
    let package_sources = [root.join("python/src"), root.join("python/Cargo.toml")];
    for dir in library_sources.chain(package_sources) {
        let newest = if dir.is_file() {
            std::fs::metadata(&dir).and_then(|m| m.modified()).ok().map(|t| (t, dir.clone()))
        } else {
            newest_source(&dir)
        };
        if let Some((changed, path)) = newest {
            assert!(
                changed <= built,
                "the Python package in {} is older than {}: rebuild it with scripts/install-python.sh",
                module.display(),
                path.display()
            );
        }
    }
    let out = Command::new(python)
        .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", "-k", select, "python/tests"])
        .current_dir(&root)
        .env("COOPNAV_CLI", env!("CARGO_BIN_EXE_coopnav"))
        .output()
        .expect("run pytest in tools/pyenv");
    let report = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    println!("{report}");
    assert!(out.status.success(), "pytest failed:\n{report}");
    let summary = report.lines().rev().find(|l| l.contains(" in ") && l.contains("passed")).unwrap_or_default();
    assert!(!summary.is_empty(), "no pytest summary line with passed tests:\n{report}");
    assert!(!summary.contains("skipped"), "pytest skipped tests (the reasons are above):\n{report}");
}

/// The pytest tests that need BELLHOP, in a Rust test of their own that is ignored without it.
const NEEDS_BELLHOP: &str = "bellhop";

#[test]
#[cfg_attr(
    not(python_package_installed),
    ignore = "coopnav's Python package is not built into tools/pyenv (or $COOPNAV_PYENV_PYTHON): run scripts/install-python.sh"
)]
fn the_python_package_passes_its_pytest_suite_against_this_cli() {
    run_pytest(&format!("not {NEEDS_BELLHOP}"));
}

#[test]
#[cfg_attr(
    not(all(python_package_installed, bellhop_installed)),
    ignore = "needs coopnav's Python package (scripts/install-python.sh) and BELLHOP (scripts/install-bellhop.sh)"
)]
fn the_python_package_matches_the_cli_with_bellhop() {
    run_pytest(NEEDS_BELLHOP);
}
