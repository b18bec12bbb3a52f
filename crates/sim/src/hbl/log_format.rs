//! How the simulated HBL field log is written (gill digest §6.4, §10 A28): positions in metres,
//! or as latitude/longitude about a geodetic origin like the field logs, optionally with the buoy
//! fixes rounded the way the UI AUV's Rabbit stored them (float32, maybe one more bit lost).

use super::config::ConfigError;
use coopnav_core::{Geodetic, LatLonStorage, LocalFrame};
use serde::{Deserialize, Serialize};

/// The scenario's `[log]` section.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogFormat {
    /// Write the position rows as `_ll` latitude/longitude about this origin (the simulation's
    /// (0, 0)); metres when absent. Post-process with the same `origin` in the config.
    pub geodetic_origin: Option<Geodetic>,
    /// How the logged buoy fixes were stored before logging; anything but `f64` needs
    /// `geodetic_origin`, since the rounding happens in degrees.
    pub buoy_fix_storage: LatLonStorage,
}

impl LogFormat {
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.buoy_fix_storage != LatLonStorage::F64 && self.geodetic_origin.is_none() {
            return Err(ConfigError::LogStorage(self.buoy_fix_storage));
        }
        Ok(())
    }

    /// The local frame of the `_ll` rows, if the log is geodetic.
    pub fn frame(&self) -> Option<LocalFrame> {
        self.geodetic_origin.map(LocalFrame::new)
    }

    /// A buoy fix (east, north) as the logging device stored it, back in metres.
    pub fn stored_buoy_fix(&self, e: f64, n: f64) -> (f64, f64) {
        let Some(frame) = self.frame().filter(|_| self.buoy_fix_storage != LatLonStorage::F64) else {
            return (e, n);
        };
        match frame.from_plane(e, n) {
            Ok(ll) => frame.to_plane(self.buoy_fix_storage.store(ll)),
            Err(err) => {
                tracing::warn!("buoy fix left unrounded: {err}");
                (e, n)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hbl::Scenario;

    #[test]
    fn storage_without_an_origin_is_rejected() {
        let e = Scenario::from_toml("[log]\nbuoy_fix_storage = \"f32\"\n").unwrap_err().to_string();
        assert!(e.contains("log.buoy_fix_storage") && e.contains("log.geodetic_origin"), "{e}");
        let e = Scenario::from_toml("[log]\ngeodetic_origin = { lat_deg = 91.0, lon_deg = 0.0 }\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("latitude 91"), "{e}");
        let e = Scenario::from_toml("[log]\nf32 = true\n").unwrap_err().to_string();
        assert!(e.contains("f32"), "{e}");
        let sc = Scenario::from_toml(
            "[log]\ngeodetic_origin = { lat_deg = 47.97, lon_deg = -116.5 }\nbuoy_fix_storage = \"f32_lost_bit\"\n",
        )
        .unwrap();
        assert_eq!(sc.log.buoy_fix_storage, LatLonStorage::F32LostBit);
    }

    #[test]
    fn stored_fixes_land_on_the_float32_grid() {
        let sc = Scenario::from_toml(
            "[log]\ngeodetic_origin = { lat_deg = 47.97, lon_deg = -116.5 }\nbuoy_fix_storage = \"f32\"\n",
        )
        .unwrap();
        let f = sc.log.frame().unwrap();
        let (e, n) = sc.log.stored_buoy_fix(20.3, 80.1);
        // Moved by at most half a grid step (0.285 m E, 0.212 m N), and exactly onto f32 values.
        assert!((e - 20.3).abs() <= 0.29 && (n - 80.1).abs() <= 0.22, "{e} {n}");
        let ll = f.from_plane(e, n).unwrap();
        assert!((ll.lat_deg() - f64::from(ll.lat_deg() as f32)).abs() < 1e-11, "{}", ll.lat_deg());
        assert!((ll.lon_deg() - f64::from(ll.lon_deg() as f32)).abs() < 1e-11, "{}", ll.lon_deg());
        assert_eq!(LogFormat::default().stored_buoy_fix(20.3, 80.1), (20.3, 80.1));
    }
}
