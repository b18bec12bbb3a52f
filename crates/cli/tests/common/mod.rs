//! What the CLI tests share: running the built `coopnav` binary in a directory, and editing the
//! input files its `--example`s print.

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

/// Writes `file` in `dir`: the stdout of `coopnav ARGS` (an `--example`) with each `(from, to)`
/// replaced once; each `from` must occur, so an edit cannot silently stop applying.
#[allow(dead_code)] // each test binary compiles this module; not all of them edit examples
pub fn edited_example(dir: &Path, args: &[&str], file: &str, edits: &[(&str, &str)]) {
    let out = coopnav(dir, args);
    assert!(out.status.success(), "`coopnav {args:?}` failed: {}", String::from_utf8_lossy(&out.stderr));
    let mut text = String::from_utf8(out.stdout).expect("examples are UTF-8");
    for (from, to) in edits {
        assert!(text.contains(from), "`coopnav {args:?}` no longer prints {from:?}");
        text = text.replacen(from, to, 1);
    }
    std::fs::write(dir.join(file), text).expect("writes the edited example");
}
