//! The Python package's pytest suite (python/tests), run in the venv scripts/install-python.sh
//! builds, against this build's `coopnav` binary: every Python API must give the CLI's numbers.
//! Ignored, with the reason, when the package is not installed.

use std::path::Path;
use std::process::Command;

#[test]
#[cfg_attr(
    not(python_package_installed),
    ignore = "coopnav's Python package is not built into tools/pyenv (or $COOPNAV_PYENV_PYTHON): run scripts/install-python.sh"
)]
fn the_python_package_passes_its_pytest_suite_against_this_cli() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let python = option_env!("COOPNAV_PYENV_FOUND").expect("build.rs sets it with cfg python_package_installed");
    let out = Command::new(python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "python/tests"])
        .current_dir(&root)
        .env("COOPNAV_CLI", env!("CARGO_BIN_EXE_coopnav"))
        .output()
        .expect("run pytest in tools/pyenv");
    let report = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    println!("{report}");
    assert!(out.status.success(), "pytest failed:\n{report}");
}
