//! A run as the MOOS tools see it: named vehicle tracks (truth, estimate, CNA), the acoustic
//! pulses between vehicles and the CNA's planned legs. Simulators fill one in from their own
//! records; [`crate::export`] writes it as an alog. Positions are in the local frame (x east,
//! y north, depth positive down, metres), times in seconds from the start of the run.

use coopnav_core::LocalFrame;

/// The Unix time a simulated run's log counts from (2000-01-01T00:00:00Z): simulated runs have no
/// wall clock, and a fixed start keeps every export of one run byte-identical.
pub const SIMULATED_LOG_START: f64 = 946_684_800.0;

/// What a track shows; written as the NODE_REPORT `GROUP`, so viewers can tell them apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Where a survey vehicle really was.
    Truth,
    /// Where its navigation filter believed it was (`NAV_SD` carries the filter's 1σ).
    Estimate,
    /// The communication and navigation aid.
    Cna,
    /// A fixed or drifting reference such as a buoy.
    Beacon,
}

impl Role {
    pub const fn group(self) -> &'static str {
        match self {
            Role::Truth => "truth",
            Role::Estimate => "estimate",
            Role::Cna => "cna",
            Role::Beacon => "beacon",
        }
    }

    pub fn from_group(group: &str) -> Option<Self> {
        [Role::Truth, Role::Estimate, Role::Cna, Role::Beacon].into_iter().find(|r| r.group() == group)
    }
}

/// One point of a track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub t: f64,
    pub x: f64,
    pub y: f64,
    pub depth: f64,
    /// The filter's horizontal 1σ (√(P_EE + P_NN)), m, for estimates.
    pub sd: Option<f64>,
    /// The filter's horizontal covariance [P_EE, P_EN, P_NN], m², for estimates that report it
    /// (drawn as 1σ/2σ ellipses; linear interpolation of covariances stays positive semi-definite).
    pub cov: Option<[f64; 3]>,
}

/// One vehicle's track, samples in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct Vehicle {
    /// The NODE_REPORT `NAME`: `auv0`, `auv0_est`, `cna`.
    pub name: String,
    pub role: Role,
    /// The NODE_REPORT `TYPE` (MOOS vehicle types: `auv`, `ship`, `buoy`).
    pub kind: &'static str,
    pub samples: Vec<Sample>,
}

/// Which acoustic exchange a pulse shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PulseKind {
    /// A one-way-travel-time ranging broadcast from `from`, drawn as a ring reaching `to`.
    Range,
    /// A data packet from `from` to `to`, drawn as a beam.
    Comms,
}

/// One acoustic transmission, received or lost.
#[derive(Debug, Clone, PartialEq)]
pub struct Pulse {
    pub t: f64,
    pub kind: PulseKind,
    pub from: String,
    pub to: String,
    pub received: bool,
}

/// A leg the CNA's planner chose at time `t`: points (x, y, depth) to steer through.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    pub t: f64,
    pub points: Vec<[f64; 3]>,
}

/// Everything one run exports.
#[derive(Debug, Clone)]
pub struct RunLog {
    /// What the run was: shown by viewers (e.g. "closed loop, policy planner").
    pub scenario: String,
    /// The coopnav command that produced it ("simulate", "hbl simulate", "plan").
    pub command: String,
    pub version: String,
    /// When set, NODE_REPORTs carry LAT/LON too.
    pub origin: Option<LocalFrame>,
    pub vehicles: Vec<Vehicle>,
    pub pulses: Vec<Pulse>,
    pub legs: Vec<Leg>,
}

impl RunLog {
    pub fn vehicle(&self, name: &str) -> Option<&Vehicle> {
        self.vehicles.iter().find(|v| v.name == name)
    }
}

impl Vehicle {
    /// The position at `t`, linearly interpolated between samples; `None` outside the track.
    pub fn at(&self, t: f64) -> Option<Sample> {
        sample_at(&self.samples, t)
    }
}

/// The point of a time-ordered track at `t`, linearly interpolated; `None` outside the track.
pub fn sample_at(s: &[Sample], t: f64) -> Option<Sample> {
    let after = s.partition_point(|p| p.t < t);
    if after == s.len() {
        return None;
    }
    let b = s[after];
    if b.t == t {
        return Some(b);
    }
    let a = *s.get(after.checked_sub(1)?)?;
    let f = (t - a.t) / (b.t - a.t);
    let lerp = |u: f64, v: f64| u + f * (v - u);
    let sd = match (a.sd, b.sd) {
        (Some(u), Some(v)) => Some(lerp(u, v)),
        _ => None,
    };
    let cov = match (a.cov, b.cov) {
        (Some(u), Some(v)) => Some([lerp(u[0], v[0]), lerp(u[1], v[1]), lerp(u[2], v[2])]),
        _ => None,
    };
    Some(Sample { t, x: lerp(a.x, b.x), y: lerp(a.y, b.y), depth: lerp(a.depth, b.depth), sd, cov })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight() -> Vehicle {
        let sample = |t: f64, x: f64| Sample { t, x, y: -x, depth: 2.0 * x, sd: Some(t), cov: None };
        Vehicle {
            name: "auv1".into(),
            role: Role::Truth,
            kind: "auv",
            samples: vec![sample(0.0, 0.0), sample(10.0, 5.0)],
        }
    }

    #[test]
    fn positions_between_samples_are_interpolated_and_outside_are_none() {
        let v = straight();
        let mid = v.at(4.0).unwrap();
        assert_eq!((mid.x, mid.y, mid.depth, mid.sd), (2.0, -2.0, 4.0, Some(4.0)));
        assert_eq!(v.at(0.0).unwrap().x, 0.0);
        assert_eq!(v.at(10.0).unwrap().x, 5.0);
        assert!(v.at(-0.5).is_none() && v.at(10.5).is_none());
    }

    #[test]
    fn groups_name_their_role_and_back() {
        for role in [Role::Truth, Role::Estimate, Role::Cna, Role::Beacon] {
            assert_eq!(Role::from_group(role.group()), Some(role));
        }
        assert_eq!(Role::from_group("red"), None);
    }
}
