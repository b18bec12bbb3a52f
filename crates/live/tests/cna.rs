//! The live CNA without a socket, against the engine: a mission's CNA inputs recorded from the
//! engine (its fix and clock at each decision, every status its modem received, in the engine's
//! order), fed as LCM payloads to `CnaPlanner`, give the engine policy's commands bit for bit,
//! decision by decision, and its planner's tally. The expected commands are the engine's own
//! policy's (built and stepped by coopnav-sim); the live planner decodes the payloads, rebuilds
//! its knowledge of the fleet from the status bytes and the schedule, and decides by itself.

use coopnav_lcm::messages::{CnaCommand as CommandMsg, Decision, Message};
use coopnav_lcm::Schema;
use coopnav_live::world::{record, Recorded};
use coopnav_live::{CnaChannels, CnaPlanner, Outgoing};
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
