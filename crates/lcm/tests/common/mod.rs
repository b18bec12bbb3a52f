//! Helpers shared by the tests against the official LCM library: the JSON form of a value that
//! tests/py/interop.py also writes, running a child process with a deadline, and generating the
//! Python types from the repository's `.lcm` files with lcm-gen.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use coopnav_lcm::{Record, Value};
use serde_json::{json, Map, Value as Json};

/// The JSON form of a value (see tests/py/interop.py's docstring).
pub fn value_json(v: &Value) -> Json {
    match v {
        Value::Int8(x) => json!(x),
        Value::Int16(x) => json!(x),
        Value::Int32(x) => json!(x),
        Value::Int64(x) => json!(x),
        Value::Byte(x) => json!(x),
        Value::Boolean(x) => json!(x),
        Value::Float(x) => json!(format!("f:{:08x}", x.to_bits())),
        Value::Double(x) => json!(format!("d:{:016x}", x.to_bits())),
        Value::String(s) => json!(s),
        Value::Bytes(b) => Json::Array(b.iter().map(|x| json!(x)).collect()),
        Value::Array(items) => Json::Array(items.iter().map(value_json).collect()),
        Value::Struct(r) => record_json(r),
    }
}

/// The JSON form of a record: an object of its fields.
pub fn record_json(r: &Record) -> Json {
    Json::Object(r.fields.iter().map(|(k, v)| (k.clone(), value_json(v))).collect::<Map<_, _>>())
}

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

pub fn unhex(s: &str) -> Vec<u8> {
    (0..s.len()).step_by(2).map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex")).collect()
}

/// The crate's directory.
pub fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// tests/py/interop.py.
pub fn interop_py() -> PathBuf {
    crate_dir().join("tests/py/interop.py")
}

/// Waits for `child` until `timeout`, killing it (by its pid) past that; panics on a timeout.
pub fn wait_with_deadline(mut child: Child, timeout: Duration, what: &str) -> Output {
    let deadline = Instant::now() + timeout;
    loop {
        match child.try_wait().expect("try_wait") {
            Some(_) => return child.wait_with_output().expect("output"),
            None if Instant::now() >= deadline => {
                let _ = child.kill();
                let out = child.wait_with_output().expect("output");
                panic!("{what} did not finish within {timeout:?}; stderr:\n{}", String::from_utf8_lossy(&out.stderr));
            }
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// Runs a command to completion within `timeout`, panicking unless it succeeds.
pub fn run(cmd: &mut Command, timeout: Duration, what: &str) -> Output {
    let child = cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect(what);
    let out = wait_with_deadline(child, timeout, what);
    assert!(
        out.status.success(),
        "{what} failed ({}):\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The `.lcm` files of the repository.
pub fn lcm_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(crate_dir().join("lcm"))
        .expect("crates/lcm/lcm")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lcm"))
        .collect();
    files.sort();
    files
}

/// Generates Python types for `files` into `dir` with lcm-gen.
pub fn lcm_gen_python(lcm_gen: &str, files: &[PathBuf], dir: &Path) {
    run(
        Command::new(lcm_gen).arg("--python").arg("--ppath").arg(dir).args(files),
        Duration::from_secs(60),
        "lcm-gen --python",
    );
}

/// Runs tests/py/interop.py with `args` under `python`.
pub fn interop(python: &str, args: &[&dyn AsRef<std::ffi::OsStr>], timeout: Duration) -> Output {
    let mut cmd = Command::new(python);
    cmd.arg(interop_py());
    for a in args {
        cmd.arg(a);
    }
    run(&mut cmd, timeout, "tests/py/interop.py")
}

/// A child process killed (by its pid) and reaped when dropped, should a test panic before it
/// stops the child itself.
pub struct Reaped(pub Child);

impl std::ops::Deref for Reaped {
    type Target = Child;
    fn deref(&self) -> &Child {
        &self.0
    }
}

impl std::ops::DerefMut for Reaped {
    fn deref_mut(&mut self) -> &mut Child {
        &mut self.0
    }
}

impl Drop for Reaped {
    fn drop(&mut self) {
        if matches!(self.0.try_wait(), Ok(None)) {
            let _ = self.0.kill();
        }
        let _ = self.0.wait();
    }
}
