//! The survey AUV's status message of Hudson (2012) Appendix C, "SURVEY_STATUS": a NODE_REPORT
//! (position, speed, heading, depth, altitude), the next three waypoints and health data, packed
//! bit-exactly with the DCCL-style bounded fields of [`crate::codec`]
//! (docs/models.md#hudson-status-message).
//!
//! Body: 176 bits = 22 bytes, field by field as the thesis's listing. Header (ours; DCCL1 header
//! byte-compatibility is not kept): message id (61), source modem id and the time of day
//! in whole seconds, 31 bits. Total 207 bits = 26 bytes, within the 32-byte rate-0 frame (the
//! thesis reports 27 of 32 bytes with the DCCL1 header).
//!
//! Waypoints carry no depth. Appendix C has no null value; a waypoint slot that the AUV cannot
//! fill (fewer than three left) is sent as the code one below the field minimum, which costs no
//! extra bit (32 002 states still fit 15 bits). Headings are compass degrees on the wire and math
//! radians in [`NodeReport`].

use crate::codec::{BitReader, BitWriter, Bounded, DecodeError, EncodeError};
use coopnav_core::{CompassDeg, Heading};

/// Message id of SURVEY_STATUS (Appendix C header `id 61`).
pub const MESSAGE_ID: i64 = 61;
/// Largest encoded size, bytes (the thesis's `size 32`).
pub const MAX_BYTES: usize = 32;

const ID: Bounded = Bounded::new("id", MESSAGE_ID, MESSAGE_ID + 63);
const SRC: Bounded = Bounded::new("src_id", 0, 31);
const TIME: Bounded = Bounded::new("time", 0, 86_399);
const TYPE: Bounded = Bounded::new("type", 0, 5);
const NAV_X: Bounded = Bounded::new("nav_x", -16_000, 16_000);
const NAV_Y: Bounded = Bounded::new("nav_y", -16_000, 16_000);
const SPEED: Bounded = Bounded::new("speed", -20, 90);
const HEADING: Bounded = Bounded::new("heading", 0, 360);
const WAYPOINT: [Bounded; 6] = [
    Bounded::new("x1", -16_001, 16_000),
    Bounded::new("y1", -16_001, 16_000),
    Bounded::new("x2", -16_001, 16_000),
    Bounded::new("y2", -16_001, 16_000),
    Bounded::new("x3", -16_001, 16_000),
    Bounded::new("y3", -16_001, 16_000),
];
const NO_WAYPOINT: i64 = -16_001;
const FRONT_ERROR: Bounded = Bounded::new("front_seat_error", 0, 14);
const FRONT_MODE: Bounded = Bounded::new("front_mode", 0, 4);
const DEPTH: Bounded = Bounded::new("depth", -10, 2030);
const ALTITUDE: Bounded = Bounded::new("altitude", -10, 2030);
const BATTERY: Bounded = Bounded::new("battery", 0, 100);

/// VEHICLE_TYPE (Appendix C enum, in its order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VehicleType {
    Asc,
    Auv,
    Ship,
    Buoy,
    Glider,
    Unknown,
}

const TYPES: [VehicleType; 6] = [
    VehicleType::Asc,
    VehicleType::Auv,
    VehicleType::Ship,
    VehicleType::Buoy,
    VehicleType::Glider,
    VehicleType::Unknown,
];

/// One SURVEY_STATUS message in SI units, as quantised on the wire.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeReport {
    pub src_id: u8,
    /// Seconds since midnight, whole seconds.
    pub time_of_day: u32,
    pub vehicle: VehicleType,
    /// NAV_X, NAV_Y: metres, whole metres, within ±16 000 m.
    pub x: f64,
    pub y: f64,
    /// m/s, 0.1 m/s steps, −2…9.
    pub speed: f64,
    /// Math heading (rad); sent as whole compass degrees.
    pub heading: Heading,
    /// Up to three next waypoints (x, y), whole metres.
    pub waypoints: Vec<(f64, f64)>,
    /// FRONTSEAT_ERROR index 0..=14 (n, e, m, sop, …, sti).
    pub front_seat_error: u8,
    /// FRONTSEAT_MODE index 0..=4 (normal, manual_override, servo, stopped, manual_park).
    pub front_mode: u8,
    pub leak: bool,
    /// Metres, 0.1 m steps, −1…203.
    pub depth: f64,
    pub altitude: f64,
    /// Percent, whole, 0…100.
    pub battery: f64,
}

fn put(w: &mut BitWriter, f: Bounded, v: f64, scale: f64) -> Result<(), EncodeError> {
    let q = (v * scale).round();
    // A NaN or a value beyond i64 is reported as the field's out-of-range sentinel.
    let code = if q.is_finite() && q.abs() < 1e15 { q as i64 } else { i64::MIN };
    w.put(f, code)
}

impl NodeReport {
    /// The message as the receiver will decode it (every field rounded to its resolution).
    pub fn quantised(&self) -> Result<NodeReport, EncodeError> {
        let bytes = self.encode()?;
        Ok(Self::decode(&bytes).expect("an encoded message always decodes"))
    }

    /// Packs the message; a value outside its field's range is an error naming the field.
    pub fn encode(&self) -> Result<Vec<u8>, EncodeError> {
        let mut w = BitWriter::new();
        w.put(ID, MESSAGE_ID)?;
        w.put(SRC, self.src_id as i64)?;
        w.put(TIME, self.time_of_day as i64)?;
        let ty = TYPES.iter().position(|t| *t == self.vehicle).unwrap_or(TYPES.len() - 1);
        w.put(TYPE, ty as i64)?;
        put(&mut w, NAV_X, self.x, 1.0)?;
        put(&mut w, NAV_Y, self.y, 1.0)?;
        put(&mut w, SPEED, self.speed, 10.0)?;
        // 360° is a valid code on the wire, but the encoder always sends north as 0°.
        let compass = CompassDeg::from(self.heading).0.rem_euclid(360.0).round() % 360.0;
        put(&mut w, HEADING, compass, 1.0)?;
        if self.waypoints.len() > 3 {
            return Err(EncodeError { field: "waypoints", value: self.waypoints.len() as i64, min: 0, max: 3 });
        }
        for (i, pair) in WAYPOINT.chunks(2).enumerate() {
            match self.waypoints.get(i) {
                Some(&(x, y)) => {
                    // The sentinel is not a position: keep real waypoints inside ±16 000 m.
                    for (f, v) in [(pair[0], x), (pair[1], y)] {
                        let q = v.round();
                        if q.is_nan() || q <= NO_WAYPOINT as f64 {
                            return Err(EncodeError {
                                field: f.name,
                                value: if q.is_finite() { q as i64 } else { i64::MIN },
                                min: -16_000,
                                max: 16_000,
                            });
                        }
                        put(&mut w, f, v, 1.0)?;
                    }
                }
                None => {
                    w.put(pair[0], NO_WAYPOINT)?;
                    w.put(pair[1], NO_WAYPOINT)?;
                }
            }
        }
        w.put(FRONT_ERROR, self.front_seat_error as i64)?;
        w.put(FRONT_MODE, self.front_mode as i64)?;
        w.put_bool(self.leak);
        put(&mut w, DEPTH, self.depth, 10.0)?;
        put(&mut w, ALTITUDE, self.altitude, 10.0)?;
        put(&mut w, BATTERY, self.battery, 1.0)?;
        Ok(w.finish())
    }

    /// Unpacks a message; truncated, oversized or out-of-range input is an error naming the field.
    pub fn decode(bytes: &[u8]) -> Result<NodeReport, DecodeError> {
        if bytes.len() > MAX_BYTES {
            return Err(DecodeError::Oversized { extra: bytes.len() - MAX_BYTES });
        }
        let mut r = BitReader::new(bytes);
        let id = r.get(ID)?;
        if id != MESSAGE_ID {
            return Err(DecodeError::Invalid {
                field: "id",
                message: format!("message id {id} is not SURVEY_STATUS ({MESSAGE_ID})"),
            });
        }
        let src_id = r.get(SRC)? as u8;
        let time_of_day = r.get(TIME)? as u32;
        let vehicle = TYPES[r.get(TYPE)? as usize];
        let x = r.get(NAV_X)? as f64;
        let y = r.get(NAV_Y)? as f64;
        let speed = r.get(SPEED)? as f64 / 10.0;
        let heading = Heading::from(CompassDeg(r.get(HEADING)? as f64));
        let mut waypoints = Vec::with_capacity(3);
        let mut ended = false;
        for pair in WAYPOINT.chunks(2) {
            let (wx, wy) = (r.get(pair[0])?, r.get(pair[1])?);
            match (wx == NO_WAYPOINT, wy == NO_WAYPOINT) {
                (true, true) => ended = true,
                (false, false) if !ended => waypoints.push((wx as f64, wy as f64)),
                _ => {
                    return Err(DecodeError::Invalid {
                        field: pair[0].name,
                        message: "waypoint half-set or set after an empty slot".into(),
                    });
                }
            }
        }
        let front_seat_error = r.get(FRONT_ERROR)? as u8;
        let front_mode = r.get(FRONT_MODE)? as u8;
        let leak = r.get_bool("leak")?;
        let depth = r.get(DEPTH)? as f64 / 10.0;
        let altitude = r.get(ALTITUDE)? as f64 / 10.0;
        let battery = r.get(BATTERY)? as f64;
        r.finish()?;
        Ok(NodeReport {
            src_id,
            time_of_day,
            vehicle,
            x,
            y,
            speed,
            heading,
            waypoints,
            front_seat_error,
            front_mode,
            leak,
            depth,
            altitude,
            battery,
        })
    }
}

/// Bits of the header (id, source, time) and of the Appendix C body.
pub const HEADER_BITS: u32 = ID.bits() + SRC.bits() + TIME.bits();
pub const BODY_BITS: u32 = TYPE.bits()
    + NAV_X.bits()
    + NAV_Y.bits()
    + SPEED.bits()
    + HEADING.bits()
    + 6 * WAYPOINT[0].bits()
    + FRONT_ERROR.bits()
    + FRONT_MODE.bits()
    + 1
    + DEPTH.bits()
    + ALTITUDE.bits()
    + BATTERY.bits();

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample() -> NodeReport {
        NodeReport {
            src_id: 3,
            time_of_day: 43_210,
            vehicle: VehicleType::Auv,
            x: 1234.4,
            y: -987.6,
            speed: 1.46,
            heading: Heading::from(CompassDeg(271.2)),
            waypoints: vec![(1500.0, -900.0), (1500.0, -400.0)],
            front_seat_error: 0,
            front_mode: 0,
            leak: false,
            depth: 12.34,
            altitude: 7.0,
            battery: 88.0,
        }
    }

    #[test]
    fn layout_is_the_thesis_listing() {
        assert_eq!(BODY_BITS, 176, "Appendix C body: 22 bytes");
        assert_eq!(HEADER_BITS, 7 + 6 + 17);
        let bytes = sample().encode().unwrap();
        assert_eq!(bytes.len(), ((HEADER_BITS + BODY_BITS) as usize).div_ceil(8));
        assert!(bytes.len() <= MAX_BYTES);
        // The first field is the message id: code 61 − 61 + 1 = 1, LSB first.
        assert_eq!(bytes[0] & 0x7f, 1);
    }

    #[test]
    fn quantisation_rounds_each_field() {
        let q = sample().quantised().unwrap();
        assert_eq!((q.x, q.y), (1234.0, -988.0));
        assert!((q.speed - 1.5).abs() < 1e-12);
        assert!((CompassDeg::from(q.heading).0 - 271.0).abs() < 1e-9);
        assert!((q.depth - 12.3).abs() < 1e-12);
        assert_eq!(q.waypoints, vec![(1500.0, -900.0), (1500.0, -400.0)]);
    }

    #[test]
    fn out_of_range_values_name_the_field() {
        let mut m = sample();
        m.x = 16_000.6;
        assert_eq!(m.encode().unwrap_err().field, "nav_x");
        let mut m = sample();
        m.waypoints[1].1 = f64::NAN;
        assert_eq!(m.encode().unwrap_err().field, "y2");
        let mut m = sample();
        m.waypoints = vec![(0.0, 0.0); 4];
        assert_eq!(m.encode().unwrap_err().field, "waypoints");
        let mut m = sample();
        m.speed = 9.5;
        assert_eq!(m.encode().unwrap_err().field, "speed");
    }

    #[test]
    fn malformed_input_is_an_error_never_a_panic() {
        let bytes = sample().encode().unwrap();
        assert!(matches!(NodeReport::decode(&bytes[..10]), Err(DecodeError::Truncated { .. })));
        assert!(matches!(NodeReport::decode(&[]), Err(DecodeError::Truncated { field: "id", .. })));
        let mut long = bytes.clone();
        long.push(0);
        assert!(matches!(NodeReport::decode(&long), Err(DecodeError::Oversized { extra: 1 })));
        assert!(matches!(NodeReport::decode(&[0u8; 40]), Err(DecodeError::Oversized { .. })));
        // Another message id.
        let mut other = bytes.clone();
        other[0] = (other[0] & 0x80) | 5;
        assert!(matches!(NodeReport::decode(&other), Err(DecodeError::Invalid { field: "id", .. })));
        // All-zero body: the id is "not set".
        assert!(matches!(NodeReport::decode(&[0u8; 26]), Err(DecodeError::NotSet { field: "id" })));
    }

    #[test]
    fn a_waypoint_after_an_empty_slot_is_rejected() {
        let mut m = sample();
        m.waypoints = vec![];
        let empty = m.encode().unwrap();
        m.waypoints = vec![(5.0, 6.0)];
        let one = m.encode().unwrap();
        assert_ne!(empty, one);
        assert_eq!(NodeReport::decode(&one).unwrap().waypoints, vec![(5.0, 6.0)]);
        // Build "empty, set" by hand: header 30 bits + type 3 + x,y 30 + speed 7 + heading 9 = 79.
        let mut w = BitWriter::new();
        w.put(ID, MESSAGE_ID).unwrap();
        w.put(SRC, 1).unwrap();
        w.put(TIME, 0).unwrap();
        w.put(TYPE, 1).unwrap();
        w.put(NAV_X, 0).unwrap();
        w.put(NAV_Y, 0).unwrap();
        w.put(SPEED, 0).unwrap();
        w.put(HEADING, 0).unwrap();
        w.put(WAYPOINT[0], NO_WAYPOINT).unwrap();
        w.put(WAYPOINT[1], NO_WAYPOINT).unwrap();
        w.put(WAYPOINT[2], 7).unwrap();
        w.put(WAYPOINT[3], 8).unwrap();
        w.put(WAYPOINT[4], NO_WAYPOINT).unwrap();
        w.put(WAYPOINT[5], NO_WAYPOINT).unwrap();
        w.put(FRONT_ERROR, 0).unwrap();
        w.put(FRONT_MODE, 0).unwrap();
        w.put_bool(false);
        w.put(DEPTH, 0).unwrap();
        w.put(ALTITUDE, 0).unwrap();
        w.put(BATTERY, 0).unwrap();
        assert!(matches!(NodeReport::decode(&w.finish()), Err(DecodeError::Invalid { field: "x2", .. })));
    }

    fn arb_report() -> impl Strategy<Value = NodeReport> {
        let pos = -16_000.4f64..16_000.4;
        (
            (0u8..32, 0u32..86_400, 0usize..6, pos.clone(), pos.clone(), -2.0f64..9.0, 0.0f64..360.0),
            (
                proptest::collection::vec((pos.clone(), pos), 0..=3),
                0u8..15,
                0u8..5,
                any::<bool>(),
                -1.0f64..203.0,
                -1.0f64..203.0,
                0.0f64..100.0,
            ),
        )
            .prop_map(
                |((src_id, time_of_day, ty, x, y, speed, hdg), (waypoints, fe, fm, leak, depth, altitude, battery))| {
                    NodeReport {
                        src_id,
                        time_of_day,
                        vehicle: TYPES[ty],
                        x,
                        y,
                        speed,
                        heading: Heading::from(CompassDeg(hdg)),
                        waypoints,
                        front_seat_error: fe,
                        front_mode: fm,
                        leak,
                        depth,
                        altitude,
                        battery,
                    }
                },
            )
    }

    thread_local! {
        /// Altered reports that decoded on this thread, counted by the proptest that makes them.
        static DECODED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    }

    /// The altered-report property must see many decodes: of its 2000 cases, at least a tenth.
    #[test]
    fn altered_reports_often_decode() {
        DECODED.set(0);
        altered_reports_are_refused_or_decode_consistently();
        let n = DECODED.get();
        assert!(n >= 200, "{n} altered reports decoded");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn round_trip_within_half_a_step(m in arb_report()) {
            let bytes = m.encode().unwrap();
            prop_assert!(bytes.len() <= MAX_BYTES);
            let d = NodeReport::decode(&bytes).unwrap();
            prop_assert!((d.x - m.x).abs() <= 0.5 + 1e-9 && (d.y - m.y).abs() <= 0.5 + 1e-9);
            prop_assert!((d.speed - m.speed).abs() <= 0.05 + 1e-9);
            prop_assert!((d.depth - m.depth).abs() <= 0.05 + 1e-9);
            let dh = coopnav_core::wrap_pi(d.heading.radians() - m.heading.radians()).abs();
            prop_assert!(dh <= 0.5f64.to_radians() + 1e-9);
            prop_assert_eq!(d.waypoints.len(), m.waypoints.len());
            prop_assert_eq!((d.src_id, d.time_of_day, d.vehicle, d.leak), (m.src_id, m.time_of_day, m.vehicle, m.leak));
            // Canonical: re-encoding the decoded message gives the same bytes.
            prop_assert_eq!(d.encode().unwrap(), bytes);
        }

        /// A valid report with a few bytes overwritten or the end cut: many of these decode
        /// (random bytes almost never do), so the re-encoding check below is exercised.
        #[test]
        fn altered_reports_are_refused_or_decode_consistently(
            m in arb_report(), edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..3), cut in any::<bool>(),
        ) {
            let mut bytes = m.encode().unwrap();
            for (at, byte) in edits {
                let at = at % bytes.len();
                bytes[at] = byte;
            }
            if cut {
                bytes.pop();
            }
            if let Ok(m) = NodeReport::decode(&bytes) {
                DECODED.set(DECODED.get() + 1);
                let again = NodeReport::decode(&m.encode().unwrap()).unwrap();
                prop_assert!(coopnav_core::wrap_pi(again.heading.radians() - m.heading.radians()).abs() < 1e-9);
                prop_assert_eq!(NodeReport { heading: m.heading, ..again }, m);
            }
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..40)) {
            if let Ok(m) = NodeReport::decode(&bytes) {
                // Whatever decodes re-encodes to a message that decodes the same (a 360° heading
                // comes back as 0°, the same direction).
                let again = NodeReport::decode(&m.encode().unwrap()).unwrap();
                prop_assert!(coopnav_core::wrap_pi(again.heading.radians() - m.heading.radians()).abs() < 1e-9);
                prop_assert_eq!(NodeReport { heading: m.heading, ..again }, m);
            }
        }
    }
}
