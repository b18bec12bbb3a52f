//! Tells the tests whether the real BELLHOP is installed (cfg `bellhop_installed`), so a test
//! that needs it is reported as ignored, with its reason, when it is absent — not as passed.
//! Looked for as `Bellhop::locate` does: `$COOPNAV_BELLHOP`, else tools/bellhop/bellhop.exe.
//! `.ci/run` installs BELLHOP before building; after installing it by hand, touch this file.

use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(bellhop_installed)");
    println!("cargo:rerun-if-env-changed=COOPNAV_BELLHOP");
    println!("cargo:rerun-if-changed=build.rs");
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/bellhop/bellhop.exe");
    let installed = match std::env::var_os("COOPNAV_BELLHOP") {
        Some(path) => Path::new(&path).is_file(),
        None => bundled.is_file(),
    };
    if installed {
        println!("cargo:rerun-if-changed={}", bundled.display());
        println!("cargo:rustc-cfg=bellhop_installed");
    }
}
