//! The status message (position, depth, heading, speed, next waypoint as a 1-byte id or full
//! lat/lon; Nams 2014, §5.1; docs/models.md#nams-status-message) and frame 0, which carries the
//! tracking header and the status message together (docs/models.md#nams-tracker: the header lives
//! in frame 0).
//!
//! Two variants: the thesis-exact [`StatusMessage`] (Appendix C), and the versioned
//! [`CovStatus`] (ours, docs/models.md#estimator-cost), which starts with a 3-bit version (1) and adds the sender's
//! horizontal position covariance as an error ellipse ([`CovarianceReport`], 3 bytes), so a CNA
//! can plan on the survey AUVs' own estimators. Both travel in a frame 0 through the same
//! [`StatusCodec`] trait. [`CovTrailer`] carries the same version and ellipse in 4 bytes after
//! another message (the closed loop's Appendix C node report).

use crate::codec::{BitReader, BitWriter, Bounded, DecodeError, EncodeError};
use crate::tracker::{MaskWidth, TrackingHeader};
use coopnav_core::{CompassDeg, Heading, Vec3};
use serde::{Deserialize, Serialize};

const X: Bounded = Bounded::new("status.x_dm", -200_000, 200_000);
const Y: Bounded = Bounded::new("status.y_dm", -200_000, 200_000);
const DEPTH: Bounded = Bounded::new("status.depth_dm", 0, 10_000);
const HEADING: Bounded = Bounded::new("status.heading_decideg", 0, 3599);
const SPEED: Bounded = Bounded::new("status.speed_cm_s", 0, 500);
const WP_ID: Bounded = Bounded::new("status.next_wp_id", 0, 254);
const LAT: Bounded = Bounded::new("status.next_wp_lat_1e5", -9_000_000, 9_000_000);
const LON: Bounded = Bounded::new("status.next_wp_lon_1e5", -18_000_000, 18_000_000);
const EARTH_RADIUS: f64 = 6_371_000.0;

/// Flat-earth map between the local frame and latitude/longitude around an origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalOrigin {
    pub lat_deg: f64,
    pub lon_deg: f64,
}

impl Default for LocalOrigin {
    /// Bedford Basin, Halifax (the thesis's site).
    fn default() -> Self {
        LocalOrigin { lat_deg: 44.69, lon_deg: -63.63 }
    }
}

impl LocalOrigin {
    pub fn to_latlon(&self, x: f64, y: f64) -> (f64, f64) {
        let lat = self.lat_deg + (y / EARTH_RADIUS).to_degrees();
        let lon = self.lon_deg + (x / (EARTH_RADIUS * self.lat_deg.to_radians().cos())).to_degrees();
        (lat, lon)
    }
    pub fn to_local(&self, lat: f64, lon: f64) -> (f64, f64) {
        let y = (lat - self.lat_deg).to_radians() * EARTH_RADIUS;
        let x = (lon - self.lon_deg).to_radians() * EARTH_RADIUS * self.lat_deg.to_radians().cos();
        (x, y)
    }
}

/// Where the vehicle is heading next.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum NextWaypoint {
    /// Index into a mission plan the receiver knows (pre-planned mode).
    Id(u8),
    /// Full position (dynamic mode), degrees.
    LatLon { lat: f64, lon: f64 },
}

/// A collaborator's self-report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatusMessage {
    pub pos: Vec3,
    pub heading: Heading,
    pub speed: f64,
    pub next: NextWaypoint,
}

fn q(v: f64, scale: f64, f: Bounded) -> Result<i64, EncodeError> {
    let c = (v * scale).round();
    if !c.is_finite() || c < f.min as f64 || c > f.max as f64 {
        return Err(EncodeError {
            field: f.name,
            value: if c.is_finite() { c as i64 } else { i64::MAX },
            min: f.min,
            max: f.max,
        });
    }
    Ok(c as i64)
}

impl StatusMessage {
    pub fn bits(&self) -> usize {
        let fixed = [X, Y, DEPTH, HEADING, SPEED].iter().map(|f| f.bits() as usize).sum::<usize>() + 1;
        fixed
            + match self.next {
                NextWaypoint::Id(_) => WP_ID.bits() as usize,
                NextWaypoint::LatLon { .. } => (LAT.bits() + LON.bits()) as usize,
            }
    }

    pub fn encode_into(&self, w: &mut BitWriter) -> Result<(), EncodeError> {
        w.put(X, q(self.pos.x, 10.0, X)?)?;
        w.put(Y, q(self.pos.y, 10.0, Y)?)?;
        w.put(DEPTH, q(self.pos.z, 10.0, DEPTH)?)?;
        // Rounding 359.96° gives 3600: wrap it to 0 before the bounds check.
        let compass = (CompassDeg::from(self.heading).0 * 10.0).round().rem_euclid(3600.0);
        w.put(HEADING, q(compass, 1.0, HEADING)?)?;
        w.put(SPEED, q(self.speed, 100.0, SPEED)?)?;
        match self.next {
            NextWaypoint::Id(id) => {
                w.put_bool(false);
                w.put(WP_ID, id as i64)?;
            }
            NextWaypoint::LatLon { lat, lon } => {
                w.put_bool(true);
                w.put(LAT, q(lat, 1e5, LAT)?)?;
                w.put(LON, q(lon, 1e5, LON)?)?;
            }
        }
        Ok(())
    }

    pub fn decode_from(r: &mut BitReader<'_>) -> Result<Self, DecodeError> {
        let x = r.get(X)? as f64 / 10.0;
        let y = r.get(Y)? as f64 / 10.0;
        let z = r.get(DEPTH)? as f64 / 10.0;
        let heading = Heading::from(CompassDeg(r.get(HEADING)? as f64 / 10.0));
        let speed = r.get(SPEED)? as f64 / 100.0;
        let next = if r.get_bool("status.next_wp_kind")? {
            NextWaypoint::LatLon { lat: r.get(LAT)? as f64 / 1e5, lon: r.get(LON)? as f64 / 1e5 }
        } else {
            NextWaypoint::Id(r.get(WP_ID)? as u8)
        };
        Ok(StatusMessage { pos: Vec3::new(x, y, z), heading, speed, next })
    }
}

/// A status-message variant that frame 0 can carry.
pub trait StatusCodec: Sized {
    fn encode_into(&self, w: &mut BitWriter) -> Result<(), EncodeError>;
    fn decode_from(r: &mut BitReader<'_>) -> Result<Self, DecodeError>;
}

impl StatusCodec for StatusMessage {
    fn encode_into(&self, w: &mut BitWriter) -> Result<(), EncodeError> {
        StatusMessage::encode_into(self, w)
    }
    fn decode_from(r: &mut BitReader<'_>) -> Result<Self, DecodeError> {
        StatusMessage::decode_from(r)
    }
}

/// Frame 0 of every packet: tracking header then a status message of variant `S`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StatusFrame<S> {
    pub header: TrackingHeader,
    pub status: S,
}

/// The thesis-exact frame 0.
pub type Frame0 = StatusFrame<StatusMessage>;
/// Frame 0 with the versioned covariance status.
pub type CovFrame0 = StatusFrame<CovStatus>;

impl<S: StatusCodec> StatusFrame<S> {
    /// Encodes into at most `frame_bytes` bytes.
    pub fn encode(&self, w: MaskWidth, frame_bytes: usize) -> Result<Vec<u8>, EncodeError> {
        let mut out = BitWriter::new();
        self.header.encode_into(&mut out, w)?;
        self.status.encode_into(&mut out)?;
        let bytes = out.finish();
        if bytes.len() > frame_bytes {
            return Err(EncodeError { field: "frame0", value: bytes.len() as i64, min: 0, max: frame_bytes as i64 });
        }
        Ok(bytes)
    }

    pub fn decode(bytes: &[u8], w: MaskWidth) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(bytes);
        let header = TrackingHeader::decode_from(&mut r, w)?;
        let status = S::decode_from(&mut r)?;
        r.finish()?;
        Ok(StatusFrame { header, status })
    }
}

impl Frame0 {
    /// Most header entries that fit in a frame of `frame_bytes` next to a status of `status_bits`.
    pub fn max_header_entries(frame_bytes: usize, status_bits: usize, w: MaskWidth) -> usize {
        let empty = TrackingHeader::default().bits(w);
        (frame_bytes * 8).saturating_sub(status_bits + empty) / w.entry_bits()
    }
}

const VERSION: Bounded = Bounded::new("status.version", 0, 6);
/// The version [`CovStatus`] writes (the thesis message has no version field).
const COV_VERSION: i64 = 1;
/// σ codes: σ = SIGMA_FLOOR·exp(code / SIGMA_PER_E), 255 codes from 1 cm to 10 km, 5.6 % apart
/// (so ±2.8 % after rounding). Invented: a ratio scale keeps small and large errors
/// equally precise in one byte.
const SIGMA_MAJOR: Bounded = Bounded::new("status.sigma_major_code", 0, 254);
const SIGMA_MINOR: Bounded = Bounded::new("status.sigma_minor_code", 0, 254);
const SIGMA_FLOOR: f64 = 0.01;
const SIGMA_MAX: f64 = 10_000.0;
/// Orientation of the major axis, whole degrees counter-clockwise from east, [0, 180).
const ORIENTATION: Bounded = Bounded::new("status.orientation_deg", 0, 179);

fn sigma_per_e() -> f64 {
    254.0 / (SIGMA_MAX / SIGMA_FLOOR).ln()
}

/// A horizontal position covariance as an error ellipse: standard deviations along the major
/// and minor axes (m) and the major axis's direction (radians counter-clockwise from east).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CovarianceReport {
    pub sigma_major: f64,
    pub sigma_minor: f64,
    pub orientation: f64,
}

impl CovarianceReport {
    /// The ellipse of the covariance [P_ee, P_en, P_nn] (m²).
    pub fn from_cov(cov: [f64; 3]) -> Self {
        let [a, b, c] = cov;
        let mean = 0.5 * (a + c);
        let radius = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        CovarianceReport {
            sigma_major: (mean + radius).max(0.0).sqrt(),
            sigma_minor: (mean - radius).max(0.0).sqrt(),
            orientation: 0.5 * (2.0 * b).atan2(a - c),
        }
    }

    /// The covariance [P_ee, P_en, P_nn] (m²) of the ellipse.
    pub fn to_cov(&self) -> [f64; 3] {
        let (major, minor) = (self.sigma_major * self.sigma_major, self.sigma_minor * self.sigma_minor);
        let (s, c) = self.orientation.sin_cos();
        [major * c * c + minor * s * s, (major - minor) * s * c, major * s * s + minor * c * c]
    }

    fn encode_into(&self, w: &mut BitWriter) -> Result<(), EncodeError> {
        let code = |sigma: f64, f: Bounded| q((sigma.max(SIGMA_FLOOR) / SIGMA_FLOOR).ln(), sigma_per_e(), f);
        let (major, minor) = (code(self.sigma_major, SIGMA_MAJOR)?, code(self.sigma_minor, SIGMA_MINOR)?);
        if minor > major {
            return Err(EncodeError { field: SIGMA_MINOR.name, value: minor, min: 0, max: major });
        }
        w.put(SIGMA_MAJOR, major)?;
        w.put(SIGMA_MINOR, minor)?;
        let degrees = self.orientation.to_degrees().round().rem_euclid(180.0);
        w.put(ORIENTATION, q(degrees, 1.0, ORIENTATION)?)
    }

    fn decode_from(r: &mut BitReader<'_>) -> Result<Self, DecodeError> {
        let sigma = |code: i64| SIGMA_FLOOR * (code as f64 / sigma_per_e()).exp();
        let (major, minor) = (r.get(SIGMA_MAJOR)?, r.get(SIGMA_MINOR)?);
        if minor > major {
            return Err(DecodeError::Invalid {
                field: SIGMA_MINOR.name,
                message: format!("minor-axis code {minor} above the major-axis code {major}"),
            });
        }
        let orientation = (r.get(ORIENTATION)? as f64).to_radians();
        Ok(CovarianceReport { sigma_major: sigma(major), sigma_minor: sigma(minor), orientation })
    }
}

/// The versioned status message: the thesis's fields, then the sender's covariance ellipse.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CovStatus {
    pub status: StatusMessage,
    pub cov: CovarianceReport,
}

impl CovStatus {
    pub fn bits(&self) -> usize {
        (VERSION.bits() + SIGMA_MAJOR.bits() + SIGMA_MINOR.bits() + ORIENTATION.bits()) as usize + self.status.bits()
    }
}

impl StatusCodec for CovStatus {
    fn encode_into(&self, w: &mut BitWriter) -> Result<(), EncodeError> {
        w.put(VERSION, COV_VERSION)?;
        self.status.encode_into(w)?;
        self.cov.encode_into(w)
    }

    fn decode_from(r: &mut BitReader<'_>) -> Result<Self, DecodeError> {
        let version = r.get(VERSION)?;
        if version != COV_VERSION {
            return Err(DecodeError::Invalid {
                field: VERSION.name,
                message: format!("version {version} is not known (this codec reads version {COV_VERSION})"),
            });
        }
        let status = StatusMessage::decode_from(r)?;
        Ok(CovStatus { status, cov: CovarianceReport::decode_from(r)? })
    }
}

/// The covariance trailer: the same version field (1) and [`CovarianceReport`] as [`CovStatus`],
/// in their own 4 bytes after a complete message (the closed loop appends it to the Appendix C
/// node report, whose bytes stay the thesis's). A receiver that reads only the thesis message
/// stops before it; one that knows version 1 gets the sender's error ellipse.
pub struct CovTrailer;

impl CovTrailer {
    /// Bytes a trailer takes: 3 + 3·8 + 8 bits, padded to whole bytes.
    pub const BYTES: usize = 4;

    pub fn encode(cov: &CovarianceReport) -> Result<Vec<u8>, EncodeError> {
        let mut w = BitWriter::new();
        w.put(VERSION, COV_VERSION)?;
        cov.encode_into(&mut w)?;
        Ok(w.finish())
    }

    /// Reads a trailer of exactly [`Self::BYTES`] bytes (a truncated, padded or other-version
    /// trailer is an error naming the field).
    pub fn decode(bytes: &[u8]) -> Result<CovarianceReport, DecodeError> {
        let mut r = BitReader::new(bytes);
        let version = r.get(VERSION)?;
        if version != COV_VERSION {
            return Err(DecodeError::Invalid {
                field: VERSION.name,
                message: format!("version {version} is not known (this codec reads version {COV_VERSION})"),
            });
        }
        let cov = CovarianceReport::decode_from(&mut r)?;
        r.finish()?;
        Ok(cov)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tracker::HeaderEntry;
    use proptest::prelude::*;

    fn status(next: NextWaypoint) -> StatusMessage {
        StatusMessage { pos: Vec3::new(1234.5, -987.6, 33.3), heading: Heading::from_radians(0.3), speed: 1.54, next }
    }

    #[test]
    fn sizes() {
        assert_eq!(status(NextWaypoint::Id(3)).bits(), 19 + 19 + 14 + 12 + 9 + 1 + 8);
        let ll = status(NextWaypoint::LatLon { lat: 44.7, lon: -63.6 }).bits() - status(NextWaypoint::Id(0)).bits() + 8;
        assert_eq!(ll, 51, "full lat/lon costs about 7 bytes, as in the thesis");
        assert_eq!(Frame0::max_header_entries(32, 125, MaskWidth::Narrow), 11);
    }

    #[test]
    fn latlon_round_trip_is_centimetric() {
        let o = LocalOrigin::default();
        let (lat, lon) = o.to_latlon(1500.0, -700.0);
        let (x, y) = o.to_local(lat, lon);
        assert!((x - 1500.0).abs() < 1e-6 && (y + 700.0).abs() < 1e-6);
    }

    #[test]
    fn out_of_range_and_malformed() {
        let mut bad = status(NextWaypoint::Id(1));
        bad.pos.x = 1e6;
        assert!(bad.encode_into(&mut BitWriter::new()).is_err());
        bad.pos.x = f64::NAN;
        assert!(bad.encode_into(&mut BitWriter::new()).is_err());
        let f = Frame0 { header: TrackingHeader::default(), status: status(NextWaypoint::Id(1)) };
        let b = f.encode(MaskWidth::Narrow, 32).unwrap();
        assert!(Frame0::decode(&b[..b.len() - 2], MaskWidth::Narrow).is_err());
        let big = Frame0 {
            header: TrackingHeader {
                entries: (1..=20).map(|c| HeaderEntry { cycles_ago: c, frames: 1 }).collect(),
                truncated: false,
            },
            ..f
        };
        assert!(big.encode(MaskWidth::Narrow, 32).is_err());
    }

    fn cov_frame(cov: CovarianceReport) -> CovFrame0 {
        CovFrame0 { header: TrackingHeader::default(), status: CovStatus { status: status(NextWaypoint::Id(2)), cov } }
    }

    #[test]
    fn covariance_status_costs_27_bits_more_and_rejects_malformed_frames() {
        let ellipse = CovarianceReport { sigma_major: 3.0, sigma_minor: 1.0, orientation: 0.4 };
        let f = cov_frame(ellipse);
        assert_eq!(f.status.bits(), status(NextWaypoint::Id(2)).bits() + 3 + 8 + 8 + 8);
        let b = f.encode(MaskWidth::Narrow, 32).unwrap();
        assert!(CovFrame0::decode(&b[..b.len() - 1], MaskWidth::Narrow).is_err(), "truncated");
        let mut long = b.clone();
        long.push(0);
        assert!(matches!(CovFrame0::decode(&long, MaskWidth::Narrow), Err(DecodeError::Oversized { .. })));
        // A thesis frame is not a covariance frame and the other way round.
        let thesis = Frame0 { header: TrackingHeader::default(), status: status(NextWaypoint::Id(2)) };
        assert!(CovFrame0::decode(&thesis.encode(MaskWidth::Narrow, 32).unwrap(), MaskWidth::Narrow).is_err());
        assert!(Frame0::decode(&b, MaskWidth::Narrow).is_err());
        // Another version and a minor axis above the major are refused with their field named.
        let hand_made = |version: i64, major: i64, minor: i64| {
            let mut w = BitWriter::new();
            TrackingHeader::default().encode_into(&mut w, MaskWidth::Narrow).unwrap();
            w.put(VERSION, version).unwrap();
            status(NextWaypoint::Id(2)).encode_into(&mut w).unwrap();
            for (f, v) in [(SIGMA_MAJOR, major), (SIGMA_MINOR, minor), (ORIENTATION, 0)] {
                w.put(f, v).unwrap();
            }
            CovFrame0::decode(&w.finish(), MaskWidth::Narrow).map_err(|e| e.to_string())
        };
        assert!(hand_made(1, 11, 10).is_ok());
        let e = hand_made(2, 11, 10).unwrap_err();
        assert!(e.contains("status.version") && e.contains("version 2"), "{e}");
        let e = hand_made(1, 10, 11).unwrap_err();
        assert!(e.contains("status.sigma_minor_code"), "{e}");
        let huge = CovarianceReport { sigma_major: 2e4, ..ellipse };
        assert!(cov_frame(huge).encode(MaskWidth::Narrow, 32).is_err());
    }

    #[test]
    fn the_covariance_trailer_round_trips_in_four_bytes_and_rejects_malformed_ones() {
        let ellipse = CovarianceReport { sigma_major: 25.0, sigma_minor: 0.4, orientation: 1.2 };
        let b = CovTrailer::encode(&ellipse).unwrap();
        assert_eq!(b.len(), CovTrailer::BYTES);
        let back = CovTrailer::decode(&b).unwrap();
        // Log-spaced codes: 254 steps over six decades, about 2.8 % per step.
        assert!((back.sigma_major / 25.0 - 1.0).abs() < 0.03 && (back.sigma_minor / 0.4 - 1.0).abs() < 0.03);
        assert!((back.orientation - 1.2f64.to_degrees().round().to_radians()).abs() < 1e-12);
        assert!(matches!(CovTrailer::decode(&b[..3]), Err(DecodeError::Truncated { .. })));
        let mut long = b.clone();
        long.push(0);
        assert!(matches!(CovTrailer::decode(&long), Err(DecodeError::Oversized { .. })));
        let mut other = BitWriter::new();
        other.put(VERSION, 2).unwrap();
        ellipse.encode_into(&mut other).unwrap();
        let e = CovTrailer::decode(&other.finish()).unwrap_err().to_string();
        assert!(e.contains("status.version") && e.contains("version 2"), "{e}");
        assert!(CovTrailer::encode(&CovarianceReport { sigma_major: 2e4, ..ellipse }).is_err());
    }

    fn cov_frame_thesis(f: &CovFrame0) -> Frame0 {
        Frame0 { header: f.header.clone(), status: f.status.status }
    }

    #[test]
    fn an_ellipse_and_its_covariance_agree() {
        // Major axis 3 m along 30°, minor 1 m: P = R diag(9, 1) Rᵀ.
        let e = CovarianceReport { sigma_major: 3.0, sigma_minor: 1.0, orientation: 30f64.to_radians() };
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let p = e.to_cov();
        let want = [9.0 * c * c + s * s, 8.0 * s * c, 9.0 * s * s + c * c];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < 1e-12);
        }
        let back = CovarianceReport::from_cov(p);
        assert!((back.sigma_major - 3.0).abs() < 1e-12 && (back.sigma_minor - 1.0).abs() < 1e-12);
        assert!((back.orientation - 30f64.to_radians()).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn covariance_frame_round_trip(major in 0.01f64..9_000.0, ratio in 0.0f64..1.0, angle in -3.2f64..3.2) {
            let cov = CovarianceReport { sigma_major: major, sigma_minor: major * ratio, orientation: angle };
            let f = cov_frame(cov);
            let b = f.encode(MaskWidth::Narrow, 64).unwrap();
            let d = CovFrame0::decode(&b, MaskWidth::Narrow).unwrap();
            prop_assert_eq!(d.status.status, Frame0::decode(&cov_frame_thesis(&f).encode(MaskWidth::Narrow, 64).unwrap(), MaskWidth::Narrow).unwrap().status);
            let rel = |got: f64, want: f64| (got / want.max(SIGMA_FLOOR)).ln().abs();
            prop_assert!(rel(d.status.cov.sigma_major, major) <= 0.5 / sigma_per_e() + 1e-9);
            prop_assert!(major * ratio < SIGMA_FLOOR || rel(d.status.cov.sigma_minor, major * ratio) <= 0.5 / sigma_per_e() + 1e-9);
            // Orientation is modulo 180°, to the nearest degree.
            let turn = (d.status.cov.orientation - angle).rem_euclid(std::f64::consts::PI);
            prop_assert!(turn.min(std::f64::consts::PI - turn) <= 0.5f64.to_radians() + 1e-9);
            prop_assert_eq!(d.encode(MaskWidth::Narrow, 64).unwrap(), b);
        }

        #[test]
        fn frame0_round_trip(x in -19_999.0f64..19_999.0, y in -19_999.0f64..19_999.0, z in 0.0f64..999.0,
                             h in -std::f64::consts::PI..std::f64::consts::PI, s in 0.0f64..5.0, id in 0u8..=254, ll in any::<bool>(),
                             n in 0usize..11) {
            let o = LocalOrigin::default();
            let (lat, lon) = o.to_latlon(x, y);
            let next = if ll { NextWaypoint::LatLon { lat, lon } } else { NextWaypoint::Id(id) };
            let st = StatusMessage { pos: Vec3::new(x, y, z), heading: Heading::from_radians(h), speed: s, next };
            let header = TrackingHeader { entries: (1..=n as u8).map(|c| HeaderEntry { cycles_ago: c * 3, frames: 1 + u16::from(c % 7) }).collect(), truncated: n == 10 };
            let f = Frame0 { header, status: st };
            let b = f.encode(MaskWidth::Narrow, 32).unwrap();
            let d = Frame0::decode(&b, MaskWidth::Narrow).unwrap();
            prop_assert_eq!(&d.header, &f.header);
            prop_assert!((d.status.pos - st.pos).abs().max() <= 0.05 + 1e-9);
            prop_assert!(d.status.heading.turn_to(st.heading).abs() <= 0.051f64.to_radians());
            prop_assert!((d.status.speed - s).abs() <= 0.005 + 1e-9);
            // Re-encoding the decoded message reproduces the bytes exactly.
            prop_assert_eq!(d.encode(MaskWidth::Narrow, 32).unwrap(), b);
        }
    }
}
