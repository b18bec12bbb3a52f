//! Survey missions: lawnmower patterns and time-stamped tracks.
//!
//! A [`Track`] is what the planner needs of a survey AUV in pre-deployment mode (its position at
//! any time), and what the simulators use as a plan to follow. A [`Lawnmower`] is the usual MCM
//! survey pattern, generated from a handful of numbers.

use crate::{Heading, Vec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One time-stamped position of a track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrackSample {
    pub t: f64,
    pub pos: Vec3,
}

#[derive(Debug, Error, PartialEq)]
pub enum TrackError {
    #[error("track is empty: at least one sample is needed")]
    Empty,
    #[error(
        "track sample {index}: time {t} is not after the previous sample's time {prev} (times must increase strictly)"
    )]
    NonMonotone { index: usize, t: f64, prev: f64 },
    #[error("track sample {index}: non-finite value (time and x, y, z must be finite numbers)")]
    NonFinite { index: usize },
}

/// A survey AUV's path as time-stamped positions, linearly interpolated between samples and held
/// at the first/last sample outside its time span.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    samples: Vec<TrackSample>,
}

impl Track {
    /// Builds a track, checking that it is non-empty, finite and strictly increasing in time.
    pub fn new(samples: Vec<TrackSample>) -> Result<Self, TrackError> {
        if samples.is_empty() {
            return Err(TrackError::Empty);
        }
        for (index, s) in samples.iter().enumerate() {
            if !(s.t.is_finite() && s.pos.iter().all(|v| v.is_finite())) {
                return Err(TrackError::NonFinite { index });
            }
            if index > 0 && s.t <= samples[index - 1].t {
                return Err(TrackError::NonMonotone { index, t: s.t, prev: samples[index - 1].t });
            }
        }
        Ok(Track { samples })
    }

    pub fn samples(&self) -> &[TrackSample] {
        &self.samples
    }
    pub fn start_time(&self) -> f64 {
        self.samples[0].t
    }
    pub fn end_time(&self) -> f64 {
        self.samples[self.samples.len() - 1].t
    }

    /// Position at time `t` (linear interpolation; clamped to the ends).
    pub fn at(&self, t: f64) -> Vec3 {
        let s = &self.samples;
        let i = s.partition_point(|p| p.t <= t);
        if i == 0 {
            return s[0].pos;
        }
        if i == s.len() {
            return s[s.len() - 1].pos;
        }
        let (a, b) = (&s[i - 1], &s[i]);
        let f = (t - a.t) / (b.t - a.t);
        a.pos + (b.pos - a.pos) * f
    }
}

/// Depth of a survey AUV over time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DepthProfile {
    /// Constant depth, metres.
    Constant { depth: f64 },
    /// z̄ + a·sin(2πt/T): the Hudson thesis's variable-depth survey AUVs.
    Sinusoid { mean: f64, amplitude: f64, period: f64 },
}

impl DepthProfile {
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            DepthProfile::Constant { depth } => depth,
            DepthProfile::Sinusoid { mean, amplitude, period } => {
                mean + amplitude * (std::f64::consts::TAU * t / period).sin()
            }
        }
    }
}

/// A lawnmower survey: `lanes` parallel lanes of `lane_length` m, `spacing` m apart, the first
/// starting at `origin` and running along `lane_heading`; successive lanes step to the left of
/// that heading (use a negative spacing to step right) and alternate direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Lawnmower {
    pub origin: (f64, f64),
    pub lane_heading: Heading,
    pub lane_length: f64,
    pub spacing: f64,
    pub lanes: usize,
    pub speed: f64,
    pub depth: DepthProfile,
}

impl Lawnmower {
    /// The horizontal turning points of the pattern, in order.
    pub fn waypoints(&self) -> Vec<(f64, f64)> {
        let (ux, uy) = self.lane_heading.unit();
        let (lx, ly) = (-uy, ux);
        let mut pts = Vec::with_capacity(2 * self.lanes);
        for lane in 0..self.lanes {
            let off = lane as f64 * self.spacing;
            let start = (self.origin.0 + lx * off, self.origin.1 + ly * off);
            let end = (start.0 + ux * self.lane_length, start.1 + uy * self.lane_length);
            if lane % 2 == 0 {
                pts.extend([start, end]);
            } else {
                pts.extend([end, start]);
            }
        }
        pts
    }

    /// Total path length, metres.
    pub fn path_length(&self) -> f64 {
        self.waypoints().windows(2).map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)).sum()
    }

    /// Samples the pattern flown at constant speed from t = 0, every `dt` seconds (and at the end).
    pub fn track(&self, dt: f64) -> Result<Track, TrackError> {
        track_through(&self.waypoints(), self.origin, self.speed, &self.depth, dt)
    }
}

/// A survey AUV's planned path: waypoints flown in order at constant speed and depth profile (a
/// lawnmower's turning points, or the waypoints of an imported mission).
#[derive(Debug, Clone, PartialEq)]
pub struct SurveyPath {
    pub waypoints: Vec<(f64, f64)>,
    pub speed: f64,
    pub depth: DepthProfile,
}

impl SurveyPath {
    /// The horizontal waypoints, in order.
    pub fn waypoints(&self) -> Vec<(f64, f64)> {
        self.waypoints.clone()
    }

    /// Total path length, metres.
    pub fn path_length(&self) -> f64 {
        self.waypoints.windows(2).map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)).sum()
    }

    /// Samples the path flown at constant speed from t = 0, every `dt` seconds (and at the end).
    pub fn track(&self, dt: f64) -> Result<Track, TrackError> {
        let start = self.waypoints.first().copied().unwrap_or((0.0, 0.0));
        track_through(&self.waypoints, start, self.speed, &self.depth, dt)
    }
}

impl From<Lawnmower> for SurveyPath {
    fn from(m: Lawnmower) -> Self {
        SurveyPath { waypoints: m.waypoints(), speed: m.speed, depth: m.depth }
    }
}

/// `wps` flown at constant `speed` from t = 0, sampled every `dt` s and at the end; `fallback` is
/// the position when there are no waypoints.
fn track_through(
    wps: &[(f64, f64)],
    fallback: (f64, f64),
    speed: f64,
    depth: &DepthProfile,
    dt: f64,
) -> Result<Track, TrackError> {
    let total: f64 = wps.windows(2).map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)).sum();
    let duration = if speed > 0.0 { total / speed } else { 0.0 };
    let n = (duration / dt).ceil().max(0.0) as usize;
    let mut samples = Vec::with_capacity(n + 1);
    let (mut seg, mut seg_start) = (0usize, 0.0);
    for k in 0..=n {
        let t = (k as f64 * dt).min(duration);
        let s = t * speed;
        while seg + 2 < wps.len() && s > seg_start + seg_len(wps, seg) {
            seg_start += seg_len(wps, seg);
            seg += 1;
        }
        let (x, y) = if wps.len() < 2 {
            wps.first().copied().unwrap_or(fallback)
        } else {
            let len = seg_len(wps, seg);
            let f = if len > 0.0 { ((s - seg_start) / len).clamp(0.0, 1.0) } else { 0.0 };
            let (a, b) = (wps[seg], wps[seg + 1]);
            (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f)
        };
        samples.push(TrackSample { t, pos: Vec3::new(x, y, depth.at(t)) });
        if t >= duration {
            break;
        }
    }
    Track::new(samples)
}

fn seg_len(wps: &[(f64, f64)], i: usize) -> f64 {
    (wps[i + 1].0 - wps[i].0).hypot(wps[i + 1].1 - wps[i].1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mower() -> Lawnmower {
        Lawnmower {
            origin: (0.0, 0.0),
            lane_heading: Heading::from_radians(0.0),
            lane_length: 100.0,
            spacing: 20.0,
            lanes: 3,
            speed: 2.0,
            depth: DepthProfile::Constant { depth: 10.0 },
        }
    }

    #[test]
    fn lawnmower_waypoints_alternate() {
        let w = mower().waypoints();
        assert_eq!(w.len(), 6);
        assert!((w[1].0 - 100.0).abs() < 1e-9 && w[1].1.abs() < 1e-9);
        assert!((w[2].0 - 100.0).abs() < 1e-9 && (w[2].1 - 20.0).abs() < 1e-9);
        assert!(w[3].0.abs() < 1e-9);
        assert!((mower().path_length() - 340.0).abs() < 1e-9);
    }

    #[test]
    fn track_flies_at_speed_and_interpolates() {
        let tr = mower().track(1.0).unwrap();
        assert!((tr.end_time() - 170.0).abs() < 1e-9);
        let p = tr.at(55.5);
        assert!((p.x - 100.0).abs() < 1e-9 && (p.y - 11.0).abs() < 1e-9 && p.z == 10.0);
        assert_eq!(tr.at(1e6), tr.samples().last().unwrap().pos);
    }

    #[test]
    fn bad_tracks_are_rejected() {
        assert_eq!(Track::new(vec![]), Err(TrackError::Empty));
        let s = |t| TrackSample { t, pos: Vec3::zeros() };
        assert!(matches!(Track::new(vec![s(0.0), s(0.0)]), Err(TrackError::NonMonotone { index: 1, .. })));
        assert!(matches!(Track::new(vec![s(f64::NAN)]), Err(TrackError::NonFinite { index: 0 })));
    }

    #[test]
    fn sinusoid_depth() {
        let d = DepthProfile::Sinusoid { mean: 20.0, amplitude: 5.0, period: 40.0 };
        assert!((d.at(10.0) - 25.0).abs() < 1e-12);
        assert!((d.at(30.0) - 15.0).abs() < 1e-12);
    }
}
