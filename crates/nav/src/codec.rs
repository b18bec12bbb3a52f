//! The 13-bit WHOI mini-packet of the HBL cycle (Gill 2013, §2.1.2 and Appendix B): a 5-bit header
//! and an 8-bit quantisation-box index, word = (header << 8) | index; the quantisation of East,
//! North, speed and heading with saturation at the zone edge and decoding to the box centre; and
//! the NMEA `$CAMUC` (sent) / `$CAMUA` (received) sentences `SRC,DEST,HHHH*CS` with an 8-bit XOR
//! checksum over the characters between `$` and `*`.

use serde::{Deserialize, Serialize};
use std::fmt;
use thiserror::Error;

/// Modem IDs of the HBL missions (Gill 2013, Appendix B).
pub const MODEM_BUOY: u8 = 13;
pub const MODEM_SHIP_PORT: u8 = 14;
pub const MODEM_SHIP_STARBOARD: u8 = 15;
/// Destination 0 = broadcast.
pub const BROADCAST: u8 = 0;

/// Message type in the 5-bit header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Header {
    North = 0x1A,
    East = 0x1B,
    Speed = 0x1C,
    Heading = 0x1D,
    /// Not given in the thesis; 0x1E is the unused value of the range (invented).
    FleetLeader = 0x1E,
    Abort = 0x1F,
}

impl Header {
    pub fn from_bits(bits: u8) -> Result<Self, CodecError> {
        Ok(match bits {
            0x1A => Header::North,
            0x1B => Header::East,
            0x1C => Header::Speed,
            0x1D => Header::Heading,
            0x1E => Header::FleetLeader,
            0x1F => Header::Abort,
            other => return Err(CodecError::UnknownHeader(other)),
        })
    }
}

#[derive(Debug, Error, PartialEq, Eq)]
pub enum CodecError {
    #[error("mini-packet word 0x{0:04X} exceeds 13 bits (allowed 0x0000..=0x1FFF)")]
    TooWide(u16),
    #[error("mini-packet header 0x{0:02X} is not a known message type (allowed 0x1A..=0x1F)")]
    UnknownHeader(u8),
    #[error("sentence does not start with '$CAMUC' or '$CAMUA': {0:?}")]
    BadTalker(String),
    #[error("sentence has no '*' checksum delimiter: {0:?}")]
    NoChecksum(String),
    #[error("checksum field {0:?} is not two hex digits")]
    BadChecksumField(String),
    #[error("checksum mismatch: sentence says {stated:02X}, contents XOR to {computed:02X}")]
    ChecksumMismatch { stated: u8, computed: u8 },
    #[error("sentence has {0} comma-separated fields; expected 4 (talker,SRC,DEST,HHHH)")]
    FieldCount(usize),
    #[error("{field} field {value:?} is not a modem id (decimal 0..=255)")]
    BadId { field: &'static str, value: String },
    #[error("payload field {0:?} is not 1-4 hex digits")]
    BadHex(String),
    #[error("sentence contains non-ASCII characters")]
    NotAscii,
}

/// One 13-bit mini-packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MiniPacket {
    pub header: Header,
    pub index: u8,
}

impl MiniPacket {
    pub fn word(self) -> u16 {
        ((self.header as u16) << 8) | self.index as u16
    }
    pub fn from_word(word: u16) -> Result<Self, CodecError> {
        if word > 0x1FFF {
            return Err(CodecError::TooWide(word));
        }
        Ok(MiniPacket { header: Header::from_bits((word >> 8) as u8)?, index: (word & 0xFF) as u8 })
    }
}

/// One quantised axis: 256 boxes of `resolution` starting at `origin`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    pub origin: f64,
    pub resolution: f64,
}

/// A quantised value: its box index and whether it had to be clamped into the zone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Quantised {
    pub index: u8,
    pub saturated: bool,
}

impl Axis {
    pub fn extent(&self) -> f64 {
        256.0 * self.resolution
    }
    /// Box index of `value`, clamped to 0..=255 (saturation at the zone edge).
    pub fn encode(&self, value: f64) -> Quantised {
        let raw = ((value - self.origin) / self.resolution).floor();
        if !(raw >= 0.0) {
            // Also catches NaN: the bottom box, flagged.
            return Quantised { index: 0, saturated: true };
        }
        if raw > 255.0 {
            return Quantised { index: 255, saturated: true };
        }
        Quantised { index: raw as u8, saturated: false }
    }
    /// Centre of box `index` (an interpretation: docs/models.md#gill-quantisation).
    pub fn decode(&self, index: u8) -> f64 {
        self.origin + (index as f64 + 0.5) * self.resolution
    }
    /// `value` clamped into the zone (what saturation turns it into, before boxing).
    pub fn clamp(&self, value: f64) -> f64 {
        value.clamp(self.origin, self.origin + self.extent())
    }
}

/// A rectangular position zone (East × North).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Zone {
    pub east: Axis,
    pub north: Axis,
}

impl Zone {
    /// The field zone: 1.6 m E × 0.6 m N boxes, E centred on `centre_e`, N from `north_min`
    /// (docs/models.md#gill-quantisation: [−53.6, +100] about the path).
    pub fn standard(centre_e: f64, north_min: f64) -> Self {
        Zone::with_resolution(centre_e, north_min, 1.6, 0.6)
    }
    pub fn with_resolution(centre_e: f64, north_min: f64, res_e: f64, res_n: f64) -> Self {
        Zone {
            east: Axis { origin: centre_e - 128.0 * res_e, resolution: res_e },
            north: Axis { origin: north_min, resolution: res_n },
        }
    }
    /// A zone of the given resolutions centred on (e, n).
    pub fn centred(e: f64, n: f64, res_e: f64, res_n: f64) -> Self {
        Zone::with_resolution(e, n - 128.0 * res_n, res_e, res_n)
    }
    /// Distance from a point to its clamp into the zone (the saturation error of Gill 2013, Table 4).
    pub fn saturation_error(&self, e: f64, n: f64) -> f64 {
        (e - self.east.clamp(e)).hypot(n - self.north.clamp(n))
    }
}

/// Speed: 0.015625 m/s boxes from 0 to 4 m/s (Gill 2013, §2.1.2; docs/models.md#gill-quantisation).
pub const SPEED_AXIS: Axis = Axis { origin: 0.0, resolution: 4.0 / 256.0 };
/// Compass heading in degrees: 1.40625° boxes over [0, 360).
pub const HEADING_RESOLUTION_DEG: f64 = 360.0 / 256.0;

/// Heading box of a compass heading in degrees (wrapped to [0, 360), never saturates).
pub fn encode_heading_deg(compass_deg: f64) -> u8 {
    let w = compass_deg.rem_euclid(360.0);
    ((w / HEADING_RESOLUTION_DEG).floor() as i64).clamp(0, 255) as u8
}

/// Centre of a heading box, compass degrees.
pub fn decode_heading_deg(index: u8) -> f64 {
    (index as f64 + 0.5) * HEADING_RESOLUTION_DEG
}

/// Direction of an NMEA sentence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// `$CAMUC`: the host asks the modem to send.
    Send,
    /// `$CAMUA`: the modem reports a reception.
    Received,
}

/// A mini-packet NMEA sentence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sentence {
    pub direction: Direction,
    pub src: u8,
    pub dest: u8,
    pub packet: MiniPacket,
}

/// 8-bit XOR of the bytes.
pub fn xor_checksum(body: &str) -> u8 {
    body.bytes().fold(0, |acc, b| acc ^ b)
}

impl fmt::Display for Sentence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let talker = match self.direction {
            Direction::Send => "CAMUC",
            Direction::Received => "CAMUA",
        };
        let body = format!("{talker},{},{},{:04X}", self.src, self.dest, self.packet.word());
        write!(f, "${body}*{:02X}", xor_checksum(&body))
    }
}

impl std::str::FromStr for Sentence {
    type Err = CodecError;
    fn from_str(s: &str) -> Result<Self, CodecError> {
        let s = s.trim_end_matches(['\r', '\n']);
        if !s.is_ascii() {
            return Err(CodecError::NotAscii);
        }
        let rest = s.strip_prefix('$').ok_or_else(|| CodecError::BadTalker(s.to_string()))?;
        let (body, cs) = rest.rsplit_once('*').ok_or_else(|| CodecError::NoChecksum(s.to_string()))?;
        if cs.len() != 2 || !cs.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(CodecError::BadChecksumField(cs.to_string()));
        }
        let stated = u8::from_str_radix(cs, 16).map_err(|_| CodecError::BadChecksumField(cs.to_string()))?;
        let computed = xor_checksum(body);
        if stated != computed {
            return Err(CodecError::ChecksumMismatch { stated, computed });
        }
        let fields: Vec<&str> = body.split(',').collect();
        if fields.len() != 4 {
            return Err(CodecError::FieldCount(fields.len()));
        }
        let direction = match fields[0] {
            "CAMUC" => Direction::Send,
            "CAMUA" => Direction::Received,
            _ => return Err(CodecError::BadTalker(s.to_string())),
        };
        let id = |field: &'static str, v: &str| -> Result<u8, CodecError> {
            if v.is_empty() || !v.bytes().all(|b| b.is_ascii_digit()) {
                return Err(CodecError::BadId { field, value: v.to_string() });
            }
            v.parse::<u8>().map_err(|_| CodecError::BadId { field, value: v.to_string() })
        };
        let src = id("SRC", fields[1])?;
        let dest = id("DEST", fields[2])?;
        let hex = fields[3];
        if hex.is_empty() || hex.len() > 4 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(CodecError::BadHex(hex.to_string()));
        }
        let word = u16::from_str_radix(hex, 16).map_err(|_| CodecError::BadHex(hex.to_string()))?;
        Ok(Sentence { direction, src, dest, packet: MiniPacket::from_word(word)? })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn header() -> impl Strategy<Value = Header> {
        prop::sample::select(vec![
            Header::North,
            Header::East,
            Header::Speed,
            Header::Heading,
            Header::FleetLeader,
            Header::Abort,
        ])
    }

    #[test]
    fn bit_layout_matches_appendix_b() {
        let p = MiniPacket { header: Header::North, index: 127 };
        assert_eq!(p.word(), 0x1A7F);
        assert_eq!(MiniPacket { header: Header::Abort, index: 255 }.word(), 0x1FFF);
        let s = Sentence { direction: Direction::Send, src: MODEM_SHIP_PORT, dest: BROADCAST, packet: p };
        let text = s.to_string();
        assert!(text.starts_with("$CAMUC,14,0,1A7F*"));
        assert_eq!(&text[text.len() - 2..], format!("{:02X}", xor_checksum("CAMUC,14,0,1A7F")));
    }

    #[test]
    fn quantisation_constants_and_centres() {
        let z = Zone::standard(0.0, -53.6);
        assert!((z.east.extent() - 409.6).abs() < 1e-9 && (z.north.origin + 53.6).abs() < 1e-12);
        let q = z.north.encode(0.0);
        assert_eq!(q, Quantised { index: 89, saturated: false });
        assert!((z.north.decode(89) - 0.1).abs() < 1e-9);
        assert_eq!(z.north.encode(500.0), Quantised { index: 255, saturated: true });
        assert_eq!(z.east.encode(-1e9), Quantised { index: 0, saturated: true });
        assert_eq!(z.east.encode(f64::NAN).saturated, true);
        assert_eq!(SPEED_AXIS.encode(1.3).index, 83);
        assert_eq!(encode_heading_deg(-1.0), 255);
        assert_eq!(encode_heading_deg(360.0), 0);
        assert!((z.saturation_error(0.0, 110.0) - 10.0).abs() < 1e-9);
        assert_eq!(z.saturation_error(0.0, 99.0), 0.0);
    }

    #[test]
    fn malformed_sentences_are_typed_errors() {
        let good = Sentence {
            direction: Direction::Received,
            src: 13,
            dest: 0,
            packet: MiniPacket { header: Header::East, index: 3 },
        }
        .to_string();
        assert_eq!(good.parse::<Sentence>().unwrap().src, 13);
        let mut bad_cs = good.clone();
        bad_cs.replace_range(good.len() - 2.., "00");
        assert!(matches!(bad_cs.parse::<Sentence>(), Err(CodecError::ChecksumMismatch { .. })));
        let with_cs = |body: &str| format!("${body}*{:02X}", xor_checksum(body));
        assert!(matches!(with_cs("CAMUA,13,0,1G03").parse::<Sentence>(), Err(CodecError::BadHex(_))));
        assert!(matches!(with_cs("CAMUA,13,0").parse::<Sentence>(), Err(CodecError::FieldCount(3))));
        assert!(matches!(with_cs("CAMUA,13,0,1B03,9").parse::<Sentence>(), Err(CodecError::FieldCount(5))));
        assert!(matches!(with_cs("CAMUA,300,0,1B03").parse::<Sentence>(), Err(CodecError::BadId { field: "SRC", .. })));
        assert!(matches!(
            with_cs("CAMUA,13,-1,1B03").parse::<Sentence>(),
            Err(CodecError::BadId { field: "DEST", .. })
        ));
        assert!(matches!(with_cs("CAMUA,13,0,2B03").parse::<Sentence>(), Err(CodecError::TooWide(0x2B03))));
        assert!(matches!(with_cs("CAMUA,13,0,0B03").parse::<Sentence>(), Err(CodecError::UnknownHeader(0x0B))));
        assert!(matches!(with_cs("GPGGA,13,0,1B03").parse::<Sentence>(), Err(CodecError::BadTalker(_))));
        assert!(matches!("$CAMUA,13,0,1B03".parse::<Sentence>(), Err(CodecError::NoChecksum(_))));
        assert!(matches!("$CAMUA,13,0,1B03*G1".parse::<Sentence>(), Err(CodecError::BadChecksumField(_))));
        assert!(matches!("CAMUA,13,0,1B03*00".parse::<Sentence>(), Err(CodecError::BadTalker(_))));
        assert!(matches!("$CAMUA,13,0,1B03*é".parse::<Sentence>(), Err(CodecError::NotAscii)));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1024))]
        #[test]
        fn word_round_trip(h in header(), index in any::<u8>()) {
            let p = MiniPacket { header: h, index };
            prop_assert!(p.word() <= 0x1FFF);
            prop_assert_eq!(MiniPacket::from_word(p.word()), Ok(p));
        }

        #[test]
        fn sentence_round_trip(h in header(), index in any::<u8>(), src in any::<u8>(), dest in any::<u8>(), send in any::<bool>()) {
            let s = Sentence { direction: if send { Direction::Send } else { Direction::Received }, src, dest, packet: MiniPacket { header: h, index } };
            prop_assert_eq!(s.to_string().parse::<Sentence>(), Ok(s));
        }

        #[test]
        fn arbitrary_text_is_refused_without_a_panic(text in "\\PC{0,40}") {
            // Random text has no `$` first (or, if it does, no valid checksum but by chance):
            // refused, whatever else it holds.
            if !text.starts_with('$') {
                prop_assert!(text.parse::<Sentence>().is_err());
            }
        }

        /// Near-sentences: each field valid or slightly wrong, the checksum right or wrong. The
        /// expected outcome is worked out from the grammar here, field by field.
        #[test]
        fn near_sentences_parse_exactly_when_well_formed(
            talker in prop_oneof![Just("CAMUC"), Just("CAMUA"), Just("CAMUX"), Just("GPGGA")],
            src in prop_oneof!["[0-9]{1,3}", Just(String::new()), Just("-1".to_string())],
            dest in prop_oneof!["[0-9]{1,3}", Just("1x".to_string())],
            hex in prop_oneof![
                3 => (0x18u16..=0x20, any::<u8>(), any::<bool>()).prop_map(|(h, i, lower)| {
                    let w = format!("{h:X}{i:02X}");
                    if lower { w.to_lowercase() } else { w }
                }),
                1 => "[0-9A-F]{1,4}", 1 => "[0-9A-F]{5}", 1 => Just("1G".to_string()),
            ],
            extra in prop_oneof![Just(None), Just(Some(String::new())), Just(Some("7".to_string()))],
            checksum_right in any::<bool>(), wrong in 1u8..=255,
        ) {
            let mut body = format!("{talker},{src},{dest},{hex}");
            if let Some(e) = &extra {
                body = format!("{body},{e}");
            }
            let cs = if checksum_right { xor_checksum(&body) } else { xor_checksum(&body) ^ wrong };
            let text = format!("${body}*{cs:02X}");
            let id = |v: &str| v.parse::<u8>().ok().filter(|_| v.bytes().all(|b| b.is_ascii_digit()));
            let word = u16::from_str_radix(&hex, 16).ok().filter(|_| hex.len() <= 4);
            // Appendix B: the header is the word's top five bits, 0x1A..=0x1F in its high byte.
            let header = word.and_then(|w| match w >> 8 {
                0x1A => Some(Header::North),
                0x1B => Some(Header::East),
                0x1C => Some(Header::Speed),
                0x1D => Some(Header::Heading),
                0x1E => Some(Header::FleetLeader),
                0x1F => Some(Header::Abort),
                _ => None,
            });
            let direction = match talker {
                "CAMUC" => Some(Direction::Send),
                "CAMUA" => Some(Direction::Received),
                _ => None,
            };
            let parsed = text.parse::<Sentence>();
            if !checksum_right {
                prop_assert!(matches!(parsed, Err(CodecError::ChecksumMismatch { .. })), "{text}: {parsed:?}");
            } else if let (None, Some(d), Some(s), Some(t), Some(w), Some(h)) = (&extra, direction, id(&src), id(&dest), word, header) {
                let want = Sentence { direction: d, src: s, dest: t, packet: MiniPacket { header: h, index: (w & 0xFF) as u8 } };
                prop_assert_eq!(parsed, Ok(want));
            } else {
                prop_assert!(parsed.is_err(), "{text} parsed as {parsed:?}");
            }
        }

        #[test]
        fn decode_encode_is_identity_and_error_within_half_box(index in any::<u8>(), res in 0.05f64..2.0, origin in -500.0f64..500.0, frac in 0.0f64..1.0) {
            let a = Axis { origin, resolution: res };
            prop_assert_eq!(a.encode(a.decode(index)).index, index);
            let v = origin + (index as f64 + frac * 0.999) * res;
            let q = a.encode(v);
            prop_assert!(!q.saturated);
            prop_assert!((a.decode(q.index) - v).abs() <= 0.5 * res + 1e-9);
        }

        #[test]
        fn heading_round_trip_within_half_box(deg in -720.0f64..720.0) {
            let back = decode_heading_deg(encode_heading_deg(deg));
            let diff = (back - deg.rem_euclid(360.0) + 180.0).rem_euclid(360.0) - 180.0;
            prop_assert!(diff.abs() <= 0.5 * HEADING_RESOLUTION_DEG + 1e-9);
        }
    }
}
