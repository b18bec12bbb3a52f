//! Buoys as transponder vehicles (Gill's hybrid baseline, Gill 2013, §1.4 and §2.4.1): a buoy
//! floats at a known GPS position, moored or drifting, and broadcasts that position in its own
//! slot of the schedule; every survey AUV that decodes it applies the one-way travel time as a
//! range, beside the CNA's. The spec (`[[buoys]]`) and its validation live here; the engine's
//! buoy vehicle is in `engine/vehicles.rs`.

use super::minipacket::check_zone;
use crate::models::noise::{BuoyMotion, LakeDrift};
use coopnav_acomms::Rate;
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_nav::codec::Zone;
use coopnav_nav::SurfaceParams;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// One `[[buoys]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuoySpec {
    /// Deployment position, m (the survey frame: x east, y north).
    pub x: f64,
    pub y: f64,
    #[serde(default)]
    pub drift: Drift,
    /// Depth of its modem's transducer, m (a surface buoy's hangs just below the waves).
    #[serde(default = "default_modem_depth")]
    pub modem_depth_m: f64,
    /// SD of its broadcast GPS position per axis, m (Gill's DGPS, Gill 2013, §2.4.1: 0.1 m).
    #[serde(default = "default_gps_sd")]
    pub gps_sd_m: f64,
    /// WHOI rate of its position broadcast (default 0, the most robust).
    #[serde(default = "default_rate")]
    pub rate: Rate,
    /// Quantisation zone of its East/North mini-packets (a `gill_cycle` or a `tdma` slot with a
    /// `message`); default: Gill's 1.6 m × 0.6 m boxes centred on its deployment position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zone: Option<Zone>,
    /// The buoy filter every survey AUV runs from its mini-packets (Gill 2013, §2.2.2 and Table 3).
    #[serde(default = "SurfaceParams::buoy")]
    pub filter: SurfaceParams,
}

/// How a buoy moves: moored, a constant drift, or Gill's lake statistics drawn per run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Drift {
    #[default]
    Moored,
    Constant {
        velocity_m_s: [f64; 2],
    },
    /// Lake Pend Oreille statistics (Gill 2013, §2.4.1): a drift of 0.056 ± 0.039 m/s, straight or
    /// on a large circle (the split and the radius invented: docs/models.md#gill-buoy-drift).
    Lake(LakeDrift),
}

fn default_modem_depth() -> f64 {
    1.0
}

fn default_gps_sd() -> f64 {
    0.1
}

fn default_rate() -> Rate {
    Rate::R0
}

/// Most buoys a scenario may deploy.
pub const MAX_BUOYS: usize = 8;

impl BuoySpec {
    /// The zone its mini-packets are quantised in.
    pub fn zone(&self) -> Zone {
        self.zone.unwrap_or_else(|| Zone::centred(self.x, self.y, 1.6, 0.6))
    }

    /// Its true trajectory for one run (a lake drift draws from `rng`, its own stream).
    pub fn motion(&self, rng: &mut ChaCha8Rng) -> BuoyMotion {
        let p0 = [self.x, self.y];
        match self.drift {
            Drift::Moored => BuoyMotion::moored(p0),
            Drift::Constant { velocity_m_s } => BuoyMotion::Linear { p0, v: velocity_m_s },
            Drift::Lake(s) => BuoyMotion::lake(p0, &s, rng),
        }
    }
}

impl CheckFields for BuoySpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let mut need =
            |field: &str, v: f64, ok: bool, allowed: &str| p.require(&format!("{prefix}{field}"), v, ok, allowed);
        need("x", self.x, true, "a finite number");
        need("y", self.y, true, "a finite number");
        need("modem_depth_m", self.modem_depth_m, (0.0..=100.0).contains(&self.modem_depth_m), "0..=100 m");
        need("gps_sd_m", self.gps_sd_m, (0.0..=100.0).contains(&self.gps_sd_m), "0..=100 m");
        match self.drift {
            Drift::Moored => {}
            Drift::Constant { velocity_m_s: [ve, vn] } => {
                let speed = ve.hypot(vn);
                need("drift.velocity_m_s", speed, speed <= 2.0, "a drift of at most 2 m/s");
            }
            Drift::Lake(s) => {
                need("drift.mean_m_s", s.mean_m_s, (0.0..=2.0).contains(&s.mean_m_s), "0..=2 m/s");
                need("drift.sd_m_s", s.sd_m_s, (0.0..=2.0).contains(&s.sd_m_s), "0..=2 m/s");
                let f = s.circular_fraction;
                need("drift.circular_fraction", f, (0.0..=1.0).contains(&f), "a probability in [0, 1]");
                need("drift.circular_radius_m", s.circular_radius_m, s.circular_radius_m > 0.0, "a number > 0 m");
            }
        }
        if let Some(zone) = &self.zone {
            check_zone(&format!("{prefix}zone."), zone, p);
        }
        if self.rate.spec().deprecated {
            p.push(format!("{prefix}rate"), self.rate.to_string(), "0, 1, 4 or 5 (rates 2 and 3 are deprecated)");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::SeedStream;

    fn spec(drift: Drift) -> BuoySpec {
        toml::from_str::<BuoySpec>("x = 100.0\ny = 200.0").map(|b| BuoySpec { drift, ..b }).unwrap()
    }

    #[test]
    fn a_moored_buoy_stays_and_a_drifting_one_moves_at_its_speed() {
        let rng = || SeedStream::new(4).rng(1);
        assert_eq!(spec(Drift::Moored).motion(&mut rng()).at(3600.0), [100.0, 200.0]);
        let constant = spec(Drift::Constant { velocity_m_s: [0.03, -0.04] }).motion(&mut rng());
        let p = constant.at(100.0);
        assert!((p[0] - 103.0).abs() < 1e-9 && (p[1] - 196.0).abs() < 1e-9, "{p:?}");
        let lake = LakeDrift { mean_m_s: 0.056, sd_m_s: 0.0, circular_fraction: 0.0, circular_radius_m: 200.0 };
        let m = spec(Drift::Lake(lake)).motion(&mut rng());
        let (a, b) = (m.at(0.0), m.at(100.0));
        assert!(((b[0] - a[0]).hypot(b[1] - a[1]) - 5.6).abs() < 1e-6, "{a:?} -> {b:?}");
    }

    #[test]
    fn bad_buoy_fields_are_named() {
        let mut b = spec(Drift::Constant { velocity_m_s: [3.0, 0.0] });
        (b.modem_depth_m, b.rate) = (-1.0, Rate::new(2).unwrap());
        let fields = b.validate("buoys[1].").unwrap_err().fields();
        assert_eq!(fields, ["buoys[1].modem_depth_m", "buoys[1].drift.velocity_m_s", "buoys[1].rate"]);
        let unknown = toml::from_str::<BuoySpec>("x = 1.0\ny = 2.0\ndrift = { kind = \"anchored\" }");
        assert!(unknown.unwrap_err().to_string().contains("anchored"));
    }
}
