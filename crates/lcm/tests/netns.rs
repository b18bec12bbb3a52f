//! The UDP multicast transport against the official library (lcm 1.5.3's Python `lcm.LCM` and
//! `lcm-logger`), run only inside a private network namespace each test makes: the test re-runs
//! itself under `unshare -n`, where it brings up the namespace's own loopback, routes multicast
//! to it and uses TTL 0, so no datagram can reach a real network. Ignored, with the reason, where
//! the library or `unshare` is missing (crates/lcm/build.rs).

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use common::{hex, interop_py, run, unhex, wait_with_deadline, Reaped};
use coopnav_lcm::sample::{self, Rng};
use coopnav_lcm::{decode, encode, LogReader, Record, Schema, Udpm, Value};
use serde_json::json;

/// Set in the re-run inside the namespace.
const IN_NETNS: &str = "COOPNAV_LCM_IN_NETNS";
const URL: &str = "udpm://239.255.76.67:7667?ttl=0";

/// Runs `body` in a private network namespace: outside one, re-runs this test (by name) under
/// `unshare -n` and asserts it passed there; inside, sets up multicast on the namespace's loopback
/// and checks loopback is the only interface before running `body`.
fn in_private_netns(name: &str, body: impl FnOnce()) {
    if std::env::var_os(IN_NETNS).is_none() {
        let exe = std::env::current_exe().expect("test binary");
        let child = Command::new(unshare().0)
            .arg(unshare().1)
            .arg(exe)
            .args([name, "--exact", "--nocapture", "--test-threads=1"])
            .env(IN_NETNS, "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("unshare -n");
        let out = wait_with_deadline(child, Duration::from_secs(120), "the test inside unshare -n");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && stdout.contains("1 passed"),
            "inside the namespace:\n{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        return;
    }
    let links = run(Command::new("ip").args(["-o", "link"]), Duration::from_secs(10), "ip -o link");
    let links = String::from_utf8_lossy(&links.stdout);
    assert_eq!(links.lines().count(), 1, "not a private namespace: {links}");
    assert!(links.contains(": lo:"), "{links}");
    run(Command::new("ip").args(["link", "set", "lo", "up"]), Duration::from_secs(10), "ip link set lo up");
    run(Command::new("ip").args(["route", "add", "224.0.0.0/4", "dev", "lo"]), Duration::from_secs(10), "ip route add");
    body();
}

/// The `unshare` program and its flags the build script found to work.
#[cfg(private_netns)]
fn unshare() -> (&'static str, &'static str) {
    (env!("COOPNAV_UNSHARE_FOUND"), env!("COOPNAV_UNSHARE_FLAGS"))
}
#[cfg(not(private_netns))]
fn unshare() -> (&'static str, &'static str) {
    unreachable!("the tests needing a private namespace are ignored without one")
}

#[cfg(lcm_python)]
fn python() -> &'static str {
    env!("COOPNAV_LCM_PYTHON_FOUND")
}
#[cfg(not(lcm_python))]
fn python() -> &'static str {
    unreachable!("the tests needing the official lcm are ignored without it")
}

/// A small message and one of 200 000 bytes (fragmented: over 64 KiB), as (channel, payload).
fn messages(prefix: &str) -> Vec<(String, Vec<u8>)> {
    let schema = Schema::coopnav();
    let mut rng = Rng::new(0xc0ff_ee00);
    let fix = sample::record(&schema, schema.index("coopnav.cna_fix_t").unwrap(), &mut rng, 0);
    let data: Vec<u8> = (0..200_000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect();
    let frame = Record::new("coopnav.status_frame_t")
        .with("utime", Value::Int64(1_700_000_000_000_000))
        .with("src", Value::Int16(3))
        .with("receive_time", Value::Double(12.5))
        .with("n", Value::Int32(data.len() as i32))
        .with("data", Value::Bytes(data));
    vec![
        (format!("{prefix}_FIX"), encode(&schema, &fix).unwrap()),
        (format!("{prefix}_FRAME"), encode(&schema, &frame).unwrap()),
    ]
}

#[test]
#[cfg_attr(
    not(all(lcm_python, private_netns)),
    ignore = "needs the official lcm Python package (scripts/install-lcm.sh) and unshare -n"
)]
fn python_publishes_and_rust_receives_identical_bytes() {
    in_private_netns("python_publishes_and_rust_receives_identical_bytes", || {
        let sent = messages("PY");
        let mut lcm = Udpm::new(URL).unwrap();
        for (channel, _) in &sent {
            lcm.subscribe(channel).unwrap();
        }
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("pub.json");
        let items: Vec<_> = sent.iter().map(|(c, d)| json!({"channel": c, "data": hex(d)})).collect();
        std::fs::write(&input, serde_json::to_string(&items).unwrap()).unwrap();
        let mut publisher = Reaped(
            Command::new(python())
                .arg(interop_py())
                .args(["publish", URL])
                .arg(&input)
                .arg("20")
                .stdin(Stdio::null())
                .spawn()
                .expect("python publisher"),
        );
        let deadline = Instant::now() + Duration::from_secs(20);
        let mut got: Vec<Option<Vec<u8>>> = vec![None; sent.len()];
        while got.iter().any(Option::is_none) && Instant::now() < deadline {
            let Some(m) = lcm.recv_timeout(deadline.saturating_duration_since(Instant::now())).unwrap() else { break };
            let i = sent.iter().position(|(c, _)| *c == m.channel).expect("only subscribed channels");
            got[i].get_or_insert(m.data);
        }
        let _ = publisher.kill();
        let _ = publisher.wait();
        for ((channel, data), g) in sent.iter().zip(&got) {
            let g = g.as_ref().unwrap_or_else(|| panic!("nothing received on {channel}"));
            assert_eq!(g.len(), data.len(), "{channel}");
            assert!(g == data, "{channel}: bytes differ");
        }
        let schema = Schema::coopnav();
        let frame = decode(&schema, "coopnav.status_frame_t", got[1].as_ref().unwrap()).unwrap();
        assert_eq!(frame.get("n"), Some(&Value::Int32(200_000)));
    });
}

#[test]
#[cfg_attr(
    not(all(lcm_python, private_netns)),
    ignore = "needs the official lcm Python package (scripts/install-lcm.sh) and unshare -n"
)]
fn rust_publishes_and_python_receives_identical_bytes() {
    in_private_netns("rust_publishes_and_python_receives_identical_bytes", || {
        let sent = messages("RS");
        let dir = tempfile::tempdir().unwrap();
        let channels = dir.path().join("channels.json");
        let out = dir.path().join("got.json");
        let names: Vec<&String> = sent.iter().map(|(c, _)| c).collect();
        std::fs::write(&channels, serde_json::to_string(&names).unwrap()).unwrap();
        let mut subscriber = Reaped(
            Command::new(python())
                .arg(interop_py())
                .args(["subscribe", URL])
                .arg(&channels)
                .arg(&out)
                .arg("20")
                .stdin(Stdio::null())
                .stdout(Stdio::piped())
                .spawn()
                .expect("python subscriber"),
        );
        let stdout = subscriber.stdout.take().unwrap();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let ready = rx.recv_timeout(Duration::from_secs(20));
        if ready.as_deref() != Ok("ready") {
            let _ = subscriber.kill();
            let _ = subscriber.wait();
            panic!("the subscriber did not become ready: {ready:?}");
        }
        let mut lcm = Udpm::new(URL).unwrap();
        let deadline = Instant::now() + Duration::from_secs(20);
        let status = loop {
            if let Some(status) = subscriber.try_wait().unwrap() {
                break Some(status);
            }
            if Instant::now() >= deadline {
                let _ = subscriber.kill();
                let _ = subscriber.wait();
                break None;
            }
            for (channel, data) in &sent {
                lcm.publish(channel, data).unwrap();
            }
            std::thread::sleep(Duration::from_millis(100));
        };
        assert!(status.is_some_and(|s| s.success()), "the subscriber failed: {status:?}");
        let got: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        for (channel, data) in &sent {
            let g = unhex(got[channel].as_str().unwrap_or_else(|| panic!("nothing on {channel}")));
            assert!(g == *data, "{channel}: bytes differ ({} vs {})", g.len(), data.len());
        }
    });
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs unshare -n")]
fn rust_to_rust_over_loopback_with_many_fragments() {
    in_private_netns("rust_to_rust_over_loopback_with_many_fragments", || {
        // A larger kernel buffer, as lcm advises for big messages (capped by the kernel).
        let url = format!("{URL}&recv_buf_size=8388608");
        let mut rx = Udpm::new(&url).unwrap();
        rx.subscribe_regex("B.G|NONE").unwrap();
        let payload: Vec<u8> = (0..1_000_000u32).map(|i| (i % 251) as u8).collect();
        let (done_tx, done_rx) = mpsc::channel();
        let receiver = std::thread::spawn(move || {
            let deadline = Instant::now() + Duration::from_secs(10);
            let mut got = None;
            while got.is_none() && Instant::now() < deadline {
                got = rx.recv_timeout(deadline.saturating_duration_since(Instant::now())).unwrap();
            }
            let _ = done_tx.send(());
            got
        });
        let mut tx = Udpm::new(URL).unwrap();
        // Sixteen fragments in a burst may overflow a small socket buffer: send again until one
        // whole copy is through (at most 50 times).
        for _ in 0..50 {
            tx.publish("OTHER", b"not subscribed").unwrap();
            tx.publish("XBIGX", b"the pattern matches whole names only").unwrap();
            tx.publish("BIG", &payload).unwrap();
            if done_rx.recv_timeout(Duration::from_millis(200)).is_ok() {
                break;
            }
        }
        let m = receiver.join().unwrap().expect("a message");
        assert_eq!(m.channel, "BIG");
        assert!(m.data == payload);
        assert_eq!(m.seq % 3, 2, "the BIG messages have the sequence numbers 2, 5, 8, ...");
        // A datagram already queued is read even with a zero timeout; garbage is counted, dropped.
        let mut rx = Udpm::new(URL).unwrap();
        rx.subscribe("SMALL").unwrap();
        let raw = std::net::UdpSocket::bind("0.0.0.0:0").unwrap();
        raw.set_multicast_ttl_v4(0).unwrap();
        raw.send_to(b"LC02\0\0\0\0no NUL in reach", "239.255.76.67:7667").unwrap();
        tx.publish("SMALL", b"queued").unwrap();
        std::thread::sleep(Duration::from_millis(50));
        let m = rx.recv_timeout(Duration::ZERO).unwrap().expect("the queued message");
        assert_eq!(m.data, b"queued");
        assert_eq!(rx.bad_datagrams(), 1);
    });
}

#[test]
#[cfg_attr(
    not(all(lcm_logger, private_netns)),
    ignore = "needs the official lcm-logger (scripts/install-lcm.sh) and unshare -n"
)]
fn lcm_logger_records_what_rust_publishes() {
    #[cfg(lcm_logger)]
    let logger = env!("COOPNAV_LCM_LOGGER_FOUND");
    #[cfg(not(lcm_logger))]
    let logger = "lcm-logger";
    in_private_netns("lcm_logger_records_what_rust_publishes", || {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("logger.lcmlog");
        let mut child = Reaped(
            Command::new(logger)
                .arg(format!("--lcm-url={URL}"))
                .arg("-f")
                .arg(&path)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("lcm-logger"),
        );
        let big: Vec<u8> = (0..100_000u32).map(|i| (i % 253) as u8).collect();
        let payload = |i: usize| {
            let mut p = format!("message {i}").into_bytes();
            if i % 10 == 9 {
                p.extend_from_slice(&big);
            }
            p
        };
        let mut lcm = Udpm::new(URL).unwrap();
        // Warm-up messages until the logger has written one (it flushes every 100 ms), so it is
        // listening before the messages that count.
        let ready_by = Instant::now() + Duration::from_secs(20);
        while std::fs::metadata(&path).map_or(0, |m| m.len()) == 0 {
            assert!(Instant::now() < ready_by, "lcm-logger wrote nothing");
            lcm.publish("WARMUP", b"w").unwrap();
            std::thread::sleep(Duration::from_millis(50));
        }
        let count = 60;
        for i in 0..count {
            lcm.publish(if i % 2 == 0 { "EVEN" } else { "ODD" }, &payload(i)).unwrap();
            std::thread::sleep(Duration::from_millis(25));
        }
        std::thread::sleep(Duration::from_millis(300));
        run(Command::new("kill").args(["-INT", &child.id().to_string()]), Duration::from_secs(5), "kill -INT");
        let deadline = Instant::now() + Duration::from_secs(10);
        while child.try_wait().unwrap().is_none() {
            if Instant::now() >= deadline {
                let _ = child.kill();
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = child.wait();
        let events: Vec<_> =
            LogReader::new(std::fs::File::open(&path).unwrap()).collect::<Result<_, _>>().expect("a readable log");
        // After the warm-ups, every message in order: loopback at a small rate drops nothing.
        let warmups = events.iter().take_while(|e| e.channel == "WARMUP").count();
        assert!(warmups >= 1);
        assert_eq!(events.len() - warmups, count, "events after the warm-ups");
        for (k, e) in events.iter().enumerate() {
            assert_eq!(e.event_number, k as i64);
            if k > 0 {
                assert!(e.timestamp >= events[k - 1].timestamp);
            }
            if let Some(i) = k.checked_sub(warmups) {
                assert_eq!(e.channel, if i % 2 == 0 { "EVEN" } else { "ODD" });
                assert!(e.data == payload(i), "message {i}: data differ");
            }
        }
    });
}
