//! Tells the tests whether the real BELLHOP is installed (cfg `bellhop_installed`), so a test
//! that needs it is reported as ignored, with its reason, when it is absent — not as passed.
//! Installing BELLHOP after a build is noticed by the next one (`bellhop_cfg.rs` says what it watches).

include!("bellhop_cfg.rs");

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=bellhop_cfg.rs");
    detect_bellhop(&std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR for build scripts"));
}
