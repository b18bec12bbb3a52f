//! Tells the tests whether coopnav's Python package is built into tools/pyenv (cfg
//! `python_package_installed`), so the pytest suite is reported as ignored, with its reason, when
//! it is not — never as passed. scripts/install-python.sh writes the stamp this looks for.

use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(python_package_installed)");
    println!("cargo:rerun-if-changed=build.rs");
    let stamp = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/pyenv/coopnav-installed");
    if stamp.is_file() {
        println!("cargo:rerun-if-changed={}", stamp.display());
        println!("cargo:rustc-cfg=python_package_installed");
    }
}
