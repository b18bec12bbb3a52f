//! What the CLI tests share: running the built `coopnav` binary in a directory.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `coopnav ARGS` in `dir` (no backtraces: the user's view of an error) and waits for it.
pub fn coopnav(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("runs the binary")
}
