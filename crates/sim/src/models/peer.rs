//! The survey AUVs' status messages as Nams (2014) runs them: who hears a status (`comms.status_to`:
//! the CNA only, or the CNA and every other survey AUV) and what its frame 0 carries
//! (`comms.status_format`): the Appendix C node report with its covariance trailer (rate feedback
//! from the CNA's one-bit acks), or Nams's frame 0 — the packet-success tracker's header, then the
//! thesis status message (rate feedback from the peers' headers; each AUV keeps a shadow estimate
//! of every other, Nams 2014, §5.1–5.2).

use coopnav_acomms::status::{Frame0, NextWaypoint, StatusMessage};
use coopnav_acomms::tracker::{MaskWidth, TrackingHeader};
use coopnav_acomms::Rate;
use coopnav_core::{Heading, Vec3};
use serde::{Deserialize, Serialize};

/// Who a survey AUV's status message is addressed to (every vehicle hears it as interference
/// whatever this says).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StatusTo {
    #[default]
    Cna,
    /// The CNA and every other survey AUV, each with its own channel draw (Nams's two vehicles).
    CnaAndAuvs,
}

/// How the collaborator's position is estimated, and so what a Nams status says of the next
/// waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorMode {
    /// Mission plans known to both (status carries a 1-byte waypoint id).
    PrePlanned,
    /// Plans unknown (status carries the next waypoint's lat/lon; the shadow stops there).
    Dynamic,
}

/// What a survey AUV's status packet carries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum StatusFormat {
    /// The Appendix C node report and the covariance trailer.
    #[default]
    NodeReport,
    /// Nams's frame 0: tracking header, then the thesis status message.
    NamsFrame0 { estimator: EstimatorMode },
}

impl StatusFormat {
    /// Smallest frame 0 a status needs (empty header), bytes: what every status rate must hold.
    pub fn nams_frame0_bytes(mode: EstimatorMode, width: MaskWidth) -> usize {
        (TrackingHeader::default().bits(width) + placeholder_status(mode).bits()).div_ceil(8)
    }

    /// A Nams status from what the AUV knows: its estimated position (`pos`), heading and speed,
    /// and its next waypoint (its index in the plan, and where it is as latitude/longitude).
    pub fn nams_status(
        mode: EstimatorMode,
        pos: Vec3,
        heading: Heading,
        speed: f64,
        next: (usize, (f64, f64)),
    ) -> StatusMessage {
        let next = match mode {
            EstimatorMode::PrePlanned => NextWaypoint::Id(next.0.min(254) as u8),
            EstimatorMode::Dynamic => NextWaypoint::LatLon { lat: next.1 .0, lon: next.1 .1 },
        };
        // The message's fields are bounded: depth 0–1000 m, speed 0–5 m/s.
        let pos = Vec3::new(pos.x, pos.y, pos.z.clamp(0.0, 1000.0));
        StatusMessage { pos, heading, speed: speed.clamp(0.0, 5.0), next }
    }

    /// Most header entries a frame of `frame_bytes` holds beside a status in `mode`.
    pub fn max_header_entries(mode: EstimatorMode, frame_bytes: usize, width: MaskWidth) -> usize {
        Frame0::max_header_entries(frame_bytes, placeholder_status(mode).bits(), width)
    }
}

/// A status of the size every status in `mode` has (the encoding's width does not depend on values).
fn placeholder_status(mode: EstimatorMode) -> StatusMessage {
    StatusFormat::nams_status(mode, Vec3::new(0.0, 0.0, 0.0), Heading::from_radians(0.0), 0.0, (0, (0.0, 0.0)))
}

/// The width of the header's frame masks when a vehicle may use `rates`.
pub fn mask_width(rates: &[Rate]) -> MaskWidth {
    MaskWidth::for_rates(rates.iter().copied())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_nams_frame0_fits_rate_0s_frame_and_a_file_names_its_estimator() {
        let pre = StatusFormat::nams_frame0_bytes(EstimatorMode::PrePlanned, MaskWidth::Narrow);
        let dynamic = StatusFormat::nams_frame0_bytes(EstimatorMode::Dynamic, MaskWidth::Narrow);
        assert!(pre < dynamic && dynamic <= Rate::R0.spec().frame_bytes, "{pre} / {dynamic}");
        let f: StatusFormat = toml::from_str("kind = \"nams_frame0\"\nestimator = \"dynamic\"").unwrap();
        assert_eq!(f, StatusFormat::NamsFrame0 { estimator: EstimatorMode::Dynamic });
        assert!(toml::from_str::<StatusFormat>("kind = \"nams_frame0\"\nestimator = \"guess\"").is_err());
    }
}
