//! `coopnav hbl postprocess` never drops rows in silence: rows it does not use are warnings on
//! stderr, and under `--strict` an error that writes nothing.

use std::process::Command;

fn coopnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).output().expect("run coopnav")
}

#[test]
fn unused_rows_warn_and_strict_refuses_them() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("log.csv");
    // A speed row before init, a second init, and a buoy range with no buoy fix at all.
    std::fs::write(
        &log,
        "t,kind,src,v1,v2,v3,v4\n-1,speed,,1,,,\n0,init,,0,0,1,90\n1,init,,5,5,1,90\n2,range,13,0.1,,,\n",
    )
    .unwrap();
    let post = tmp.path().join("post");
    let args = |dir: &std::path::Path, strict: bool| {
        let mut a = vec!["hbl", "postprocess", "--log", log.to_str().unwrap(), "--out"];
        a.push(dir.to_str().unwrap());
        if strict {
            a.push("--strict");
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| coopnav(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let out = run(args(&post, false));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    for said in ["1 row(s) timed before the first 'init'", "1 'init' row(s) after the first", "1 range(s) had no"] {
        assert!(err.contains(said), "missing {said:?} in {err}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(post.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ranges_without_fix"], 1);
    let strict = tmp.path().join("strict");
    let out = run(args(&strict, true));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--strict") && err.contains("log.csv") && err.contains("1 range(s) had no"), "{err}");
    assert!(!strict.exists());
}
