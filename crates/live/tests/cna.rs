//! The live CNA without a socket, against the engine: a mission's CNA inputs recorded from the
//! engine (its fix and clock at each decision, every status its modem received, in the engine's
//! order), fed as LCM payloads to `CnaPlanner`, give the engine policy's commands bit for bit,
//! decision by decision, and its planner's tally. The expected commands are the engine's own
//! policy's (built and stepped by coopnav-sim); the live planner decodes the payloads, rebuilds
//! its knowledge of the fleet from the status bytes and the schedule, and decides by itself.

use coopnav_lcm::messages::{CnaCommand as CommandMsg, Decision, Message, StatusFrame};
use coopnav_lcm::Schema;
use coopnav_live::world::{record, Recorded, WorldMessage};
use coopnav_live::{CnaChannels, CnaCounts, CnaPlanner, Outgoing};
use coopnav_sim::engine::Faults;
use coopnav_sim::observe::metrics;
use coopnav_sim::policy::{CnaCommand, PolicySpec};
use coopnav_sim::scenario::file::load;
use coopnav_sim::scenario::Scenario;
use std::path::Path;

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name);
    load(&path, Scenario::validate).unwrap()
}

/// Feeds the recorded messages to a fresh planner; returns what it published, in order.
fn replay(sc: &Scenario, policy: &str, rec: &Recorded) -> (CnaPlanner, Vec<Outgoing>) {
    let mut cna = CnaPlanner::new(sc, policy, 0).unwrap();
    let mut out = Vec::new();
    for m in &rec.messages {
        out.extend(cna.handle(&m.channel, &m.payload).unwrap());
    }
    (cna, out)
}

/// Every decision of the live planner equals the engine's: the same decision index, hold or
/// go-to, and the waypoint's coordinates bit for bit; its records carry the engine planner's
/// tally at the end.
fn decisions_equal_the_engines(file: &str, policy: &str) {
    let sc = scenario(file);
    let rec = record(&sc, policy).unwrap();
    // Recording is transparent: the run is the engine's own.
    let mut plain = PolicySpec::new(policy, &sc).unwrap().build(&sc).unwrap();
    let direct = metrics::run(&sc, &mut plain, sc.seed, &Faults::default(), &mut ());
    assert_eq!(serde_json::to_string(&rec.result).unwrap(), serde_json::to_string(&direct).unwrap());
    let (cna, out) = replay(&sc, policy, &rec);
    let schema = Schema::coopnav();
    let ch = CnaChannels::default();
    let commands: Vec<CommandMsg> = out
        .iter()
        .filter(|o| o.channel == ch.command)
        .map(|o| CommandMsg::decode(&schema, &o.payload).unwrap())
        .collect();
    let records: Vec<Decision> = out
        .iter()
        .filter(|o| o.channel == ch.decision)
        .map(|o| Decision::decode(&schema, &o.payload).unwrap())
        .collect();
    assert!(rec.commands.len() > 50, "{file}: {} decisions", rec.commands.len());
    assert_eq!(commands.len(), rec.commands.len(), "{file}: decisions taken");
    let mut planned = 0;
    for (c, (m, expected)) in commands.iter().zip(&rec.commands) {
        assert_eq!(c.seq as u64, *m, "{file}: decision index");
        match *expected {
            CnaCommand::GoTo(p) => {
                planned += 1;
                let got = [c.waypoint_x, c.waypoint_y, c.waypoint_depth].map(f64::to_bits);
                assert!(
                    c.has_waypoint && got == [p.x, p.y, p.z].map(f64::to_bits),
                    "{file} decision {m}: {c:?} vs {p:?}"
                );
            }
            CnaCommand::Hold => assert!(!c.has_waypoint, "{file} decision {m}: {c:?} vs hold"),
        }
    }
    assert!(planned > rec.commands.len() / 2, "{file}: {planned} go-to commands");
    let last = records.last().unwrap();
    let stats = rec.stats.clone().unwrap();
    assert_eq!(last.policy, rec.result.policy);
    let tally = (last.decisions, last.deadline_misses, last.failures, last.waiting, last.min_levels_searched);
    let expected = (
        stats.decisions as i64,
        stats.deadline_misses as i64,
        stats.failures as i64,
        stats.waiting as i64,
        stats.min_levels_searched as i32,
    );
    assert_eq!(tally, expected, "{file}: the planner's tally");
    assert_eq!(last.mean_levels_searched.to_bits(), stats.mean_levels_searched.to_bits());
    // Every status the modem received was read, none dropped.
    let counts = cna.counts();
    let statuses = rec.messages.iter().filter(|m| m.channel == ch.status).count() as u64;
    assert!(statuses > 50, "{file}: {statuses} statuses");
    assert_eq!((counts.statuses_applied, counts.malformed, counts.unscheduled), (statuses, 0, 0), "{counts:?}");
    let last_fix = rec.messages.iter().rposition(|m| m.channel == ch.fix).unwrap();
    let before = rec.messages[..last_fix].iter().filter(|m| m.channel == ch.status).count() as u64;
    assert_eq!(last.n_status as u64, before, "{file}: statuses before the last decision");
    assert_eq!(counts.missed_decisions, 0);
}

#[test]
fn the_live_planner_decides_as_the_engine_on_the_default_mission() {
    decisions_equal_the_engines("default.toml", "planner-estimator");
    decisions_equal_the_engines("default.toml", "planner");
}

#[test]
fn the_live_planner_decides_as_the_engine_for_an_auv_cna_on_a_tdma_schedule() {
    decisions_equal_the_engines("auv-cna-tdma.toml", "planner-estimator");
}

/// A planner that never hears a status (or hears them garbled) decides otherwise: the check
/// above is not met by any planner on the fix alone.
#[test]
fn without_the_statuses_the_decisions_differ() {
    let sc = scenario("default.toml");
    let rec = record(&sc, "planner-estimator").unwrap();
    let ch = CnaChannels::default();
    let mut garbled = rec.clone();
    for m in garbled.messages.iter_mut().filter(|m| m.channel == ch.status) {
        let n = m.payload.len();
        m.payload[n - 1] ^= 0x5a;
    }
    let (cna, out) = replay(&sc, "planner-estimator", &garbled);
    let schema = Schema::coopnav();
    let differ = out
        .iter()
        .filter(|o| o.channel == ch.command)
        .zip(&rec.commands)
        .filter(|(o, (_, expected))| {
            let c = CommandMsg::decode(&schema, &o.payload).unwrap();
            match *expected {
                CnaCommand::GoTo(p) => !c.has_waypoint || c.waypoint_x != p.x || c.waypoint_y != p.y,
                CnaCommand::Hold => c.has_waypoint,
            }
        })
        .count();
    assert!(differ > 10, "{differ} decisions differ");
    assert!(cna.counts().malformed + cna.counts().statuses_applied > 0);
}

/// The commands the planner published for `messages`, decoded, and its counts.
fn commands_for(sc: &Scenario, messages: &[WorldMessage]) -> (CnaCounts, Vec<CommandMsg>) {
    let mut cna = CnaPlanner::new(sc, "planner-estimator", 0).unwrap();
    let out: Vec<Outgoing> = messages.iter().flat_map(|m| cna.handle(&m.channel, &m.payload).unwrap()).collect();
    let schema = Schema::coopnav();
    let ch = CnaChannels::default();
    let commands =
        out.iter().filter(|o| o.channel == ch.command).map(|o| CommandMsg::decode(&schema, &o.payload).unwrap());
    (cna.counts().clone(), commands.collect())
}

/// Whether two runs published the same commands; a difference is reported by its first decision.
fn first_difference(a: &[CommandMsg], b: &[CommandMsg]) -> Option<String> {
    if a.len() != b.len() {
        return Some(format!("{} commands against {}", a.len(), b.len()));
    }
    a.iter().zip(b).position(|(x, y)| x != y).map(|i| format!("decision {i}: {:?} against {:?}", a[i], b[i]))
}

fn status(m: &WorldMessage) -> StatusFrame {
    StatusFrame::decode(&Schema::coopnav(), &m.payload).unwrap()
}

fn status_message(frame: &StatusFrame) -> WorldMessage {
    WorldMessage { channel: CnaChannels::default().status, payload: frame.encode(&Schema::coopnav()).unwrap() }
}

/// Duplicated statuses, statuses from outside the fleet, truncated messages on every channel and
/// clocks older than the newest are each counted and dropped: every command is the clean run's,
/// bit for bit, and every clean status is applied.
#[test]
fn duplicated_foreign_malformed_and_stale_inputs_are_counted_and_change_nothing() {
    let sc = scenario("default.toml");
    let rec = record(&sc, "planner-estimator").unwrap();
    let ch = CnaChannels::default();
    let (clean_counts, clean) = commands_for(&sc, &rec.messages);
    let mut faulty = Vec::new();
    let (mut duplicated, mut foreign, mut truncated, mut stale) = (0, 0, 0, 0);
    let mut last_clock: Option<WorldMessage> = None;
    for (i, m) in rec.messages.iter().enumerate() {
        faulty.push(m.clone());
        if m.channel == ch.status && i % 3 == 0 {
            faulty.push(m.clone());
            duplicated += 1;
        }
        if m.channel == ch.status && i % 7 == 1 {
            faulty.push(status_message(&StatusFrame { src: 9, ..status(m) }));
            foreign += 1;
        }
        if i % 11 == 2 {
            faulty
                .push(WorldMessage { channel: m.channel.clone(), payload: m.payload[..m.payload.len() / 2].to_vec() });
            truncated += 1;
        }
        if m.channel == ch.clock {
            if let Some(previous) = last_clock.replace(m.clone()) {
                if i % 5 == 0 {
                    faulty.push(previous);
                    stale += 1;
                }
            }
        }
    }
    assert!(
        duplicated > 20 && foreign > 5 && truncated > 20 && stale > 10,
        "{duplicated} {foreign} {truncated} {stale}"
    );
    let (counts, commands) = commands_for(&sc, &faulty);
    assert_eq!(first_difference(&commands, &clean), None, "every command is the clean run's");
    let got = (counts.duplicates, counts.wrong_source, counts.malformed, counts.stale_clock);
    assert_eq!(got, (duplicated, foreign, truncated, stale), "{counts:?}");
    assert_eq!((counts.statuses_applied, counts.decisions), (clean_counts.statuses_applied, clean_counts.decisions));
}

/// A status that arrives after a newer one from the same AUV (reordered on the bus, or delayed) is
/// counted as stale and does not replace the newer one's report or covariance: the commands are
/// the clean run's. Statuses reordered between AUVs change nothing either.
#[test]
fn a_reordered_status_is_counted_and_never_replaces_a_newer_one() {
    let sc = scenario("default.toml");
    let rec = record(&sc, "planner-estimator").unwrap();
    let ch = CnaChannels::default();
    let (_, clean) = commands_for(&sc, &rec.messages);
    // Each AUV's status delivered again after that AUV's next one (a late copy with its own
    // receive time, so not a duplicate), and each pair of statuses between two fixes swapped.
    let mut faulty = rec.messages.clone();
    let mut previous: std::collections::HashMap<i16, StatusFrame> = Default::default();
    let mut inserts = Vec::new();
    for (i, m) in faulty.iter().enumerate().filter(|(_, m)| m.channel == ch.status) {
        let frame = status(m);
        if let Some(older) = previous.insert(frame.src, frame) {
            if i % 4 == 0 {
                inserts.push((i + 1, StatusFrame { receive_time: older.receive_time + 0.25, ..older }));
            }
        }
    }
    let late = inserts.len() as u64;
    for (at, copy) in inserts.into_iter().rev() {
        faulty.insert(at, status_message(&copy));
    }
    let mut swapped = 0;
    for i in 0..faulty.len() - 1 {
        let both = faulty[i].channel == ch.status && faulty[i + 1].channel == ch.status;
        if both && status(&faulty[i]).src != status(&faulty[i + 1]).src {
            faulty.swap(i, i + 1);
            swapped += 1;
        }
    }
    assert!(late > 5 && swapped > 5, "{late} late, {swapped} swapped");
    let (counts, commands) = commands_for(&sc, &faulty);
    assert_eq!(counts.stale_status, late, "{counts:?}");
    assert_eq!(first_difference(&commands, &clean), None, "every command is the clean run's");
}

/// Statuses lost on the bus cost only their information: every decision is still taken, each
/// status that arrived is applied, and the decisions differ from the clean run's (the planner
/// used what it heard).
#[test]
fn a_dropped_status_costs_only_its_information() {
    let sc = scenario("default.toml");
    let rec = record(&sc, "planner-estimator").unwrap();
    let ch = CnaChannels::default();
    let (clean_counts, clean) = commands_for(&sc, &rec.messages);
    let mut kept = Vec::new();
    let mut dropped = 0;
    for (i, m) in rec.messages.iter().enumerate() {
        if m.channel == ch.status && i % 2 == 0 {
            dropped += 1;
        } else {
            kept.push(m.clone());
        }
    }
    let (counts, commands) = commands_for(&sc, &kept);
    assert_eq!(commands.len(), clean.len(), "every decision taken");
    assert_eq!(counts.statuses_applied, clean_counts.statuses_applied - dropped);
    assert_eq!(counts.malformed + counts.duplicates + counts.stale_status, 0, "{counts:?}");
    assert!(first_difference(&commands, &clean).is_some(), "the lost statuses changed the plan");
}
