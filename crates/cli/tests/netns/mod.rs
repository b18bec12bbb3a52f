//! What the live-process tests share: a private network namespace for the test (it re-runs
//! itself under `unshare -n`, found by build.rs, brings up the namespace's loopback, routes
//! multicast to it and checks loopback is the only interface, so no datagram can leave), a child
//! `coopnav live ...` started and listening, its summary and its CPU from the kernel (wait4), and
//! an end by its pid. Every loop is bounded in count and time.

#![allow(dead_code)] // each test binary compiles this module; not all of them use every helper

use coopnav_lcm::messages::{Clock, Decision, Message};
use coopnav_lcm::{Schema, Udpm};
use coopnav_live::CnaChannels;
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const IN_NETNS: &str = "COOPNAV_LIVE_IN_NETNS";

#[cfg(private_netns)]
fn unshare() -> (&'static str, &'static str) {
    (env!("COOPNAV_UNSHARE_FOUND"), env!("COOPNAV_UNSHARE_FLAGS"))
}
#[cfg(not(private_netns))]
fn unshare() -> (&'static str, &'static str) {
    unreachable!("the tests needing a private namespace are ignored without one")
}

/// Runs `coopnav` with `args`, its stdin closed, bounded by `timeout` (killed by its pid past it).
pub fn coopnav_bounded(args: &[&str], timeout: Duration) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_coopnav"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_or_kill(child, timeout, &format!("coopnav {args:?}"))
}

/// Runs `coopnav` with `args` as [`coopnav_bounded`], checks that it succeeded and returns its
/// stdout.
pub fn coopnav_ok(args: &[&str], timeout: Duration) -> String {
    let out = coopnav_bounded(args, timeout);
    assert!(out.status.success(), "coopnav {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `coopnav` with `args` (bounded by 20 s) and checks that it fails with a message
/// containing `expected`.
pub fn refused(args: &[&str], expected: &str) {
    let out = coopnav_bounded(args, Duration::from_secs(20));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains(expected), "{args:?}: {err}");
}

/// Watches the decision records on `url` and, at the one numbered `seq`, publishes a stopped
/// clock, so the CNA process stops commanding. The thread gives up after 60 s; it returns whether
/// it saw that decision.
pub fn stop_clock_at_decision(url: &str, seq: i64) -> std::thread::JoinHandle<bool> {
    let ch = CnaChannels::default();
    let mut watch = Udpm::new(url).unwrap();
    watch.subscribe(&ch.decision).unwrap();
    std::thread::spawn(move || {
        let (schema, start) = (Schema::coopnav(), Instant::now());
        while start.elapsed() < Duration::from_secs(60) {
            let Some(m) = watch.recv_timeout(Duration::from_millis(200)).unwrap() else { continue };
            if Decision::decode(&schema, &m.data).unwrap().seq == seq {
                let stop = Clock { running: false, ..Clock::default() }.encode(&schema).unwrap();
                watch.publish(&ch.clock, &stop).unwrap();
                return true;
            }
        }
        false
    })
}

/// Waits for `child` at most `timeout`; past it, kills it (by its pid) and panics.
pub fn wait_or_kill(mut child: Child, timeout: Duration, what: &str) -> Output {
    let deadline = Instant::now() + timeout;
    loop {
        if child.try_wait().expect("try_wait").is_some() {
            return child.wait_with_output().expect("output");
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let out = child.wait_with_output().expect("output");
            panic!("{what} did not finish within {timeout:?}; stderr:\n{}", String::from_utf8_lossy(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn ip(args: &[&str]) -> String {
    let child = Command::new("ip").args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("ip");
    let out = wait_or_kill(child, Duration::from_secs(10), "ip");
    assert!(out.status.success(), "ip {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Outside a namespace, re-runs test `name` under `unshare -n` and asserts it passed there;
/// inside, sets up multicast on the private loopback and runs `body`.
pub fn in_private_netns(name: &str, body: impl FnOnce()) {
    if std::env::var_os(IN_NETNS).is_none() {
        let exe = std::env::current_exe().expect("test binary");
        let child = Command::new(unshare().0)
            .arg(unshare().1)
            .arg(exe)
            .args([name, "--exact", "--nocapture", "--test-threads=1", "--include-ignored"])
            .env(IN_NETNS, "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("unshare -n");
        let out = wait_or_kill(child, Duration::from_secs(300), "the test inside unshare -n");
        let stdout = String::from_utf8_lossy(&out.stdout);
        println!("{stdout}");
        assert!(
            out.status.success() && stdout.contains("1 passed"),
            "inside the namespace:\n{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        return;
    }
    let links = ip(&["-o", "link"]);
    assert_eq!(links.lines().count(), 1, "not a private namespace: {links}");
    assert!(links.contains(": lo:"), "{links}");
    ip(&["link", "set", "lo", "up"]);
    ip(&["route", "add", "224.0.0.0/4", "dev", "lo"]);
    body();
}

/// A child `coopnav live ...`, started and listening (it announces on stderr once subscribed).
pub struct Live {
    pub child: Option<Child>,
    pub stderr: mpsc::Receiver<String>,
}

impl Live {
    /// Starts `coopnav ARGS` and waits (at most 20 s) for its `listening:` line.
    pub fn start(args: &[&str]) -> Live {
        let mut child = Command::new(env!("CARGO_BIN_EXE_coopnav"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("starts coopnav live");
        let (tx, rx) = mpsc::channel();
        let err = child.stderr.take().expect("piped");
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().take(10_000) {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let live = Live { child: Some(child), stderr: rx };
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match live.stderr.recv_timeout(left) {
                Ok(line) if line.starts_with("listening:") => return live,
                Ok(_) => continue,
                Err(_) => panic!("coopnav {args:?} did not announce that it listens within 20 s"),
            }
        }
    }

    /// Waits for its exit (at most `timeout`, then kills it by pid) and returns its summary and
    /// the CPU seconds (user + system) the kernel accounted to it (wait4).
    pub fn finish(mut self, timeout: Duration) -> (serde_json::Value, f64) {
        let mut child = self.child.take().expect("running");
        let pid = child.id() as libc::pid_t;
        let deadline = Instant::now() + timeout;
        // SAFETY: wait4 on our own child's pid, writing only the status and rusage given.
        let mut status = 0;
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        loop {
            let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
            assert!(r >= 0, "wait4: {}", std::io::Error::last_os_error());
            if r == pid {
                break;
            }
            if Instant::now() >= deadline {
                // SAFETY: kill(2) on our own child's pid, which is not yet reaped.
                unsafe { libc::kill(pid, libc::SIGKILL) };
                unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
                panic!("coopnav live (pid {pid}) did not stop within {timeout:?}: killed");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let mut out = String::new();
        child.stdout.take().expect("piped").read_to_string(&mut out).expect("stdout");
        let err: Vec<String> = self.stderr.try_iter().collect();
        let ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
        assert!(ok, "coopnav live failed (wait status {status}): {out}\n{}", err.join("\n"));
        let summary: serde_json::Value = serde_json::from_str(out.trim()).unwrap_or_else(|e| panic!("{e}: {out:?}"));
        let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        let kernel_cpu = tv(usage.ru_utime) + tv(usage.ru_stime);
        // The process's own figure (getrusage just before it prints) is within the kernel's.
        let own = summary["cpu_s"].as_f64().expect("cpu_s");
        assert!(own <= kernel_cpu + 1e-3 && kernel_cpu - own < 0.5, "own {own} s, kernel {kernel_cpu} s");
        (summary, kernel_cpu)
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            // SAFETY: kill(2) on our own child's pid, which is not yet reaped.
            unsafe { libc::kill(child.id() as i32, libc::SIGKILL) };
            let _ = child.wait();
        }
    }
}
