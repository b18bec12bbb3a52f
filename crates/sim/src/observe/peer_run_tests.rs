//! Nams's link on the engine (`scenarios/nams-1.toml`): statuses delivered AUV to AUV, frames
//! counted at the peer, both vehicles' selectors adapting on each other's tracker headers, the
//! shadow estimates, and the per-AUV lawnmowers.

use crate::engine::*;
use crate::models::peer::{EstimatorMode, StatusFormat, StatusTo};
use crate::observe::metrics::run;
use crate::policy::PolicySpec;
use crate::scenario::world::Scenario;
use coopnav_acomms::selector::Choice;
use coopnav_acomms::Rate;
use coopnav_core::Vec3;
use std::path::Path;

const NAMS_1: &str = include_str!("../../../../scenarios/nams-1.toml");

fn nams_1(duration_s: f64) -> Scenario {
    let mut sc = Scenario::parse(NAMS_1, Path::new("nams-1.toml")).unwrap();
    sc.duration_s = duration_s;
    sc
}

#[derive(Default)]
struct Link {
    choices: Vec<StatusChoice>,
    frames: Vec<StatusFrames>,
    shadows: Vec<ShadowSample>,
    rows: Vec<TraceRow>,
}

impl Observer for Link {
    fn on_status_choice(&mut self, choice: &StatusChoice) {
        self.choices.push(*choice);
    }
    fn on_status_frames(&mut self, frames: &StatusFrames) {
        self.frames.push(*frames);
    }
    fn on_shadow(&mut self, sample: &ShadowSample) {
        self.shadows.push(*sample);
    }
    fn on_sample(&mut self, _t: f64, _cna: Vec3, rows: &[TraceRow]) {
        self.rows.extend_from_slice(rows);
    }
}

fn observed(sc: &Scenario, seed: u64) -> Link {
    let mut p = PolicySpec::new("none", sc).unwrap().build(sc).unwrap();
    let mut link = Link::default();
    run(sc, &mut p, seed, &Faults::default(), &mut link);
    link
}

/// Share of survey AUV `auv`'s last third of status slots sent at `rate`.
fn late_share(link: &Link, auv: usize, rate: Rate) -> f64 {
    let c: Vec<Choice> = link.choices.iter().filter(|c| c.auv == auv).map(|c| c.choice).collect();
    let late = &c[2 * c.len() / 3..];
    late.iter().filter(|c| **c == Choice::Transmit(rate)).count() as f64 / late.len().max(1) as f64
}

/// Addressed to the other vehicle, every status arrives there with its own channel draw: some
/// whole, some with only part of their frames, some not at all; addressed to the CNA only, none
/// is delivered to a survey AUV.
#[test]
fn a_status_reaches_the_other_auv_only_when_addressed_to_it() {
    let sc = nams_1(1200.0);
    let link = observed(&sc, 2);
    for (from, to) in [(0, 1), (1, 0)] {
        let at: Vec<&StatusFrames> = link.frames.iter().filter(|f| f.from == from && f.to == to).collect();
        assert_eq!(at.len(), 60, "one per own slot of 20 s");
        let whole = at.iter().filter(|f| f.frames_received == f.frames_sent).count();
        let partial = at.iter().filter(|f| f.frames_received > 0 && f.frames_received < f.frames_sent).count();
        assert!(
            whole > 10 && partial > 0 && whole + partial < 60,
            "auv{from} -> auv{to}: {whole} whole, {partial} partial"
        );
        // Frame 0's bytes are known exactly when frame 0 (bit 0) arrived; they fit the frame.
        assert!(at.iter().all(|f| f.frame0_bytes.is_none_or(|b| b > 0 && b <= f.frame_bytes)));
    }
    let mut to_cna = sc.clone();
    to_cna.comms.status_to = StatusTo::Cna;
    assert!(observed(&to_cna, 2).frames.is_empty());
}

/// Nams's scenario 1 under the analytic TL: rate 4 succeeds well above its target everywhere in
/// the square, so each vehicle's selector, told so by the other's tracker headers, grows its
/// rate-4 bin (400 m at first) until it covers the square. Without the headers (statuses to the
/// CNA only) nothing is ever resolved and no bin moves.
#[test]
fn both_vehicles_adapt_on_each_others_tracker_headers() {
    let sc = nams_1(4000.0);
    let link = observed(&sc, 1);
    let mut deaf = sc.clone();
    deaf.comms.status_to = StatusTo::Cna;
    let alone = observed(&deaf, 1);
    for auv in 0..2 {
        let (adapted, unheard) = (late_share(&link, auv, Rate::R4), late_share(&alone, auv, Rate::R4));
        assert!(adapted > 0.7 && unheard < 0.1, "auv{auv}: rate 4 in {adapted:.2} / {unheard:.2} of the last third");
    }
}

/// The shadow of the other vehicle: pre-planned, it flies the known plan from the start and each
/// status resets it (its error stays within the vehicles' dead-reckoning drift); dynamic, nothing
/// is known until the first status.
#[test]
fn each_vehicle_shadows_the_other() {
    let sc = nams_1(2000.0);
    let link = observed(&sc, 3);
    let first = |l: &Link, auv| l.shadows.iter().find(|s| s.auv == auv).map(|s| (s.t, s.peer, s.error));
    assert_eq!(first(&link, 0).map(|f| (f.0, f.1)), Some((0.0, 1)));
    assert!(first(&link, 0).unwrap().2 < 5.0, "the plan's start: {:?}", first(&link, 0));
    let mean = link.shadows.iter().map(|s| s.error).sum::<f64>() / link.shadows.len() as f64;
    assert!(mean < 40.0, "{mean}");
    let mut dynamic = sc.clone();
    dynamic.comms.status_format = StatusFormat::NamsFrame0 { estimator: EstimatorMode::Dynamic };
    let d = observed(&dynamic, 3);
    let heard_at = d.frames.iter().find(|f| f.to == 0 && f.frame0_bytes.is_some()).unwrap().t;
    assert!(d.shadows.iter().filter(|s| s.auv == 0).all(|s| s.t > heard_at), "no estimate before the first status");
    assert!(!d.shadows.is_empty());
}

/// `[[fleet.lawnmowers]]`: auv0 starts at (0, 0) running east, auv1 at the opposite corner
/// running west; a list that does not give one per AUV is refused, naming the field.
#[test]
fn each_auv_flies_its_own_lawnmower() {
    let link = observed(&nams_1(100.0), 1);
    let at = |auv: usize, t: f64| link.rows.iter().find(|r| r.auv == auv && (r.t - t).abs() < 0.5).unwrap();
    assert!(at(0, 1.0).true_x.hypot(at(0, 1.0).true_y) < 5.0 && at(0, 100.0).true_x > 100.0);
    let (a, b) = (at(1, 1.0), at(1, 100.0));
    assert!((a.true_x - 500.0).hypot(a.true_y - 500.0) < 5.0 && b.true_x < 400.0 && (b.true_y - 500.0).abs() < 10.0);
    let one =
        NAMS_1.replace("    { origin = [500.0, 500.0], lane_heading_compass_deg = 270.0, turn = \"left\" },\n", "");
    let e = Scenario::parse(&one, Path::new("one.toml")).unwrap_err().to_string();
    assert!(e.contains("fleet.lawnmowers = 1 entries: allowed none, or one per survey AUV"), "{e}");
}
