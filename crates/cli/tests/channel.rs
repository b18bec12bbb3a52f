//! `coopnav channel` end to end: a good run writes its files; bad input exits non-zero, says
//! what was wrong and writes nothing.

use std::process::Command;

fn coopnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).env("RUST_BACKTRACE", "0").output().expect("run coopnav")
}

#[test]
fn writes_table_csv_and_svgs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ch");
    let o = coopnav(&["channel", "--step", "500", "--noise-db", "6", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(table.lines().count(), 1 + 6, "header + 6 ranges:\n{table}");
    for f in ["tl.svg", "success.svg", "channel.csv", "manifest.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let again = coopnav(&["channel", "-o", out.to_str().unwrap()]);
    assert!(!again.status.success(), "refuses to overwrite without --force");
}

#[test]
fn bad_input_is_rejected_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ch");
    let o = coopnav(&["channel", "--step", "0", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--step"));
    let bad = dir.path().join("grid.csv");
    std::fs::write(&bad, "x,y,depth\n0,0,10\n10,0,oops\n").unwrap();
    let o = coopnav(&["channel", "--bathymetry", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("grid.csv") && err.contains("line 3"), "{err}");
    let o2 = Command::new(env!("CARGO_BIN_EXE_coopnav"))
        .args(["channel", "--model", "bellhop", "-o", out.to_str().unwrap()])
        .env("COOPNAV_BELLHOP", "/nonexistent/bellhop.exe")
        .output()
        .unwrap();
    assert!(!o2.status.success() && String::from_utf8_lossy(&o2.stderr).contains("install-bellhop.sh"));
    assert!(!out.exists(), "no partial output");
}
