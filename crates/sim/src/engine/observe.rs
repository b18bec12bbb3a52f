//! What the engine reports as it runs, and the one recorded time series. The engine calls an
//! [`Observer`] once per second of mission time and once per packet whose fate is known; the
//! caller keeps what it wants (`()` keeps nothing, [`Trace`] keeps everything).

use coopnav_core::Vec3;
use serde::Serialize;

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
    /// The planner's modelled error, m (empty before the model starts).
    pub modelled: Option<f64>,
    pub cna_x: f64,
    pub cna_y: f64,
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

/// A CNA decision: where it was (true position) and the point it now steers for (none: hold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    pub t: f64,
    pub from: Vec3,
    pub to: Option<Vec3>,
}

/// Hooks the engine calls; every one defaults to doing nothing.
pub trait Observer {
    /// Every CNA decision (every τ), with the leg it chose.
    fn on_decision(&mut self, _decision: &Decision) {}
    /// After the step ending at `t`, once per second: the CNA's true position and one row per AUV.
    fn on_sample(&mut self, _t: f64, _cna: Vec3, _rows: &[TraceRow]) {}
    /// Just before each `on_sample`, in a scenario with ships: ship i's true position at index i.
    fn on_ships(&mut self, _t: f64, _ships: &[Vec3]) {}
    /// A packet whose fate is known (at the end of its arrival).
    fn on_packet(&mut self, _event: &CommsEvent) {}
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
    /// CNA true track (t, x, y) every second.
    pub cna: Vec<(f64, f64, f64)>,
    pub decisions: Vec<Decision>,
}

impl Observer for Trace {
    fn on_decision(&mut self, decision: &Decision) {
        self.decisions.push(*decision);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.rows.extend_from_slice(rows);
        self.cna.push((t, cna.x, cna.y));
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.comms.push(*event);
    }
}
