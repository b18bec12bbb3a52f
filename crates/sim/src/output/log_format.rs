//! How the simulated HBL field log is written (Gill 2013, §3.3; docs/models.md#gill-geodesy): positions in metres,
//! or as latitude/longitude about a geodetic origin like the field logs, optionally with the buoy
//! fixes rounded the way the UI AUV's Rabbit stored them (float32, maybe one more bit lost).

use coopnav_core::{Geodetic, LatLonStorage, LocalFrame};
use serde::{Deserialize, Serialize};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum LogFormatError {
    #[error("buoy fix storage {0:?} needs a geodetic origin (the rounding happens in latitude/longitude); give the origin or store \"f64\"")]
    StorageWithoutOrigin(LatLonStorage),
}

/// How `coopnav hbl simulate` writes its log (the `--log-format` file).
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
    pub fn validate(&self) -> Result<(), LogFormatError> {
        if self.buoy_fix_storage != LatLonStorage::F64 && self.geodetic_origin.is_none() {
            return Err(LogFormatError::StorageWithoutOrigin(self.buoy_fix_storage));
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
    use coopnav_core::LatLon;

    fn geodetic(storage: LatLonStorage) -> LogFormat {
        let origin = Geodetic::new(LatLon::new(47.97, -116.5).unwrap(), 0.0).unwrap();
        LogFormat { geodetic_origin: Some(origin), buoy_fix_storage: storage }
    }

    #[test]
    fn storage_without_an_origin_is_rejected() {
        let bare = LogFormat { geodetic_origin: None, buoy_fix_storage: LatLonStorage::F32 };
        let e = bare.validate().unwrap_err().to_string();
        assert!(e.contains("F32") && e.contains("geodetic origin"), "{e}");
        geodetic(LatLonStorage::F32LostBit).validate().unwrap();
        LogFormat::default().validate().unwrap();
    }

    #[test]
    fn stored_fixes_land_on_the_float32_grid() {
        let log = geodetic(LatLonStorage::F32);
        let f = log.frame().unwrap();
        let (e, n) = log.stored_buoy_fix(20.3, 80.1);
        // Moved by at most half a grid step (0.285 m E, 0.212 m N), and exactly onto f32 values.
        assert!((e - 20.3).abs() <= 0.29 && (n - 80.1).abs() <= 0.22, "{e} {n}");
        let ll = f.from_plane(e, n).unwrap();
        assert!((ll.lat_deg() - f64::from(ll.lat_deg() as f32)).abs() < 1e-11, "{}", ll.lat_deg());
        assert!((ll.lon_deg() - f64::from(ll.lon_deg() as f32)).abs() < 1e-11, "{}", ll.lon_deg());
        assert_eq!(LogFormat::default().stored_buoy_fix(20.3, 80.1), (20.3, 80.1));
    }
}
