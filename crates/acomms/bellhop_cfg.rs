// Shared by the build scripts of the crates whose tests need the real BELLHOP (`include!`d, so
// the rule is written once): sets cfg `bellhop_installed` when it is found as `Bellhop::locate`
// looks for it: `$COOPNAV_BELLHOP`, else tools/bellhop/bellhop.exe at the repository root.

/// Emits the cfg (and what to watch) for the crate at `manifest_dir`, two levels below the root
/// (`CARGO_MANIFEST_DIR` read when the script runs: one compiled build script serves every checkout
/// sharing a target directory).
fn detect_bellhop(manifest_dir: &str) {
    use std::path::Path;
    println!("cargo::rustc-check-cfg=cfg(bellhop_installed)");
    println!("cargo:rerun-if-env-changed=COOPNAV_BELLHOP");
    let bundled = Path::new(manifest_dir).join("../../tools/bellhop/bellhop.exe");
    let installed = match std::env::var_os("COOPNAV_BELLHOP") {
        Some(path) => Path::new(&path).is_file(),
        None => bundled.is_file(),
    };
    if installed {
        println!("cargo:rerun-if-changed={}", bundled.display());
        println!("cargo:rustc-cfg=bellhop_installed");
    }
}
