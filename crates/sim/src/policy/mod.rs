//! CNA policies: what the communication-and-navigation aid does next, every τ seconds.
//!
//! The look-ahead planner is one policy; the baselines it must beat are others, each a named type
//! behind [`CnaPolicy`], so the closed-loop world runs any of them without knowing which.
//! A policy sees only what the CNA itself knows: its own pose and the survey AUVs' predicted
//! positions (from their status messages), never the AUVs' true positions.

mod baselines;

pub use baselines::{Centroid, FixedPattern, MidpointRelay, NoCna, Rect, TimedWaypoints, Trail};

use coopnav_core::Vec3;
use coopnav_plan::{AuvForecast, CnaPose};

/// Everything a policy may look at when it decides.
pub struct PolicyContext<'a> {
    /// Now, s.
    pub t: f64,
    /// The decision period τ, s: the command holds until t + τ.
    pub tau: f64,
    /// The CNA's pose as it knows it.
    pub cna: CnaPose,
    /// The CNA's transit speed, m/s.
    pub speed: f64,
    /// The survey AUVs' predicted positions (from their status messages).
    pub fleet: &'a dyn AuvForecast,
}

impl PolicyContext<'_> {
    /// Predicted positions of every AUV heard from, at time `t`.
    pub fn predicted_all(&self, t: f64) -> Vec<Vec3> {
        (0..self.fleet.n_auvs()).filter_map(|k| self.fleet.position(k, t)).collect()
    }
}

/// Where the CNA should head for the next τ seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CnaCommand {
    /// Drive towards this point at transit speed and hold station on arrival.
    GoTo(Vec3),
    /// Hold the current position (no target yet, or nothing to do).
    Hold,
}

/// A CNA behaviour.
pub trait CnaPolicy: Send {
    /// A short stable name, used on the command line and in reports.
    fn name(&self) -> &'static str;
    /// Whether the CNA sends navigation pings at all (false only for the no-CNA baseline).
    fn transmits(&self) -> bool {
        true
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand;
}
