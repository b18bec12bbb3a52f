//! `coopnav live auv` end to end over real UDP multicast, only inside a private network namespace
//! the test makes: it re-runs itself under `unshare -n` (found by build.rs), brings up the
//! namespace's loopback, routes multicast to it, checks loopback is the only interface, and uses
//! TTL 0, so no datagram can leave. There it starts the built binary as a child, publishes a
//! synthetic mission's message stream at a warped rate with coopnav-lcm's publisher, receives the
//! estimates, compares them with the in-process navigator (coopnav-live's library, which
//! crates/live/tests/navigator.rs checks bit for bit against post-processing's forward filter)
//! over the same stream, and ends the child by its pid if it is still running. Every loop is
//! bounded in count and time. Ignored, with the reason, where `unshare` cannot make a namespace.

mod netns;

use coopnav_lcm::messages::{AuvEstimate, Message};
use coopnav_lcm::{LogReader, Schema, Udpm};
use coopnav_live::synthetic::{stream, StreamMessage};
use coopnav_live::{AuvNavigator, LiveConfig};
use coopnav_nav::synthetic::SyntheticSpec;
use netns::{in_private_netns, refused, Live};
use std::time::{Duration, Instant};

const URL: &str = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
const AUV: i16 = 2;

impl Live {
    /// `coopnav live auv --auv AUV --url URL ARGS`, listening.
    fn auv(args: &[&str]) -> Live {
        let auv = AUV.to_string();
        Live::start(&[&["live", "auv", "--auv", &auv, "--url", URL][..], args].concat())
    }
}

/// Publishes the stream at `warp` × real time; a receiving thread collects the estimates until
/// `idle` without one (bounded by `max` messages and `limit` in all).
fn publish_and_receive(messages: &[StreamMessage], warp: f64, idle: Duration, limit: Duration) -> Vec<Vec<u8>> {
    let estimate_channel = format!("COOPNAV_AUV{AUV}_ESTIMATE");
    let mut rx = Udpm::new(URL).expect("receiver");
    rx.subscribe(&estimate_channel).expect("subscribe");
    let max = messages.len() + 10;
    let receiver = std::thread::spawn(move || {
        let start = Instant::now();
        let mut got = Vec::new();
        let mut last = Instant::now();
        while got.len() < max && start.elapsed() < limit {
            match rx.recv_timeout(Duration::from_millis(200)).expect("recv") {
                Some(m) => {
                    last = Instant::now();
                    got.push(m.data);
                }
                None if !got.is_empty() && last.elapsed() >= idle => break,
                None => {}
            }
        }
        got
    });
    let mut tx = Udpm::new(URL).expect("publisher");
    let t0 = messages.first().map_or(0.0, |m| m.t);
    let start = Instant::now();
    for m in messages {
        let due = Duration::from_secs_f64(((m.t - t0) / warp).max(0.0));
        if let Some(wait) = due.checked_sub(start.elapsed()) {
            std::thread::sleep(wait);
        }
        tx.publish(&m.channel, &m.payload).expect("publish");
    }
    receiver.join().expect("receiver thread")
}

fn in_process(messages: &[StreamMessage]) -> Vec<Vec<u8>> {
    let mut nav = AuvNavigator::new(AUV, LiveConfig::default()).unwrap();
    let mut out = Vec::new();
    for m in messages {
        out.extend(nav.handle(&m.channel, &m.payload).unwrap().into_iter().map(|p| p.payload));
    }
    out.extend(nav.flush().unwrap().into_iter().map(|p| p.payload));
    out
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_auv_over_udp_multicast_publishes_the_library_navigators_estimates() {
    in_private_netns("live_auv_over_udp_multicast_publishes_the_library_navigators_estimates", || {
        let spec = SyntheticSpec { duration_s: 300.0, ..SyntheticSpec::default() };
        let messages = stream(&spec, AUV).messages;
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("live.lcm");
        let live = Live::auv(&["--until-idle", "3", "--log", log.to_str().unwrap()]);
        // 300 s of mission in 6 s.
        let got = publish_and_receive(&messages, 50.0, Duration::from_secs(5), Duration::from_secs(60));
        let (summary, cpu) = live.finish(Duration::from_secs(30));
        println!("summary: {summary}");
        let expected = in_process(&messages);
        let schema = Schema::coopnav();
        assert_eq!(got.len(), expected.len(), "estimates received vs the library's");
        for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
            if g != e {
                let (g, e) = (AuvEstimate::decode(&schema, g), AuvEstimate::decode(&schema, e));
                panic!("estimate {i}: received {g:?}, library {e:?}");
            }
        }
        let sensors = messages.iter().filter(|m| m.channel.ends_with("_SENSORS")).count() as u64;
        let ranges = messages.len() as u64 - sensors;
        assert_eq!(summary["messages"][format!("COOPNAV_AUV{AUV}_SENSORS")], sensors);
        assert_eq!(summary["messages"][format!("COOPNAV_AUV{AUV}_RANGE")], ranges);
        assert_eq!(summary["sensors_applied"], sensors);
        assert_eq!(summary["estimates_published"], expected.len() as u64);
        assert_eq!((summary["malformed"].as_u64(), summary["duplicates"].as_u64()), (Some(0), Some(0)));
        assert_eq!(summary["stopped_by"], "idle");
        assert!(cpu > 0.0 && cpu < 30.0, "cpu {cpu}");
        // The log holds everything received and published, in lcm-logger's format.
        let mut reader = LogReader::new(std::fs::File::open(&log).unwrap());
        let mut events = 0u64;
        let mut published = 0usize;
        while let Some(ev) = reader.read_event().unwrap() {
            events += 1;
            if ev.channel.ends_with("_ESTIMATE") {
                assert_eq!(ev.data, expected[published]);
                published += 1;
            }
            assert!(events <= 100_000);
        }
        assert_eq!(events, summary["log_events"].as_u64().unwrap());
        assert_eq!(events, messages.len() as u64 + expected.len() as u64);
    });
}

/// The measured figure: CPU of `live auv` over a one-hour mission at 10 Hz (36 000 sensors
/// messages, 239 ranges, 36 239 estimates), streamed 60 × faster than real time: the kernel's
/// account of the child's user + system time (wait4), which the process's own figure in its
/// summary (getrusage at exit) matches. The target is ≤ 5 % of a core in real time, i.e. ≤ 180 s over the hour.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_auv_cpu_over_a_one_hour_mission() {
    in_private_netns("live_auv_cpu_over_a_one_hour_mission", || {
        let spec = SyntheticSpec { duration_s: 3600.0, ..SyntheticSpec::default() };
        let messages = stream(&spec, AUV).messages;
        let live = Live::auv(&["--until-idle", "3"]);
        let got = publish_and_receive(&messages, 60.0, Duration::from_secs(5), Duration::from_secs(150));
        let (summary, cpu) = live.finish(Duration::from_secs(30));
        println!("summary: {summary}");
        let wall = summary["wall_s"].as_f64().unwrap();
        println!(
            "live auv over a 3600 s mission ({} messages in, {} estimates out): {cpu:.3} s CPU \
             ({:.4} % of a core over the mission's hour; {:.1} % while streamed at 60x over {wall:.1} s)",
            messages.len(),
            got.len(),
            100.0 * cpu / 3600.0,
            100.0 * cpu / wall
        );
        assert_eq!(summary["estimates_published"].as_u64().unwrap() as usize, got.len(), "every estimate arrived");
        assert!(cpu / 3600.0 <= 0.05, "{cpu} s CPU over a 3600 s mission is over 5 % of a core");
    });
}

/// SIGTERM and SIGINT stop it cleanly: the buffered messages are applied, the summary printed, the
/// exit status 0.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_auv_stops_cleanly_on_sigterm_and_sigint() {
    in_private_netns("live_auv_stops_cleanly_on_sigterm_and_sigint", || {
        let spec = SyntheticSpec { duration_s: 20.0, ..SyntheticSpec::default() };
        let messages = stream(&spec, AUV).messages;
        for signal in [libc::SIGTERM, libc::SIGINT] {
            // --duration only as a bound: the signal comes first.
            let live = Live::auv(&["--duration", "60"]);
            let got = publish_and_receive(&messages, 20.0, Duration::from_secs(1), Duration::from_secs(20));
            let pid = live.child.as_ref().expect("running").id() as libc::pid_t;
            // SAFETY: kill(2) on our own child's pid, which is not yet reaped.
            assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
            let (summary, _) = live.finish(Duration::from_secs(10));
            assert_eq!(summary["stopped_by"], "signal", "{summary}");
            assert_eq!(summary["sensors_applied"], 200, "{summary}");
            // Those still in the reorder buffer at the signal were applied and published at exit.
            let published = summary["estimates_published"].as_u64().unwrap() as usize;
            assert_eq!(published, in_process(&messages).len());
            assert!(
                got.len() < published,
                "the reorder window's estimates come only at exit: {} of {published} before",
                got.len()
            );
        }
    });
}

/// A bad config or argument is refused, naming it, before any socket is opened (run in the
/// namespace all the same, so a mistake here cannot open one on the machine's network).
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_auv_refuses_a_bad_config_or_argument_naming_it() {
    in_private_netns("live_auv_refuses_a_bad_config_or_argument_naming_it", || {
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("bad.toml");
        std::fs::write(&bad, "reorder_window_s = 1e9\n").unwrap();
        let cases: [(&[&str], &str); 3] = [
            (&[bad.to_str().unwrap()], "reorder_window_s = 1000000000"),
            (&["--duration", "0"], "--duration 0: give a positive number of seconds"),
            (&["--url", "udpm://10.0.0.1:7667"], "not a multicast group"),
        ];
        for (args, expected) in cases {
            refused(&[&["live", "auv", "--auv", "1"][..], args].concat(), expected);
        }
    });
}
