//! CNA policies: what the communication-and-navigation aid does next, every τ seconds.
//!
//! The look-ahead planner is one policy; the baselines it must beat are others, each a named type
//! behind [`CnaPolicy`], so the closed-loop world runs any of them without knowing which.
//! A policy sees only what the CNA itself knows: its own pose and the survey AUVs' predicted
//! positions (from their status messages), never the AUVs' true positions.
//!
//! [`registry`] builds any of them by name from the scenario; [`planner`] is the look-ahead planner
//! as a policy.

mod baselines;
pub mod belief;
mod greedy;
pub mod planner;
pub mod registry;

pub use baselines::{Centroid, CentroidStandoff, FixedPattern, MidpointRelay, NoCna, TimedWaypoints, Trail};
pub use greedy::GreedyFisher;
pub use planner::{ErrorTracker, PlannerPolicy, PlannerStats};
pub use registry::{Policy, PolicyError, PolicySpec, POLICY_NAMES};

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
    /// The newest covariance each AUV's filter reported in its status message (indexed like
    /// `fleet`; shorter, or `None`, where none arrived).
    pub reported: &'a [Option<ReportedCov>],
    /// The CNA's own horizontal position variance per axis as it knows it, m² (GPS σ² for an
    /// ASC; for an AUV CNA its navigation's, grown since its last fix).
    pub cna_variance: f64,
}

/// A survey AUV's horizontal position covariance as its own filter reported it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReportedCov {
    /// When the AUV sent it, s.
    pub t: f64,
    /// [P_ee, P_en, P_nn], m² (after the status codec's quantisation).
    pub cov: [f64; 3],
}

impl PolicyContext<'_> {
    /// Predicted positions of every AUV heard from, at time `t`.
    pub fn predicted_all(&self, t: f64) -> Vec<Vec3> {
        (0..self.fleet.n_auvs()).filter_map(|k| self.fleet.position(k, t)).collect()
    }

    /// AUV `k`'s newest reported covariance, if any arrived.
    pub fn reported(&self, k: usize) -> Option<ReportedCov> {
        self.reported.get(k).copied().flatten()
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
    /// How its planning went, for a policy that plans (or relays a planner's tally).
    fn planner_stats(&self) -> Option<PlannerStats> {
        None
    }
}
