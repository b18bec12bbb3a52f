//! When an AUV CNA leaves its work to climb for a GPS fix, as a field team runs one whose own
//! dead reckoning drifts: on a fixed period, or when its own horizontal σ (which it knows from its
//! navigation filter) reaches a threshold. It climbs straight up at its pitch-limited rate,
//! stays at the surface for the fix time, takes a fix of the configured σ and goes back to work,
//! diving to the depth it left (policies that keep the current depth would otherwise stay up).
//! The climb and the wait are what it costs: meanwhile the CNA follows no policy, whichever it
//! is. A CNA that works at the surface ([`at_surface`]) has its GPS antenna out: it never
//! climbs, and after the fix time there it takes a fix at every decision while it stays, as a
//! surface craft does. Checked at each decision (every τ).
//! Invented parameters (no thesis value): the period, threshold, fix time and fix σ.

use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// Which rule sends the CNA up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SurfaceWhen {
    /// Every `period_s` seconds since the last fix (the mission start counts as one).
    Period { period_s: f64 },
    /// When the CNA's own horizontal 1-σ per axis, √(σ_fix² + D·(t − t_fix)), reaches `sigma_m`.
    Sigma { sigma_m: f64 },
}

/// `cna.navigation.surfacing` (dead reckoning): the rule, and what a fix takes and gives.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Surfacing {
    pub when: SurfaceWhen,
    /// Time at the surface before the fix is taken, s.
    pub fix_time_s: f64,
    /// σ of the GPS fix per axis, m.
    pub gps_sd_m: f64,
}

impl CheckFields for Surfacing {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        match self.when {
            SurfaceWhen::Period { period_s } => p.positive(&format!("{prefix}when.period_s"), period_s),
            SurfaceWhen::Sigma { sigma_m } => p.positive(&format!("{prefix}when.sigma_m"), sigma_m),
        }
        p.non_negative(&format!("{prefix}fix_time_s"), self.fix_time_s);
        p.non_negative(&format!("{prefix}gps_sd_m"), self.gps_sd_m);
    }
}

/// Where the CNA is in its surfacing cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    /// Following its policy.
    Working,
    /// Climbing to the surface from its working depth, m.
    Climbing { from: f64 },
    /// At the surface since this time, waiting for the fix.
    Surfaced { since: f64, from: f64 },
}

/// What the CNA does at this decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// Follow the policy.
    Work,
    /// Go (or stay) straight up at its current horizontal position.
    Climb,
    /// Take the GPS fix now and dive back to the working depth `to` (m), on the policy's course.
    Fix { to: f64 },
    /// Working at the surface: take a GPS fix now and follow the policy.
    WorkWithFix,
}

/// The CNA's own navigation uncertainty and surfacing cycle.
#[derive(Debug, Clone, Copy)]
pub struct OwnNav {
    /// Variance per axis at the last fix, m², and its time, s.
    fix_variance: f64,
    fix_t: f64,
    /// Growth of the variance, m²/s per axis (the engine's random walk).
    diffusion: f64,
    phase: Phase,
    /// Since when it has been working at the surface (None: below it).
    working_at_surface: Option<f64>,
}

/// Depth at which the CNA counts as surfaced (its GPS antenna out), m.
const SURFACE_DEPTH_M: f64 = 0.5;

/// Whether a CNA at `depth` (m) is at the surface, where an AUV CNA has GPS.
pub fn at_surface(depth: f64) -> bool {
    depth <= SURFACE_DEPTH_M
}

impl OwnNav {
    /// Starting exactly known at time 0 (the engine's CNA error starts at zero).
    pub fn new(diffusion: f64) -> Self {
        OwnNav { fix_variance: 0.0, fix_t: 0.0, diffusion, phase: Phase::Working, working_at_surface: None }
    }

    /// The CNA's own horizontal variance per axis at time `t`, m².
    pub fn variance(&self, t: f64) -> f64 {
        self.fix_variance + self.diffusion * (t - self.fix_t).max(0.0)
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The decision at time `t` with the CNA at `depth`, under `rule` (None: never surfaces).
    pub fn step(&mut self, rule: Option<&Surfacing>, t: f64, depth: f64) -> Step {
        let Some(rule) = rule else { return Step::Work };
        if self.phase == Phase::Working {
            self.working_at_surface = at_surface(depth).then(|| self.working_at_surface.unwrap_or(t));
        }
        match self.phase {
            Phase::Working if self.working_at_surface.is_some_and(|since| t - since >= rule.fix_time_s) => {
                self.take_fix(rule, t);
                Step::WorkWithFix
            }
            // At the surface already: the fix comes without a climb.
            Phase::Working if self.working_at_surface.is_some() => Step::Work,
            Phase::Working if self.due(&rule.when, t) => {
                self.phase = Phase::Climbing { from: depth };
                self.step(Some(rule), t, depth)
            }
            Phase::Working => Step::Work,
            Phase::Climbing { from } if at_surface(depth) => {
                self.phase = Phase::Surfaced { since: t, from };
                self.step(Some(rule), t, depth)
            }
            Phase::Climbing { .. } => Step::Climb,
            Phase::Surfaced { since, from } if t - since >= rule.fix_time_s => {
                self.phase = Phase::Working;
                self.take_fix(rule, t);
                Step::Fix { to: from }
            }
            Phase::Surfaced { .. } => Step::Climb,
        }
    }

    fn take_fix(&mut self, rule: &Surfacing, t: f64) {
        self.fix_variance = rule.gps_sd_m * rule.gps_sd_m;
        self.fix_t = t;
    }

    fn due(&self, when: &SurfaceWhen, t: f64) -> bool {
        match *when {
            SurfaceWhen::Period { period_s } => t - self.fix_t >= period_s,
            SurfaceWhen::Sigma { sigma_m } => self.variance(t) >= sigma_m * sigma_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rule(when: SurfaceWhen) -> Surfacing {
        Surfacing { when, fix_time_s: 30.0, gps_sd_m: 2.0 }
    }

    #[test]
    fn the_sigma_rule_climbs_waits_the_fix_time_and_resets_the_variance() {
        let r = rule(SurfaceWhen::Sigma { sigma_m: 6.0 });
        let mut nav = OwnNav::new(0.01);
        // σ² reaches 36 m² at 3600 s.
        assert_eq!(nav.step(Some(&r), 3570.0, 10.0), Step::Work);
        assert_eq!(nav.step(Some(&r), 3600.0, 10.0), Step::Climb);
        assert_eq!(nav.step(Some(&r), 3630.0, 0.0), Step::Climb);
        assert_eq!(nav.phase(), Phase::Surfaced { since: 3630.0, from: 10.0 });
        assert_eq!(nav.step(Some(&r), 3660.0, 0.0), Step::Fix { to: 10.0 });
        assert_eq!(nav.variance(3660.0), 4.0);
        assert!((nav.variance(3760.0) - 5.0).abs() < 1e-12);
        assert_eq!(nav.step(Some(&r), 3690.0, 0.0), Step::Work);
    }

    #[test]
    fn the_period_rule_counts_from_the_last_fix_and_no_rule_never_surfaces() {
        let r = Surfacing { fix_time_s: 0.0, ..rule(SurfaceWhen::Period { period_s: 900.0 }) };
        let mut nav = OwnNav::new(0.01);
        assert_eq!(nav.step(Some(&r), 870.0, 10.0), Step::Work);
        // Already at the surface and no wait: the fix comes at once, and the CNA works on.
        assert_eq!(nav.step(Some(&r), 900.0, 0.2), Step::WorkWithFix);
        assert_eq!(nav.step(Some(&r), 1770.0, 10.0), Step::Work);
        assert_eq!(nav.step(Some(&r), 1800.0, 10.0), Step::Climb);
        let mut never = OwnNav::new(0.01);
        assert_eq!(never.step(None, 1e6, 10.0), Step::Work);
        assert_eq!(never.variance(100.0), 1.0);
    }

    /// A CNA cruising at the surface has its antenna out: it never climbs, its first fix comes
    /// after the fix time there, then one at every decision; diving ends them.
    #[test]
    fn working_at_the_surface_fixes_at_every_decision_after_the_fix_time() {
        let r = rule(SurfaceWhen::Sigma { sigma_m: 1.0 });
        let mut nav = OwnNav::new(0.01);
        // σ² has reached 1 m² (100 s) and is due, but at the surface it keeps working.
        assert_eq!(nav.step(Some(&r), 120.0, 0.3), Step::Work);
        assert_eq!(nav.phase(), Phase::Working);
        assert_eq!(nav.step(Some(&r), 150.0, 0.0), Step::WorkWithFix);
        assert_eq!(nav.variance(150.0), 4.0);
        assert_eq!(nav.step(Some(&r), 180.0, 0.0), Step::WorkWithFix);
        assert!((nav.variance(200.0) - 4.2).abs() < 1e-12);
        // Below the surface it drifts again and climbs when due (σ² 4 + 0.01·t ≥ 1 at once here).
        assert_eq!(nav.step(Some(&r), 210.0, 10.0), Step::Climb);
        // Back at the surface it waits the whole fix time again (as a climbing CNA does).
        assert_eq!(nav.step(Some(&r), 240.0, 0.0), Step::Climb);
        assert_eq!(nav.step(Some(&r), 270.0, 0.0), Step::Fix { to: 10.0 });
    }

    #[test]
    fn bad_settings_are_named() {
        let mut p = Problems::default();
        Surfacing { fix_time_s: -1.0, ..rule(SurfaceWhen::Sigma { sigma_m: 0.0 }) }
            .check_fields("cna.navigation.surfacing.", &mut p);
        let text = format!("{p:?}");
        assert!(
            text.contains("cna.navigation.surfacing.when.sigma_m")
                && text.contains("cna.navigation.surfacing.fix_time_s"),
            "{text}"
        );
    }
}
