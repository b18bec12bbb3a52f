//! `coopnav live cna` end to end over real UDP multicast, only inside a private network namespace
//! the test makes (`netns`: `unshare -n`, loopback only, TTL 0). A mission's CNA inputs are
//! recorded from the engine (coopnav-live's `world::record`: the fix and clock at each decision,
//! every status the CNA's modem received, in the engine's order); the test publishes them to the
//! child in that order, waiting after each clock for its command and decision record, and
//! compares the commands with the engine policy's own, bit for bit. Every wait is bounded; the
//! child is ended by its pid if it has not stopped. Ignored, with the reason, where `unshare`
//! cannot make a namespace.

mod netns;

use coopnav_lcm::messages::{Clock, CnaCommand as CommandMsg, Decision, Message};
use coopnav_lcm::{LogReader, Schema, Udpm};
use coopnav_live::world::{record, Recorded, WorldMessage};
use coopnav_live::CnaChannels;
use coopnav_sim::policy::CnaCommand;
use coopnav_sim::scenario::file::load;
use coopnav_sim::scenario::Scenario;
use netns::{in_private_netns, refused, Live};
use std::path::PathBuf;
use std::time::{Duration, Instant};

const URL: &str = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
const POLICY: &str = "planner-estimator";

fn scenario_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name)
}

fn recorded(name: &str) -> Recorded {
    let sc: Scenario = load(&scenario_path(name), Scenario::validate).unwrap();
    record(&sc, POLICY).unwrap()
}

/// `coopnav live cna FILE --policy POLICY --clock bus --url URL ARGS`, listening.
fn start_cna(file: &str, args: &[&str]) -> Live {
    let path = scenario_path(file);
    let base = ["live", "cna", path.to_str().unwrap(), "--policy", POLICY, "--clock", "bus", "--url", URL];
    Live::start(&[&base[..], args].concat())
}

/// The command and record the child published for decision `seq` (at most 20 s).
fn await_decision(bus: &mut Udpm, seq: i64) -> (CommandMsg, Decision) {
    let (schema, ch) = (Schema::coopnav(), CnaChannels::default());
    let deadline = Instant::now() + Duration::from_secs(20);
    let (mut command, mut decision) = (None, None);
    for _ in 0..10_000 {
        if let (Some(c), Some(d)) = (command, decision.clone()) {
            return (c, d);
        }
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(!left.is_zero(), "no decision {seq} within 20 s");
        let Some(m) = bus.recv_timeout(left.min(Duration::from_millis(200))).unwrap() else { continue };
        if m.channel == ch.command {
            command = Some(CommandMsg::decode(&schema, &m.data).unwrap()).filter(|c| c.seq == seq);
        } else if m.channel == ch.decision {
            decision = Some(Decision::decode(&schema, &m.data).unwrap()).filter(|d| d.seq == seq);
        }
    }
    panic!("no decision {seq} in 10 000 messages")
}

/// Publishes `messages` in order; after each clock, waits for that decision.
fn lockstep(messages: &[WorldMessage]) -> Vec<(CommandMsg, Decision)> {
    let (schema, ch) = (Schema::coopnav(), CnaChannels::default());
    let mut bus = Udpm::new(URL).unwrap();
    bus.subscribe(&ch.command).unwrap();
    bus.subscribe(&ch.decision).unwrap();
    let mut out = Vec::new();
    for m in messages {
        bus.publish(&m.channel, &m.payload).unwrap();
        if m.channel == ch.clock {
            let tick = Clock::decode(&schema, &m.payload).unwrap().tick;
            out.push(await_decision(&mut bus, tick));
        }
    }
    out
}

fn stop_clock() {
    let stop = Clock { running: false, ..Clock::default() }.encode(&Schema::coopnav()).unwrap();
    Udpm::new(URL).unwrap().publish(&CnaChannels::default().clock, &stop).unwrap();
}

fn same(c: &CommandMsg, expected: &CnaCommand) -> bool {
    match *expected {
        CnaCommand::GoTo(p) => {
            c.has_waypoint
                && [c.waypoint_x, c.waypoint_y, c.waypoint_depth].map(f64::to_bits) == [p.x, p.y, p.z].map(f64::to_bits)
        }
        CnaCommand::Hold => !c.has_waypoint,
    }
}

#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_cna_over_udp_multicast_decides_as_the_engine() {
    in_private_netns("live_cna_over_udp_multicast_decides_as_the_engine", || {
        let rec = recorded("default.toml");
        let dir = tempfile::tempdir().unwrap();
        let log = dir.path().join("cna.lcm");
        let live = start_cna("default.toml", &["--log", log.to_str().unwrap(), "--duration", "120"]);
        let got = lockstep(&rec.messages);
        stop_clock();
        let (summary, _cpu) = live.finish(Duration::from_secs(30));
        println!("summary: {summary}");
        assert_eq!(got.len(), rec.commands.len());
        for ((c, d), (m, expected)) in got.iter().zip(&rec.commands) {
            assert!(same(c, expected), "decision {m}: {c:?} against the engine's {expected:?}");
            assert_eq!(d.policy, POLICY);
            assert!(d.elapsed_s >= 0.0 && d.fix_utime == c.utime, "{d:?}");
        }
        let ch = CnaChannels::default();
        let statuses = rec.messages.iter().filter(|m| m.channel == ch.status).count() as u64;
        assert_eq!(summary["stopped_by"], "clock_stopped");
        assert_eq!(summary["decisions"], rec.commands.len() as u64);
        assert_eq!(summary["statuses_applied"], statuses);
        assert_eq!((summary["malformed"].as_u64(), summary["missed_decisions"].as_u64()), (Some(0), Some(0)));
        // The log holds everything received (every message and the stop) and published.
        let mut reader = LogReader::new(std::fs::File::open(&log).unwrap());
        let (mut events, mut commands) = (0u64, 0usize);
        while let Some(ev) = reader.read_event().unwrap() {
            events += 1;
            if ev.channel == ch.command {
                assert_eq!(CommandMsg::decode(&Schema::coopnav(), &ev.data).unwrap(), got[commands].0);
                commands += 1;
            }
            assert!(events <= 100_000);
        }
        assert_eq!(events, summary["log_events"].as_u64().unwrap());
        assert_eq!(events, rec.messages.len() as u64 + 1 + 2 * got.len() as u64);
    });
}

/// Killed mid-mission and started again, the planner resumes from the next messages: it decides
/// at every clock after the restart (from what it has heard since), and counts nothing as lost.
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_cna_killed_and_restarted_resumes_from_the_next_messages() {
    in_private_netns("live_cna_killed_and_restarted_resumes_from_the_next_messages", || {
        let rec = recorded("default.toml");
        let ch = CnaChannels::default();
        let clocks: Vec<usize> = (0..rec.messages.len()).filter(|&i| rec.messages[i].channel == ch.clock).collect();
        let cut = clocks[clocks.len() / 2] + 1;
        let first = start_cna("default.toml", &["--duration", "120"]);
        let before = lockstep(&rec.messages[..cut]);
        let pid = first.child.as_ref().unwrap().id() as libc::pid_t;
        // SAFETY: kill(2) on our own child's pid, which is not yet reaped.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGKILL) }, 0);
        drop(first);
        let second = start_cna("default.toml", &["--duration", "120"]);
        let after = lockstep(&rec.messages[cut..]);
        stop_clock();
        let (summary, _) = second.finish(Duration::from_secs(30));
        println!("summary: {summary}");
        assert_eq!(before.len() + after.len(), rec.commands.len());
        // Its first decision after the restart is the next one; it does not count the decisions
        // before its start as missed.
        assert_eq!(after[0].0.seq, before.last().unwrap().0.seq + 1);
        assert_eq!(summary["decisions"], after.len() as u64);
        assert_eq!(summary["missed_decisions"], 0);
        assert!(before.iter().zip(&rec.commands).all(|((c, _), (_, e))| same(c, e)));
        // The restarted planner knows only the statuses since its start (its tally restarts too).
        assert_eq!(after.last().unwrap().1.decisions, after.len() as i64);
    });
}

/// A bad scenario, policy or clock is refused, naming it, before any socket is opened (run in
/// the namespace all the same).
#[test]
#[cfg_attr(not(private_netns), ignore = "needs `unshare -n` (or -rn) to make a private network namespace")]
fn live_cna_refuses_a_bad_policy_clock_or_scenario_naming_it() {
    in_private_netns("live_cna_refuses_a_bad_policy_clock_or_scenario_naming_it", || {
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("bad.toml");
        let text = std::fs::read_to_string(scenario_path("default.toml")).unwrap();
        assert!(text.contains("tau = 30.0"));
        std::fs::write(&bad, text.replacen("tau = 30.0", "tau = -3.0", 1)).unwrap();
        let cases: [(&[&str], &str); 3] = [
            (&["--policy", "nope"], "unknown policy 'nope'"),
            (&["--clock", "sundial"], "invalid value 'sundial'"),
            (&[bad.to_str().unwrap()], "comms.tau"),
        ];
        for (args, expected) in cases {
            refused(&[&["live", "cna"][..], args].concat(), expected);
        }
    });
}
