// Shared by the build scripts of the crates whose tests need the real BELLHOP (`include!`d, so
// the rule is written once): sets cfg `bellhop_installed` when it is found as `Bellhop::locate`
// looks for it: `$COOPNAV_BELLHOP`, else tools/bellhop/bellhop.exe at the repository root.
//
// What it watches, so installing or removing BELLHOP after a build re-runs it (no clean build):
// the binary when found; when not, the directory it would appear in, or the nearest existing one
// above it (tools/ at the root is always there: it is in the repository).

/// Emits the cfg (and what to watch) for the crate at `manifest_dir`, two levels below the root
/// (`CARGO_MANIFEST_DIR` read when the script runs: one compiled build script serves every checkout
/// sharing a target directory).
fn detect_bellhop(manifest_dir: &str) {
    use std::path::{Path, PathBuf};
    println!("cargo::rustc-check-cfg=cfg(bellhop_installed)");
    println!("cargo:rerun-if-env-changed=COOPNAV_BELLHOP");
    let root = Path::new(manifest_dir).join("../..");
    let exe = std::env::var_os("COOPNAV_BELLHOP")
        .map_or_else(|| root.join("tools/bellhop/bellhop.exe"), PathBuf::from);
    if exe.is_file() {
        println!("cargo:rerun-if-changed={}", exe.display());
        println!("cargo:rustc-cfg=bellhop_installed");
        return;
    }
    // Where it would appear: the nearest existing directory above it, never the root itself or
    // the file system's root (a directory is watched with everything below it).
    let root = root.canonicalize().unwrap_or(root);
    let watched = exe.ancestors().skip(1).find(|d| d.is_dir()).map(|d| d.canonicalize().unwrap_or(d.to_path_buf()));
    match watched {
        Some(dir) if dir != root && dir.parent().is_some() => println!("cargo:rerun-if-changed={}", dir.display()),
        _ => println!("cargo:rerun-if-changed={}", root.join("tools").display()),
    }
}
