//! How the CNA knows its own position, and which position it broadcasts: `[cna] navigation =
//! { kind = ... }`, one named model apart from the vehicle (`cna.auv`: depth, pitch options,
//! shallowest working depth).
//!
//! - `gps`: a GPS fix of σ `sd_m` per axis at every decision, what a surface craft has. Its
//!   stated variance is `sd_m²`.
//! - `dead-reckoning`: the position error is a random walk whose variance grows by
//!   `diffusion_m2_s` per axis (invented: no thesis value); with `surfacing` the CNA climbs for
//!   a GPS fix by its rule ([`Surfacing`]). Its stated variance is its own σ² since the last fix
//!   ([`OwnNav::variance`]). What it broadcasts is its truth plus this error: an AUV CNA's case.
//! - `exact`: a counterfactual, not a vehicle (`reproduce closed-loop-cna-navigation`): it
//!   navigates as `dead-reckoning` with the same fields does (the error is drawn, its σ grows, it
//!   surfaces as configured) but broadcasts its TRUE position, so no range or command carries the
//!   error.
//!
//! The engine asks the model for the surfacing rule, the stated variance, the error of each
//! decision and the error the broadcast carries; it does not branch on the kind.

use crate::models::noise::normal;
use crate::models::surfacing::{OwnNav, Surfacing};
use coopnav_core::validation::{CheckFields, Problems};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// `cna.navigation`: the CNA's navigation model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum CnaNavigation {
    /// A GPS fix at every decision.
    Gps(Gps),
    /// Dead reckoning between GPS fixes at the surface.
    DeadReckoning(DeadReckoning),
    /// Navigates as `dead-reckoning`, broadcasts its truth (a counterfactual).
    Exact(DeadReckoning),
}

impl Default for CnaNavigation {
    fn default() -> Self {
        CnaNavigation::Gps(Gps::default())
    }
}

/// `navigation = { kind = "gps" }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gps {
    /// σ of the GPS fix per axis, m (default 1).
    #[serde(default = "Gps::default_sd_m")]
    pub sd_m: f64,
}

impl Gps {
    fn default_sd_m() -> f64 {
        1.0
    }
}

impl Default for Gps {
    fn default() -> Self {
        Gps { sd_m: Gps::default_sd_m() }
    }
}

/// `navigation = { kind = "dead-reckoning" }` (and `"exact"`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeadReckoning {
    /// Growth of the horizontal position-error variance, m²/s per axis (a random walk).
    /// Invented: no thesis value.
    pub diffusion_m2_s: f64,
    /// When it climbs for a GPS fix (absent: never; [`Surfacing`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surfacing: Option<Surfacing>,
}

impl CheckFields for CnaNavigation {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        match self {
            CnaNavigation::Gps(g) => p.non_negative(&format!("{prefix}sd_m"), g.sd_m),
            CnaNavigation::DeadReckoning(d) | CnaNavigation::Exact(d) => {
                p.non_negative(&format!("{prefix}diffusion_m2_s"), d.diffusion_m2_s);
                if let Some(s) = &d.surfacing {
                    s.check_fields(&format!("{prefix}surfacing."), p);
                }
            }
        }
    }
}

impl CnaNavigation {
    /// The kind as a file names it.
    pub fn kind(&self) -> &'static str {
        match self {
            CnaNavigation::Gps(_) => "gps",
            CnaNavigation::DeadReckoning(_) => "dead-reckoning",
            CnaNavigation::Exact(_) => "exact",
        }
    }

    /// Whether it holds a GPS fix at every decision.
    pub fn is_gps(&self) -> bool {
        matches!(self, CnaNavigation::Gps(_))
    }

    fn dead_reckoning(&self) -> Option<&DeadReckoning> {
        match self {
            CnaNavigation::Gps(_) => None,
            CnaNavigation::DeadReckoning(d) | CnaNavigation::Exact(d) => Some(d),
        }
    }

    /// Growth of its position-error variance, m²/s per axis (0 with GPS at every decision).
    pub fn diffusion_m2_s(&self) -> f64 {
        self.dead_reckoning().map_or(0.0, |d| d.diffusion_m2_s)
    }

    /// When it climbs for a GPS fix (None: never).
    pub fn surfacing(&self) -> Option<&Surfacing> {
        self.dead_reckoning().and_then(|d| d.surfacing.as_ref())
    }

    /// The variance per axis it states for its own position at time `t`, m² (`own`: its
    /// dead-reckoning uncertainty since the last fix).
    pub fn variance(&self, own: &OwnNav, t: f64) -> f64 {
        match self {
            CnaNavigation::Gps(g) => g.sd_m * g.sd_m,
            CnaNavigation::DeadReckoning(_) | CnaNavigation::Exact(_) => own.variance(t),
        }
    }

    /// Its position error east and north after this decision, m: a GPS fix's (from `gps`) with
    /// GPS, or when `surfaced` (it takes its fix at the surface now); otherwise `previous` plus
    /// the random walk's step over `dt` s (from `walk`).
    pub fn error(
        &self,
        previous: (f64, f64),
        surfaced: bool,
        dt: f64,
        gps: &mut ChaCha8Rng,
        walk: &mut ChaCha8Rng,
    ) -> (f64, f64) {
        let fix = |sd: f64, rng: &mut ChaCha8Rng| (sd * normal(rng), sd * normal(rng));
        match self.dead_reckoning() {
            None => fix(self.gps_sd_m(), gps),
            Some(d) if surfaced => fix(d.surfacing.map_or(0.0, |s| s.gps_sd_m), gps),
            Some(d) => {
                let sd = (d.diffusion_m2_s * dt).sqrt();
                (previous.0 + sd * normal(walk), previous.1 + sd * normal(walk))
            }
        }
    }

    fn gps_sd_m(&self) -> f64 {
        match self {
            CnaNavigation::Gps(g) => g.sd_m,
            _ => 0.0,
        }
    }

    /// What its broadcast position adds to its true one, given its position error: the error,
    /// or nothing for the counterfactual `exact`.
    pub fn broadcast_error(&self, error: (f64, f64)) -> (f64, f64) {
        match self {
            CnaNavigation::Exact(_) => (0.0, 0.0),
            CnaNavigation::Gps(_) | CnaNavigation::DeadReckoning(_) => error,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::surfacing::SurfaceWhen;
    use rand::SeedableRng;

    #[derive(Debug, Serialize, Deserialize)]
    struct File {
        navigation: CnaNavigation,
    }

    fn parse(text: &str) -> Result<CnaNavigation, String> {
        toml::from_str::<File>(text).map(|f| f.navigation).map_err(|e| e.to_string())
    }

    #[test]
    fn each_kind_reads_its_own_fields_and_refuses_others() {
        assert_eq!(parse("navigation = { kind = \"gps\" }").unwrap(), CnaNavigation::Gps(Gps { sd_m: 1.0 }));
        assert_eq!(
            parse("navigation = { kind = \"gps\", sd_m = 3.0 }").unwrap(),
            CnaNavigation::Gps(Gps { sd_m: 3.0 })
        );
        let dr = parse(
            "navigation = { kind = \"dead-reckoning\", diffusion_m2_s = 0.01, surfacing = { when = { kind = \
             \"sigma\", sigma_m = 3.0 }, fix_time_s = 60.0, gps_sd_m = 1.0 } }",
        )
        .unwrap();
        assert_eq!(dr.diffusion_m2_s(), 0.01);
        assert_eq!(dr.surfacing().map(|s| s.when), Some(SurfaceWhen::Sigma { sigma_m: 3.0 }));
        let exact = parse("navigation = { kind = \"exact\", diffusion_m2_s = 0.02 }").unwrap();
        assert_eq!(exact, CnaNavigation::Exact(DeadReckoning { diffusion_m2_s: 0.02, surfacing: None }));
        let e = parse("navigation = { kind = \"gps\", diffusion_m2_s = 0.01 }").unwrap_err();
        assert!(e.contains("unknown field") && e.contains("diffusion_m2_s"), "{e}");
        let e = parse("navigation = { kind = \"dead-reckoning\" }").unwrap_err();
        assert!(e.contains("diffusion_m2_s"), "{e}");
        let e = parse("navigation = { kind = \"usbl\" }").unwrap_err();
        assert!(e.contains("usbl") && e.contains("dead-reckoning"), "{e}");
        for nav in [CnaNavigation::default(), dr, exact] {
            let text = toml::to_string(&File { navigation: nav }).unwrap();
            assert_eq!(parse(&text).unwrap(), nav, "{text}");
            assert!(text.contains(&format!("kind = \"{}\"", nav.kind())), "{text}");
        }
    }

    #[test]
    fn bad_fields_are_named_under_the_prefix() {
        let mut p = Problems::new();
        CnaNavigation::Gps(Gps { sd_m: -1.0 }).check_fields("cna.navigation.", &mut p);
        let bad = Surfacing { when: SurfaceWhen::Period { period_s: 0.0 }, fix_time_s: 1.0, gps_sd_m: 1.0 };
        CnaNavigation::Exact(DeadReckoning { diffusion_m2_s: f64::NAN, surfacing: Some(bad) })
            .check_fields("cna.navigation.", &mut p);
        let text = p.finish().unwrap_err().to_string();
        for field in ["cna.navigation.sd_m", "cna.navigation.diffusion_m2_s", "cna.navigation.surfacing.when.period_s"]
        {
            assert!(text.contains(field), "{field} missing: {text}");
        }
    }

    /// GPS draws a fresh fix from the GPS stream each time; dead reckoning walks on from its
    /// last error on its own stream, and takes a fix of the surfacing σ when surfaced; only
    /// `exact` leaves the error out of the broadcast.
    #[test]
    fn the_error_each_kind_draws_and_broadcasts() {
        let rngs = || (ChaCha8Rng::seed_from_u64(1), ChaCha8Rng::seed_from_u64(2));
        let gps = CnaNavigation::Gps(Gps { sd_m: 2.0 });
        let (mut g, mut w) = rngs();
        let e = gps.error((100.0, 100.0), false, 30.0, &mut g, &mut w);
        let (mut g2, _) = rngs();
        assert_eq!(e, (2.0 * normal(&mut g2), 2.0 * normal(&mut g2)));
        assert_eq!(gps.broadcast_error(e), e);
        assert_eq!(gps.variance(&OwnNav::new(0.0), 1000.0), 4.0);

        let walk = DeadReckoning { diffusion_m2_s: 0.5, surfacing: None };
        let dr = CnaNavigation::DeadReckoning(walk);
        let (mut g, mut w) = rngs();
        let e = dr.error((1.0, -1.0), false, 2.0, &mut g, &mut w);
        let (_, mut w2) = rngs();
        assert_eq!(e, (1.0 + normal(&mut w2), -1.0 + normal(&mut w2)));
        assert_eq!(dr.error((1.0, -1.0), false, 0.0, &mut g, &mut w), (1.0, -1.0), "no time, no step");
        assert_eq!(dr.error((1.0, -1.0), true, 2.0, &mut g, &mut w), (0.0, 0.0), "no surfacing: a σ-0 fix");
        assert_eq!(dr.broadcast_error(e), e);
        assert_eq!(dr.variance(&OwnNav::new(0.5), 10.0), 5.0);

        let exact = CnaNavigation::Exact(walk);
        let (mut g, mut w) = rngs();
        assert_eq!(exact.error((1.0, -1.0), false, 2.0, &mut g, &mut w), e, "the error is still drawn");
        assert_eq!(exact.broadcast_error(e), (0.0, 0.0));
        assert_eq!((exact.diffusion_m2_s(), gps.diffusion_m2_s()), (0.5, 0.0));
    }
}
