//! The status message (position, depth, heading, speed, next waypoint as a 1-byte id or full
//! lat/lon; nams digest §3.2 and §8 item 27) and frame 0, which carries the tracking header and
//! the status message together (digest §8 item 17: the header lives in frame 0).

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

/// Frame 0 of every packet: tracking header then status message.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Frame0 {
    pub header: TrackingHeader,
    pub status: StatusMessage,
}

impl Frame0 {
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
        let status = StatusMessage::decode_from(&mut r)?;
        r.finish()?;
        Ok(Frame0 { header, status })
    }

    /// Most header entries that fit in a frame of `frame_bytes` next to a status of `status_bits`.
    pub fn max_header_entries(frame_bytes: usize, status_bits: usize, w: MaskWidth) -> usize {
        let empty = TrackingHeader::default().bits(w);
        (frame_bytes * 8).saturating_sub(status_bits + empty) / w.entry_bits()
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

    proptest! {
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
