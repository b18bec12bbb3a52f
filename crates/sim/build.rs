//! Tells the tests whether the real BELLHOP is installed (cfg `bellhop_installed`, the rule in
//! `crates/acomms/bellhop_cfg.rs`): scenarios that use it are ignored, with the reason, without it.

include!("../acomms/bellhop_cfg.rs");

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../acomms/bellhop_cfg.rs");
    detect_bellhop(&std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR for build scripts"));
}
