//! CNA motion (Hudson 2012, Ch. 3, eq. 2; reconstructed, docs/models.md#hudson-motion): the discrete heading (and,
//! for an AUV CNA, pitch) options, and one constant-speed straight step of τ seconds.
//!
//! Headings are math convention (0 = east, counter-clockwise). Depth z is positive down and a
//! positive pitch is nose up, so z' = z − s·τ·sin φ'. The new heading and pitch hold for the
//! whole step (instantaneous turn; docs/models.md#hudson-motion).

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{Heading, Vec3};
use serde::{Deserialize, Serialize};

/// Which vehicle is the CNA.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum CnaKind {
    /// A surface craft: heading options only, depth fixed.
    Asc {},
    /// An AUV CNA: B pitch options too, with pitch and depth limits (invented defaults, docs/models.md#hudson-motion).
    Auv {
        /// Number of pitch options B (≥ 1).
        pitch_options: usize,
        /// Maximum pitch rate φ̇max, degrees per second (Table 5.1: 1.5).
        #[serde(default = "default_pitch_rate")]
        max_pitch_rate_deg_s: f64,
        /// Maximum |pitch| φmax, degrees. Invented: 30°, the thesis's dive-angle example
        /// (docs/models.md#hudson-motion).
        #[serde(default = "default_max_pitch")]
        max_pitch_deg: f64,
        /// Shallowest allowed depth, m. Invented: 0 m (docs/models.md#hudson-motion).
        #[serde(default)]
        min_depth: f64,
        /// Deepest allowed depth, m. Invented: 100 m (docs/models.md#hudson-motion).
        #[serde(default = "default_max_depth")]
        max_depth: f64,
        /// How many tree levels offer the pitch options, from level 0 (≥ 1); deeper levels hold
        /// the pitch (Δφ = 0, heading options only). None: every level. With an AUV CNA the A·B
        /// options per level force a short look-ahead, and deeper pitch options seldom pay
        /// (docs/evaluation.md).
        #[serde(default)]
        pitch_levels: Option<usize>,
        /// The CNA as the closed loop's engine flies it: every step starts
        /// level and pitches by its option alone, cut at `max_pitch_deg`, and its depth stops at
        /// `min_depth`/`max_depth` (the craft reaches the commanded depth and holds it). False: the
        /// thesis's model, the pitch carried from level to level and any excess penalised, under
        /// which a ±45° option (1.5°/s over 30 s) always breaks the 30° limit.
        #[serde(default)]
        level_off: bool,
    },
}

fn default_pitch_rate() -> f64 {
    1.5
}
fn default_max_pitch() -> f64 {
    30.0
}
fn default_max_depth() -> f64 {
    100.0
}
fn default_turn_rate() -> f64 {
    4.0
}

impl CnaKind {
    /// An AUV CNA with B pitch options and the default (invented) limits.
    pub fn auv(pitch_options: usize) -> Self {
        CnaKind::Auv {
            pitch_options,
            max_pitch_rate_deg_s: default_pitch_rate(),
            max_pitch_deg: default_max_pitch(),
            min_depth: 0.0,
            max_depth: default_max_depth(),
            pitch_levels: None,
            level_off: false,
        }
    }
}

/// How the CNA may move each step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionConfig {
    /// CNA speed s, m/s (> 0).
    pub speed: f64,
    /// Decision period τ, s (> 0).
    pub tau: f64,
    /// Number of heading options A (≥ 2).
    pub heading_options: usize,
    /// Maximum turn rate ψ̇max, degrees per second (Table 5.1: 4). ψ̇max·τ must stay below 180°.
    #[serde(default = "default_turn_rate")]
    pub max_turn_rate_deg_s: f64,
    pub cna: CnaKind,
}

/// The CNA's pose: position, heading and pitch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CnaPose {
    pub pos: Vec3,
    pub heading: Heading,
    /// Pitch φ, radians, positive nose up (0 for an ASC).
    pub pitch: f64,
}

/// One candidate manoeuvre: heading change and pitch change, radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MotionOption {
    pub dpsi: f64,
    pub dphi: f64,
}

/// A pose in the form the search steps quickly: heading as (cos, sin), rotated per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FastPose {
    pub p: [f64; 3],
    pub ch: f64,
    pub sh: f64,
    pub phi: f64,
}

/// An option with its rotation precomputed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FastOption {
    pub cd: f64,
    pub sd: f64,
    pub dphi: f64,
}

impl FastPose {
    pub fn from_pose(p: &CnaPose) -> Self {
        let (sh, ch) = p.heading.radians().sin_cos();
        FastPose { p: [p.pos.x, p.pos.y, p.pos.z], ch, sh, phi: p.pitch }
    }
    pub fn to_pose(self) -> CnaPose {
        CnaPose {
            pos: Vec3::new(self.p[0], self.p[1], self.p[2]),
            heading: Heading::from_radians(self.sh.atan2(self.ch)),
            pitch: self.phi,
        }
    }
}

fn linspace(half_width: f64, n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![0.0];
    }
    (0..n).map(|i| -half_width + 2.0 * half_width * i as f64 / (n - 1) as f64).collect()
}

impl CheckFields for MotionConfig {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.check(&format!("{prefix}speed"), self.speed, |v| v > 0.0, "a finite number > 0 m/s");
        p.check(&format!("{prefix}tau"), self.tau, |v| v > 0.0, "a finite number > 0 s");
        if self.heading_options < 2 {
            p.push(format!("{prefix}heading_options"), self.heading_options.to_string(), ">= 2");
        }
        let swing = self.max_turn_rate_deg_s * self.tau;
        if !(self.max_turn_rate_deg_s.is_finite() && self.max_turn_rate_deg_s > 0.0 && swing < 180.0) {
            p.push(
                format!("{prefix}max_turn_rate_deg_s"),
                format!("{} (x tau = {swing} deg)", self.max_turn_rate_deg_s),
                "> 0 with max_turn_rate_deg_s * tau < 180 degrees (so hard left and hard right never overlap)",
            );
        }
        if let CnaKind::Auv {
            pitch_options,
            max_pitch_rate_deg_s,
            max_pitch_deg,
            min_depth,
            max_depth,
            pitch_levels,
            ..
        } = self.cna
        {
            if pitch_options < 1 {
                p.push(format!("{prefix}cna.pitch_options"), pitch_options.to_string(), ">= 1");
            }
            if pitch_levels == Some(0) {
                p.push(format!("{prefix}cna.pitch_levels"), "0", ">= 1 (or absent: every level)");
            }
            p.non_negative(&format!("{prefix}cna.max_pitch_rate_deg_s"), max_pitch_rate_deg_s);
            p.check(&format!("{prefix}cna.max_pitch_deg"), max_pitch_deg, |v| v > 0.0 && v < 90.0, "in (0, 90)");
            if !(min_depth.is_finite() && max_depth.is_finite() && min_depth < max_depth) {
                p.push(
                    format!("{prefix}cna.min_depth/max_depth"),
                    format!("{min_depth}/{max_depth}"),
                    "finite with min_depth < max_depth",
                );
            }
        }
    }
}

impl MotionConfig {
    /// The A·B options in ascending (Δψ, Δφ) order: the order that breaks ties (docs/models.md#hudson-search).
    pub fn options(&self) -> Vec<MotionOption> {
        let psi = linspace((self.max_turn_rate_deg_s * self.tau).to_radians(), self.heading_options);
        let phi = match self.cna {
            CnaKind::Asc {} => vec![0.0],
            CnaKind::Auv { pitch_options, max_pitch_rate_deg_s, .. } => {
                linspace((max_pitch_rate_deg_s * self.tau).to_radians(), pitch_options)
            }
        };
        psi.iter().flat_map(|&dpsi| phi.iter().map(move |&dphi| MotionOption { dpsi, dphi })).collect()
    }

    /// The pose one step of option `o` from `pose` reaches, and whether it keeps the AUV CNA's
    /// pitch and depth limits (always for an ASC): a level-0 child of the search, for callers
    /// that score the options themselves (the headroom example's rollouts).
    pub fn next(&self, pose: &CnaPose, o: &MotionOption) -> (CnaPose, bool) {
        let fast = FastOption { cd: o.dpsi.cos(), sd: o.dpsi.sin(), dphi: o.dphi };
        let p = self.step(&FastPose::from_pose(pose), &fast);
        (p.to_pose(), self.limit_violation(&p) == 0.0)
    }

    /// How many tree levels, from level 0, offer the pitch options (`CnaKind::Auv::pitch_levels`;
    /// `usize::MAX`: every level).
    pub(crate) fn pitch_levels(&self) -> usize {
        match self.cna {
            CnaKind::Asc {} => usize::MAX,
            CnaKind::Auv { pitch_levels, .. } => pitch_levels.unwrap_or(usize::MAX),
        }
    }

    pub(crate) fn fast_options(&self) -> Vec<FastOption> {
        self.options().iter().map(|o| FastOption { cd: o.dpsi.cos(), sd: o.dpsi.sin(), dphi: o.dphi }).collect()
    }

    /// One step of eq. (2).
    #[inline(always)]
    pub(crate) fn step(&self, p: &FastPose, o: &FastOption) -> FastPose {
        let ch = p.ch * o.cd - p.sh * o.sd;
        let sh = p.sh * o.cd + p.ch * o.sd;
        let d = self.speed * self.tau;
        // The engine's CNA levels off at each commanded depth: with `level_off` every step starts level.
        let (phi, depths) = match self.cna {
            CnaKind::Auv { level_off: true, max_pitch_deg, min_depth, max_depth, .. } => {
                let max = max_pitch_deg.to_radians();
                (o.dphi.clamp(-max, max), Some((min_depth, max_depth)))
            }
            _ => (p.phi + o.dphi, None),
        };
        let (sp, cp) = if phi == 0.0 { (0.0, 1.0) } else { phi.sin_cos() };
        let z = p.p[2] - d * sp;
        let z = depths.map_or(z, |(lo, hi)| z.clamp(lo, hi));
        FastPose { p: [p.p[0] + d * ch * cp, p.p[1] + d * sh * cp, z], ch, sh, phi }
    }

    /// How far a pose breaks the AUV-CNA pitch and depth limits (0 = within limits; else metres:
    /// depth excess plus pitch excess times the step length). Always 0 for an ASC.
    #[inline]
    pub(crate) fn limit_violation(&self, p: &FastPose) -> f64 {
        match self.cna {
            CnaKind::Asc {} => 0.0,
            CnaKind::Auv { max_pitch_deg, min_depth, max_depth, .. } => {
                let pitch_excess = (p.phi.abs() - max_pitch_deg.to_radians()).max(0.0);
                let depth_excess = (min_depth - p.p[2]).max(0.0) + (p.p[2] - max_depth).max(0.0);
                depth_excess + pitch_excess * self.speed * self.tau
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(a: usize, cna: CnaKind) -> MotionConfig {
        MotionConfig { speed: 2.0, tau: 30.0, heading_options: a, max_turn_rate_deg_s: 4.0, cna }
    }

    #[test]
    fn heading_options_span_the_turn_limit() {
        let o = cfg(5, CnaKind::Asc {}).options();
        let d: Vec<f64> = o.iter().map(|o| o.dpsi.to_degrees()).collect();
        for (got, want) in d.iter().zip([-120.0, -60.0, 0.0, 60.0, 120.0]) {
            assert!((got - want).abs() < 1e-9);
        }
        let o = cfg(3, CnaKind::auv(3)).options();
        assert_eq!(o.len(), 9);
        assert!(o.windows(2).all(|w| (w[0].dpsi, w[0].dphi) < (w[1].dpsi, w[1].dphi)));
        assert!((o[2].dphi.to_degrees() - 45.0).abs() < 1e-9);
    }

    #[test]
    fn step_moves_at_speed_and_pitch_up_is_shallower() {
        let c = cfg(3, CnaKind::auv(3));
        let p = FastPose::from_pose(&CnaPose {
            pos: Vec3::new(0.0, 0.0, 50.0),
            heading: Heading::from_radians(0.0),
            pitch: 0.0,
        });
        let up = c.fast_options()[5]; // Δψ = 0, Δφ = +45°
        let q = c.step(&p, &up);
        let moved = ((q.p[0]).powi(2) + q.p[1].powi(2) + (q.p[2] - 50.0).powi(2)).sqrt();
        assert!((moved - 60.0).abs() < 1e-9);
        assert!(q.p[2] < 50.0);
        assert!(c.limit_violation(&q) > 0.0, "45 deg pitch breaks the 30 deg limit");
    }

    /// Levelling off (the closed loop's AUV CNA): every step starts level, its pitch is cut at
    /// the limit and its depth kept within [min_depth, max_depth]; the thesis's model instead
    /// carries the pitch on and breaks the limits.
    #[test]
    fn a_levelling_cna_cuts_its_pitch_and_depth_at_the_limits() {
        let auv = |level_off| CnaKind::Auv {
            pitch_options: 3,
            max_pitch_rate_deg_s: 1.5,
            max_pitch_deg: 30.0,
            min_depth: 0.0,
            max_depth: 40.0,
            pitch_levels: None,
            level_off,
        };
        let (thesis, level) = (cfg(3, auv(false)), cfg(3, auv(true)));
        let p = FastPose::from_pose(&CnaPose {
            pos: Vec3::new(0.0, 0.0, 10.0),
            heading: Heading::from_radians(0.0),
            pitch: 0.0,
        });
        let [down, _, up] = [3, 4, 5].map(|i| level.fast_options()[i]); // Δψ = 0, Δφ = −45°, 0, +45°
        let climbed = level.step(&p, &up);
        assert_eq!(climbed.p[2], 0.0, "60 m at 30° would climb 30 m: it levels off at the surface");
        assert!((climbed.phi - 30f64.to_radians()).abs() < 1e-12 && level.limit_violation(&climbed) == 0.0);
        assert!((climbed.p[0] - 60.0 * 30f64.to_radians().cos()).abs() < 1e-9);
        let dived = level.step(&level.step(&p, &down), &down);
        assert_eq!(dived.p[2], 40.0, "two 30 m dives from 10 m stop at 40 m");
        let held = level.step(&climbed, &level.fast_options()[4]);
        assert_eq!((held.phi, held.p[2]), (0.0, 0.0), "the next step starts level");
        let broken = thesis.step(&p, &up);
        assert!(broken.p[2] < 0.0 && thesis.limit_violation(&broken) > 0.0);
    }

    #[test]
    fn next_is_the_searchs_step_with_its_limit_check() {
        let c = cfg(3, CnaKind::auv(3));
        let pose = CnaPose { pos: Vec3::new(0.0, 0.0, 50.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        let options = c.options();
        // Δψ = 0, Δφ = 0: 60 m east, within limits; Δφ = +45°: the search's own pose, off limits.
        let (level, ok) = c.next(&pose, &options[4]);
        assert!((level.pos - Vec3::new(60.0, 0.0, 50.0)).norm() < 1e-9 && ok, "{level:?}");
        let (up, ok) = c.next(&pose, &options[5]);
        assert_eq!(up, c.step(&FastPose::from_pose(&pose), &c.fast_options()[5]).to_pose());
        assert!(!ok);
    }

    #[test]
    fn bad_motion_is_rejected() {
        assert!(cfg(1, CnaKind::Asc {}).validate("").is_err());
        assert!(MotionConfig { speed: -1.0, ..cfg(3, CnaKind::Asc {}) }.validate("").is_err());
        let e = MotionConfig { tau: 45.0, ..cfg(3, CnaKind::Asc {}) }.validate("motion.").unwrap_err();
        assert!(e.to_string().contains("motion.max_turn_rate_deg_s"), "{e}");
        assert!(cfg(3, CnaKind::Asc {}).validate("").is_ok());
        let both = MotionConfig { speed: f64::NAN, heading_options: 1, ..cfg(3, CnaKind::Asc {}) };
        let fields: Vec<String> = both.validate("").unwrap_err().0.into_iter().map(|p| p.field).collect();
        assert_eq!(fields, ["speed", "heading_options"]);
    }
}
