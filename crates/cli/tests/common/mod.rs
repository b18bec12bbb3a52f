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

/// What the kernel accounted to one finished child: CPU seconds (user + system) and peak
/// resident memory (kB).
#[allow(dead_code)] // not every test binary measures
pub struct Usage {
    pub cpu_s: f64,
    pub peak_kb: u64,
}

/// Runs `coopnav ARGS` in `dir` as [`coopnav`] does and reaps it with wait4(2), so its CPU time
/// and peak memory come from the kernel, whatever tools the machine has.
#[allow(dead_code)]
pub fn measured(dir: &Path, args: &[&str]) -> (Output, Usage) {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_coopnav"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "0")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs the binary");
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            pipe.read_to_end(&mut bytes).expect("reads the child's output");
            bytes
        })
    };
    let out = drain(Box::new(child.stdout.take().expect("piped")));
    let err = drain(Box::new(child.stderr.take().expect("piped")));
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    // SAFETY: waits for our own child, with valid pointers to a status word and a rusage.
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t, "wait4 failed: {}", std::io::Error::last_os_error());
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let output = Output {
        status: std::os::unix::process::ExitStatusExt::from_raw(status),
        stdout: out.join().expect("stdout reader"),
        stderr: err.join().expect("stderr reader"),
    };
    let usage = Usage { cpu_s: seconds(usage.ru_utime) + seconds(usage.ru_stime), peak_kb: usage.ru_maxrss as u64 };
    (output, usage)
}

/// Copies directory `from` into `to`, recursively (a test's own copy of the library's scenarios).
#[allow(dead_code)] // not every test binary copies a directory
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}
