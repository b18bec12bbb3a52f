//! What the engine reports as it runs, and the one recorded time series. The engine calls an
//! [`Observer`] once per second of mission time, once per packet whose fate is known and at the
//! end of every phase of a step; the caller keeps what it wants (`()` keeps nothing, [`Trace`]
//! keeps the time series, [`PhaseClock`] the wall time of each phase).

use crate::models::schedule::Owner;
use coopnav_acomms::selector::Choice;
use coopnav_acomms::Rate;
use coopnav_core::Vec3;
use coopnav_nav::{Recoveries, UpdateOutcome};
use serde::Serialize;
use std::time::Instant;

/// One row of the time series (every second, per AUV).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceRow {
    pub t: f64,
    pub auv: usize,
    pub true_x: f64,
    pub true_y: f64,
    /// True depth, m.
    pub true_z: f64,
    pub est_x: f64,
    pub est_y: f64,
    pub error: f64,
    /// Filter's horizontal 1-σ (√(P_EE + P_NN)), m.
    pub est_sd: f64,
    /// Filter's horizontal covariance, m² (east, east–north, north): its error ellipse.
    pub p_ee: f64,
    pub p_en: f64,
    pub p_nn: f64,
    /// Normalised estimation error squared of the horizontal position (2 degrees of freedom).
    pub nees: f64,
    /// The planner's modelled error, m (empty before the model starts). The engine leaves it
    /// empty; a scored run (`observe::metrics`) fills it from Hudson's error model before any
    /// other observer sees the row.
    pub modelled: Option<f64>,
    pub cna_x: f64,
    pub cna_y: f64,
    /// The CNA's true depth, m (an AUV CNA dives and surfaces; a surface craft's transducer depth).
    pub cna_z: f64,
    pub distance: f64,
}

/// One packet on the comms timeline.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CommsEvent {
    /// Transmission time, s.
    pub t: f64,
    /// "down" = CNA broadcast to the AUV, "up" = the AUV's status to the CNA.
    pub direction: &'static str,
    pub auv: usize,
    pub received: bool,
    /// Why a packet was lost: "channel" (the success draw) or "collision or half-duplex" (empty
    /// when received).
    pub lost_to: &'static str,
}

/// One buoy at a sample: its transducer's true position and, per survey AUV (by index), where
/// that AUV's filter of the buoy (fed by its mini-packets) puts it.
#[derive(Debug, Clone, PartialEq)]
pub struct BuoySample {
    pub truth: Vec3,
    pub estimates: Vec<[f64; 2]>,
}

/// A ship at a sample: its reference point's true position and, per survey AUV (by index), where
/// that AUV's filter of the ship (fed by its mini-packets) puts it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShipSample {
    pub truth: Vec3,
    pub estimates: Vec<[f64; 2]>,
}

/// A survey AUV's filter at the start of the run: its position estimate (m), speed (m/s) and
/// math heading (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterStart {
    pub auv: usize,
    pub x: f64,
    pub y: f64,
    pub speed: f64,
    pub heading: f64,
}

/// What one survey AUV's filter step was given: the heading-rate reading it predicted with
/// (math sense, rad/s), the speed and compass readings it then took (m/s; math heading, rad),
/// and the AUV's true position at the step's end `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadReckoning {
    pub t: f64,
    pub auv: usize,
    pub yaw_rate: f64,
    pub speed: f64,
    pub heading: f64,
    pub truth: Vec3,
}

/// A usable range a survey AUV decoded: the sender, its transmit time, the travel time the
/// AUV measured (on its own clock) and the transmitter's position the packet carried (its fix at
/// launch; none for a mini-packet, which carries one component).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeHeard {
    pub t_tx: f64,
    pub auv: usize,
    pub from: Owner,
    pub travel_time: f64,
    pub fix: Option<Vec3>,
}

/// A ship's truth at the end of a step: its reference point and math heading (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShipPose {
    pub t: f64,
    pub ship: usize,
    pub pos: Vec3,
    pub heading: f64,
}

/// The GPS fix a buoy broadcast (whole or as a mini-packet component) at `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuoyFix {
    pub t: f64,
    pub buoy: usize,
    pub fix: Vec3,
}

/// A survey AUV's status slot: what its rate policy chose, from its estimated distance to the
/// CNA (none before it has heard the CNA).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatusChoice {
    pub t: f64,
    pub auv: usize,
    pub distance: Option<f64>,
    pub choice: Choice,
}

/// The CNA's broadcast slot, when its broadcast has a rate policy: the distance to the farthest
/// survey AUV it has a forecast of (none before it has one), and the policy's choice.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CnaChoice {
    pub t: f64,
    pub distance: Option<f64>,
    pub choice: Choice,
}

/// A survey AUV's status as sent: its rate and the tracking header in its frame 0 (Nams's frame 0;
/// no header in a node report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatusSent {
    pub t: f64,
    pub auv: usize,
    pub rate: Rate,
    pub header_entries: usize,
    pub header_bits: usize,
}

/// A survey AUV's status arriving at another survey AUV (`comms.status_to = "cna_and_auvs"`): how
/// many of its frames arrived (after collisions and half-duplex), and the frame-0 bytes spent on
/// header and status when frame 0 was decoded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatusFrames {
    /// Transmission time, s.
    pub t: f64,
    pub from: usize,
    pub to: usize,
    pub rate: Rate,
    pub frames_received: u32,
    pub frames_sent: u32,
    pub frame_bytes: usize,
    pub frame0_bytes: Option<usize>,
}

/// At a survey AUV's status slot (Nams's frame 0): where its shadow estimate of another survey AUV
/// is, against that vehicle's truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ShadowSample {
    pub t: f64,
    pub auv: usize,
    pub peer: usize,
    /// Horizontal distance from the estimate to the truth, m.
    pub error: f64,
}

/// A CNA decision: where it was (true position) and the point it now steers for (none: hold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    pub t: f64,
    pub from: Vec3,
    pub to: Option<Vec3>,
}

/// The CNA's position fix at a decision (before its policy decides), whether its policy
/// transmits, and where its forecast puts each survey AUV then (by index; None: no forecast;
/// empty when the policy does not transmit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CnaFix<'a> {
    pub t: f64,
    pub fix: Vec3,
    pub transmits: bool,
    pub forecast: &'a [Option<Vec3>],
}

/// A survey AUV's filter offered a range (at the end of its arrival): applied, gated or unusable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeUpdate {
    pub t: f64,
    pub auv: usize,
    pub outcome: UpdateOutcome,
    /// The range the filter was given less the one the true travel time gives at the same sound
    /// speed, m: what the channel's range error and the clocks added (positive: long).
    pub error_m: f64,
    /// The update left the filter's NIS bounds and the filter recovered (inflated its position
    /// and relinearised).
    pub recovered: bool,
}

/// A packet's fate on one survey AUV's link (at the end of its arrival): a broadcast from the CNA,
/// a buoy or a ship to AUV `auv`, or AUV `auv`'s status to the CNA (`from` is then the AUV). `rate`
/// is the packet's rate index; `received`: its content was used (for a status, the CNA could read
/// it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkArrival {
    pub auv: usize,
    pub from: Owner,
    pub rate: u8,
    pub decoded: bool,
    pub survived: bool,
    pub received: bool,
}

/// The end of a run: every survey AUV's filter recoveries (by index) and whether every filter
/// stayed finite at every sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunEnd<'a> {
    pub recoveries: &'a [Recoveries],
    pub finite: bool,
}

/// A survey AUV's status the CNA's modem received (its frame 0 decoded and not lost to a
/// collision): the status codec's bytes as they arrived, before the CNA reads them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CnaStatusHeard<'a> {
    /// Transmission time and the end of its arrival at the CNA, s.
    pub t_tx: f64,
    pub t_rx: f64,
    pub auv: usize,
    pub bytes: &'a [u8],
}

/// Hooks the engine calls; every one defaults to doing nothing.
pub trait Observer {
    /// Every CNA decision (every τ), with the leg it chose.
    fn on_decision(&mut self, _decision: &Decision) {}
    /// After the step ending at `t`, once per second: the CNA's true position and one row per AUV.
    fn on_sample(&mut self, _t: f64, _cna: Vec3, _rows: &[TraceRow]) {}
    /// Just before each `on_sample`, in a scenario with ships: ship i's true position at index i.
    fn on_ships(&mut self, _t: f64, _ships: &[Vec3]) {}
    /// Just before each `on_sample`, in a scenario with buoys: buoy i's truth and what every
    /// survey AUV's filter of it holds, at index i.
    fn on_buoys(&mut self, _t: f64, _buoys: &[BuoySample]) {}
    /// Just before each `on_sample`, in a scenario with ships: ship i's truth and what every survey
    /// AUV's filter of it holds, at index i.
    fn on_ship_samples(&mut self, _t: f64, _ships: &[ShipSample]) {}
    /// Every survey AUV's filter as the run starts (after the set-up).
    fn on_filter_start(&mut self, _start: &FilterStart) {}
    /// Every survey AUV's every filter step (the dead-reckoning stream a field log holds).
    fn on_dead_reckoning(&mut self, _dr: &DeadReckoning) {}
    /// Every ship at the start of the run and at the end of every truth step.
    fn on_ship_pose(&mut self, _pose: &ShipPose) {}
    /// Every buoy GPS fix broadcast, at its transmit time.
    fn on_buoy_fix(&mut self, _fix: &BuoyFix) {}
    /// A survey AUV decoded a packet with a usable range (before its filter applies it).
    fn on_range(&mut self, _range: &RangeHeard) {}
    /// Every survey AUV's status slot, with its rate policy's choice.
    fn on_status_choice(&mut self, _choice: &StatusChoice) {}
    /// The CNA's broadcast slot, with its rate policy's choice (only when it has one).
    fn on_cna_choice(&mut self, _choice: &CnaChoice) {}
    /// A survey AUV's status leaving, with the header its frame 0 carries.
    fn on_status_sent(&mut self, _sent: &StatusSent) {}
    /// A survey AUV's status arriving at another survey AUV, frames counted.
    fn on_status_frames(&mut self, _frames: &StatusFrames) {}
    /// A survey AUV's shadow estimate of another, at its status slot.
    fn on_shadow(&mut self, _sample: &ShadowSample) {}
    /// A status the CNA's modem received, at the end of its arrival (before the CNA reads it).
    fn on_cna_status(&mut self, _status: &CnaStatusHeard) {}
    /// A packet whose fate is known (at the end of its arrival).
    fn on_packet(&mut self, _event: &CommsEvent) {}
    /// The CNA's fix at every decision, before its policy decides.
    fn on_cna_fix(&mut self, _fix: &CnaFix) {}
    /// Every range a survey AUV's filter was offered, with what the filter did with it.
    fn on_range_update(&mut self, _update: &RangeUpdate) {}
    /// Every packet on a survey AUV's link whose fate is known (beside [`Observer::on_packet`],
    /// with its rate and whether its content was used).
    fn on_link(&mut self, _arrival: &LinkArrival) {}
    /// Once, when the run ends ([`super::Mission::finish`]).
    fn on_end(&mut self, _end: &RunEnd) {}
    /// A phase of the run ended: the set-up once, then each phase of every step, in order.
    fn on_phase_end(&mut self, _phase: Phase) {}
    /// Asked before every truth step: true ends the run there (a caller's cancellation, e.g.
    /// Ctrl-C in the Python bindings); the result then covers only the steps run.
    fn stop(&self) -> bool {
        false
    }
}

impl Observer for () {}

/// Recorded time series.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    pub rows: Vec<TraceRow>,
    pub comms: Vec<CommsEvent>,
    /// CNA true track (t, position) every second; an AUV CNA's depth included.
    pub cna: Vec<(f64, Vec3)>,
    pub decisions: Vec<Decision>,
    /// Every range a survey AUV's filter was offered, in time order.
    pub ranges: Vec<RangeUpdate>,
}

impl Observer for Trace {
    fn on_decision(&mut self, decision: &Decision) {
        self.decisions.push(*decision);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.rows.extend_from_slice(rows);
        self.cna.push((t, cna));
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.comms.push(*event);
    }
    fn on_range_update(&mut self, update: &RangeUpdate) {
        self.ranges.push(*update);
    }
}

/// The parts of a run, in the order the engine ends them (the phases of a step: see
/// `engine::phases`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Building the run: vehicles, schedule, the transmission-loss provider.
    Setup,
    Decide,
    Advance,
    Transmit,
    Deliver,
    Sense,
    Observe,
}

/// Wall-clock time per part of a run (not part of the deterministic results).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    /// Building the run (vehicles, schedule, transmission-loss provider).
    pub setup_s: f64,
    /// CNA decisions, including the planner.
    pub decide_s: f64,
    /// Truth kinematics of every vehicle.
    pub advance_s: f64,
    /// Slots due: encoding, channel draws, travel times.
    pub transmit_s: f64,
    /// Packets' fates and the range updates they carry.
    pub deliver_s: f64,
    /// Filter predictions and sensor updates.
    pub sense_s: f64,
    /// Metrics and the observer.
    pub observe_s: f64,
}

/// Times every part of a run (the benchmark's observer). Reading the clock at each of a step's
/// six phase ends costs about as much as a phase, so only a run that asks for it pays it.
#[derive(Debug, Clone)]
pub struct PhaseClock {
    last: Instant,
    pub timing: Timing,
}

impl PhaseClock {
    /// A clock started now: start it just before the run.
    pub fn start() -> Self {
        PhaseClock { last: Instant::now(), timing: Timing::default() }
    }
}

impl Observer for PhaseClock {
    fn on_phase_end(&mut self, phase: Phase) {
        let now = Instant::now();
        let elapsed = (now - self.last).as_secs_f64();
        self.last = now;
        let t = &mut self.timing;
        let slot = match phase {
            Phase::Setup => &mut t.setup_s,
            Phase::Decide => &mut t.decide_s,
            Phase::Advance => &mut t.advance_s,
            Phase::Transmit => &mut t.transmit_s,
            Phase::Deliver => &mut t.deliver_s,
            Phase::Sense => &mut t.sense_s,
            Phase::Observe => &mut t.observe_s,
        };
        *slot += elapsed;
    }
}
