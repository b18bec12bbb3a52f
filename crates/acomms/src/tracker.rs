//! The packet-success tracker (Nams 2014, §5.2; the algorithm reconstructed from its design,
//! docs/models.md#nams-tracker): a database of this vehicle's
//! transmissions with a status per collaborator (unknown / received / failed), and the tracking
//! header every packet carries, which reports which collaborator packets this vehicle received.
//!
//! Headers report receptions explicitly as "cycles ago" (counted in TDMA slots, ≤ 63) with a
//! frame bitmask, and failures implicitly: a slot inside the horizon that a complete header does
//! not list failed. Feedback leaves the headers once the collaborator is known to have it (it
//! acknowledged, with frame 0 — the header frame — received, a packet that carried it).
//!
//! Wire format (bit-exact, DCCL bounded integers): count ∈ [0, 63] (7 bits), truncated flag
//! (1 bit), then per entry cycles_ago ∈ [0, 63] (7 bits) and the frame mask ∈ [0, 7] (4 bits) or
//! [0, 255] (9 bits, when rate 5 is enabled network-wide; docs/models.md#nams-tracker): 11 or 16 bits per
//! entry. (The thesis also quotes 13 bits for the narrow entry, which its own field widths do
//! not add up to; we follow the field widths.) Entries newest
//! first. The truncated flag (our addition) marks a header cut to fit its frame: the implicit
//! failure rule then only covers slots no older than the oldest listed entry.

use crate::codec::{BitReader, BitWriter, Bounded, DecodeError, EncodeError};
use crate::rates::Rate;
use crate::success::Reception;
use serde::Serialize;
use std::collections::BTreeMap;

/// Feedback horizon, slots: older headers are lost for good (thesis: 63 cycles).
pub const HORIZON: u64 = 63;
const COUNT: Bounded = Bounded::new("header.count", 0, 63);
const CYCLES_AGO: Bounded = Bounded::new("header.cycles_ago", 0, HORIZON as i64);

/// Width of the frame-success bitmask.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum MaskWidth {
    /// Up to 3 frames (rates 0, 1, 4): 4 bits.
    Narrow,
    /// Up to 8 frames (rate 5): 9 bits.
    Wide,
}

impl MaskWidth {
    fn field(self) -> Bounded {
        match self {
            MaskWidth::Narrow => Bounded::new("header.frames", 0, 7),
            MaskWidth::Wide => Bounded::new("header.frames", 0, 255),
        }
    }
    /// Bits of one header entry (13 or 16).
    pub fn entry_bits(self) -> usize {
        (CYCLES_AGO.bits() + self.field().bits()) as usize
    }
    /// Width needed when `rates` may be used.
    pub fn for_rates(rates: impl IntoIterator<Item = Rate>) -> Self {
        if rates.into_iter().any(|r| r.spec().frames > 3) {
            MaskWidth::Wide
        } else {
            MaskWidth::Narrow
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct HeaderEntry {
    pub cycles_ago: u8,
    pub frames: u16,
}

#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
pub struct TrackingHeader {
    pub entries: Vec<HeaderEntry>,
    pub truncated: bool,
}

impl TrackingHeader {
    /// Encoded size in bits.
    pub fn bits(&self, w: MaskWidth) -> usize {
        (COUNT.bits() + 1) as usize + self.entries.len() * w.entry_bits()
    }

    pub fn encode_into(&self, out: &mut BitWriter, w: MaskWidth) -> Result<(), EncodeError> {
        out.put(COUNT, self.entries.len() as i64)?;
        out.put_bool(self.truncated);
        for e in &self.entries {
            out.put(CYCLES_AGO, e.cycles_ago as i64)?;
            out.put(w.field(), e.frames as i64)?;
        }
        Ok(())
    }

    /// Decodes and validates (entries strictly older one after another, ≥ 1 cycle ago, at least
    /// one frame each).
    pub fn decode_from(r: &mut BitReader<'_>, w: MaskWidth) -> Result<Self, DecodeError> {
        let n = r.get(COUNT)? as usize;
        let truncated = r.get_bool("header.truncated")?;
        let mut entries = Vec::with_capacity(n);
        for _ in 0..n {
            let cycles_ago = r.get(CYCLES_AGO)? as u8;
            let frames = r.get(w.field())? as u16;
            if cycles_ago == 0 {
                return Err(DecodeError::Invalid {
                    field: "header.cycles_ago",
                    message: "0: a vehicle cannot report the slot it transmits in (allowed 1..=63)".into(),
                });
            }
            if frames == 0 {
                return Err(DecodeError::Invalid {
                    field: "header.frames",
                    message: "empty mask: a reception has at least one frame".into(),
                });
            }
            if entries.last().is_some_and(|p: &HeaderEntry| p.cycles_ago >= cycles_ago) {
                return Err(DecodeError::Invalid {
                    field: "header.cycles_ago",
                    message: "entries must be newest first with distinct slots".into(),
                });
            }
            entries.push(HeaderEntry { cycles_ago, frames });
        }
        Ok(TrackingHeader { entries, truncated })
    }

    pub fn encode(&self, w: MaskWidth) -> Result<Vec<u8>, EncodeError> {
        let mut out = BitWriter::new();
        self.encode_into(&mut out, w)?;
        Ok(out.finish())
    }

    pub fn decode(bytes: &[u8], w: MaskWidth) -> Result<Self, DecodeError> {
        let mut r = BitReader::new(bytes);
        let h = Self::decode_from(&mut r, w)?;
        r.finish()?;
        Ok(h)
    }
}

/// Delivery status of one transmission to one collaborator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Delivery {
    Unknown,
    /// Received, with the frame bitmask the collaborator reported.
    Received {
        frames: u16,
    },
    Failed,
}

/// One transmission in the database.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TxRecord {
    pub rate: Rate,
    pub n_frames: u8,
    /// Per vehicle index (this vehicle's own entry stays `Unknown`).
    pub status: Vec<Delivery>,
}

/// A status change the tracker learned: own slot `slot` to collaborator `peer`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Resolution {
    pub slot: u64,
    pub peer: usize,
    pub delivery: Delivery,
}

#[derive(Debug, Clone)]
struct RxEntry {
    slot: u64,
    src: usize,
    frames: u16,
    carried_in: Vec<u64>,
}

/// The database and header queue of one vehicle in an `n`-vehicle TDMA network.
#[derive(Debug, Clone)]
pub struct Tracker {
    me: usize,
    n: usize,
    width: MaskWidth,
    max_entries: usize,
    db: BTreeMap<u64, TxRecord>,
    rx_log: Vec<RxEntry>,
}

impl Tracker {
    /// `max_entries` caps the header so it fits its frame (see [`TrackingHeader::bits`]).
    pub fn new(me: usize, n: usize, width: MaskWidth, max_entries: usize) -> Self {
        Tracker {
            me,
            n,
            width,
            max_entries: max_entries.min(COUNT.max as usize),
            db: BTreeMap::new(),
            rx_log: Vec::new(),
        }
    }

    pub fn width(&self) -> MaskWidth {
        self.width
    }
    pub fn db(&self) -> &BTreeMap<u64, TxRecord> {
        &self.db
    }
    /// Receptions whose feedback is not yet confirmed delivered (the header queue length).
    pub fn queue_len(&self) -> usize {
        self.rx_log.len()
    }

    /// Builds the header for own slot `k`, records the transmission as unknown, and returns the
    /// header to send in frame 0.
    pub fn on_transmit(&mut self, k: u64, rate: Rate) -> TrackingHeader {
        self.rx_log.retain(|e| k - e.slot <= HORIZON);
        let mut order: Vec<usize> = (0..self.rx_log.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.rx_log[i].slot));
        let truncated = order.len() > self.max_entries;
        order.truncate(self.max_entries);
        let entries = order
            .iter()
            .map(|&i| {
                let e = &mut self.rx_log[i];
                e.carried_in.push(k);
                HeaderEntry { cycles_ago: (k - e.slot) as u8, frames: e.frames }
            })
            .collect();
        let status = vec![Delivery::Unknown; self.n];
        self.db.insert(k, TxRecord { rate, n_frames: rate.spec().frames as u8, status });
        TrackingHeader { entries, truncated }
    }

    /// Processes a packet from `src` sent in slot `k`: `rx` is what arrived; `header` is the
    /// decoded header if frame 0 arrived. Returns what this taught about own transmissions.
    pub fn on_receive(
        &mut self,
        k: u64,
        src: usize,
        rx: Reception,
        header: Option<&TrackingHeader>,
    ) -> Vec<Resolution> {
        if rx.received() {
            self.rx_log.push(RxEntry { slot: k, src, frames: rx.frames, carried_in: Vec::new() });
        }
        let Some(h) = header else { return Vec::new() };
        let reported: BTreeMap<u64, u16> = h
            .entries
            .iter()
            .filter(|e| u64::from(e.cycles_ago) <= k)
            .map(|e| (k - u64::from(e.cycles_ago), e.frames))
            .collect();
        let oldest_implicit = match (h.truncated, h.entries.last()) {
            (false, _) => k.saturating_sub(HORIZON),
            (true, Some(e)) => k.saturating_sub(u64::from(e.cycles_ago)),
            (true, None) => k,
        };
        let mut out = Vec::new();
        let lo = k.saturating_sub(HORIZON);
        for (&j, rec) in self.db.range_mut(lo..k) {
            if rec.status[src] != Delivery::Unknown {
                continue;
            }
            let d = match reported.get(&j) {
                Some(&frames) => Delivery::Received { frames },
                None if j >= oldest_implicit => Delivery::Failed,
                None => continue,
            };
            rec.status[src] = d;
            out.push(Resolution { slot: j, peer: src, delivery: d });
        }
        // Confirmation: src acknowledged own slots j with the header frame received, so it holds
        // every piece of feedback about src's packets that slot j carried.
        let confirmed: Vec<u64> =
            reported.iter().filter(|(j, f)| *f & 1 == 1 && self.db.contains_key(j)).map(|(j, _)| *j).collect();
        self.rx_log.retain(|e| !(e.src == src && e.carried_in.iter().any(|c| confirmed.contains(c))));
        out
    }

    /// Own vehicle index.
    pub fn me(&self) -> usize {
        self.me
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rx(frames: u16, n: u8) -> Reception {
        Reception { frames, n_frames: n }
    }

    #[test]
    fn entry_sizes_match_thesis() {
        // The thesis states 7-bit cycles_ago and 4/9-bit masks (11/16 bits per entry) but also
        // "13 bits = 1.625 B" for the narrow entry; the per-field widths are implemented.
        assert_eq!(MaskWidth::Narrow.entry_bits(), 11);
        assert_eq!(MaskWidth::Wide.entry_bits(), 16);
        let h = TrackingHeader {
            entries: vec![HeaderEntry { cycles_ago: 1, frames: 7 }, HeaderEntry { cycles_ago: 3, frames: 1 }],
            truncated: false,
        };
        assert_eq!(h.bits(MaskWidth::Narrow), 8 + 22);
        assert_eq!(h.encode(MaskWidth::Narrow).unwrap().len(), 4);
        assert_eq!(h.bits(MaskWidth::Wide), 8 + 32);
        assert_eq!(MaskWidth::for_rates([Rate::R0, Rate::R5]), MaskWidth::Wide);
    }

    #[test]
    fn exact_header_layout() {
        let h = TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 1, frames: 5 }], truncated: true };
        // count 1 → code 2 (7 bits), truncated 1, cycles 1 → code 2 (7 bits), frames 5 → code 6 (4 bits)
        // bits LSB first: 0100000 1 0100000 0110
        let b = h.encode(MaskWidth::Narrow).unwrap();
        assert_eq!(b, vec![0b1000_0010, 0b0000_0010, 0b0000_0011]);
        assert_eq!(TrackingHeader::decode(&b, MaskWidth::Narrow).unwrap(), h);
    }

    #[test]
    fn malformed_headers_are_errors() {
        let ok = TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 2, frames: 3 }], truncated: false };
        let b = ok.encode(MaskWidth::Narrow).unwrap();
        assert!(matches!(TrackingHeader::decode(&b[..1], MaskWidth::Narrow), Err(DecodeError::Truncated { .. })));
        let mut long = b.clone();
        long.push(0);
        assert!(matches!(TrackingHeader::decode(&long, MaskWidth::Narrow), Err(DecodeError::Oversized { extra: 1 })));
        let zero = TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 2, frames: 0 }], truncated: false };
        assert!(matches!(
            TrackingHeader::decode(&zero.encode(MaskWidth::Narrow).unwrap(), MaskWidth::Narrow),
            Err(DecodeError::Invalid { .. })
        ));
        let unordered = TrackingHeader {
            entries: vec![HeaderEntry { cycles_ago: 4, frames: 1 }, HeaderEntry { cycles_ago: 2, frames: 1 }],
            truncated: false,
        };
        assert!(TrackingHeader::decode(&unordered.encode(MaskWidth::Narrow).unwrap(), MaskWidth::Narrow).is_err());
        assert!(TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 64, frames: 1 }], truncated: false }
            .encode(MaskWidth::Narrow)
            .is_err());
        assert!(TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 1, frames: 8 }], truncated: false }
            .encode(MaskWidth::Narrow)
            .is_err());
    }

    #[test]
    fn explicit_success_implicit_failure_and_confirmation() {
        let (mut a, mut b) = (Tracker::new(0, 2, MaskWidth::Narrow, 10), Tracker::new(1, 2, MaskWidth::Narrow, 10));
        // slot 0: A sends, B receives all 3 frames. slot 2: A sends, B hears nothing.
        let _ = a.on_transmit(0, Rate::R1);
        b.on_receive(0, 0, rx(7, 3), None);
        let h1 = b.on_transmit(1, Rate::R1);
        assert_eq!(h1.entries, vec![HeaderEntry { cycles_ago: 1, frames: 7 }]);
        // slot 1 lost at A: nothing resolved.
        assert!(a.on_receive(1, 1, rx(0, 3), None).is_empty());
        let _ = a.on_transmit(2, Rate::R1);
        b.on_receive(2, 0, rx(0, 3), None);
        let h3 = b.on_transmit(3, Rate::R1);
        assert_eq!(h3.entries, vec![HeaderEntry { cycles_ago: 3, frames: 7 }], "unconfirmed feedback is repeated");
        let res = a.on_receive(3, 1, rx(7, 3), Some(&h3));
        assert_eq!(
            res,
            vec![
                Resolution { slot: 0, peer: 1, delivery: Delivery::Received { frames: 7 } },
                Resolution { slot: 2, peer: 1, delivery: Delivery::Failed },
            ]
        );
        // A reports B's slot 3 with frame 0; B then knows A holds the feedback carried in slot 3.
        let h4 = a.on_transmit(4, Rate::R1);
        assert_eq!(h4.entries, vec![HeaderEntry { cycles_ago: 1, frames: 7 }]);
        assert_eq!(b.queue_len(), 1);
        let res_b = b.on_receive(4, 0, rx(7, 3), Some(&h4));
        assert_eq!(
            res_b,
            vec![
                Resolution { slot: 1, peer: 0, delivery: Delivery::Failed },
                Resolution { slot: 3, peer: 0, delivery: Delivery::Received { frames: 7 } },
            ]
        );
        assert_eq!(b.queue_len(), 1, "only the new reception of slot 4 is queued");
        assert_eq!(b.on_transmit(5, Rate::R1).entries, vec![HeaderEntry { cycles_ago: 1, frames: 7 }]);
    }

    #[test]
    fn ack_without_header_frame_does_not_confirm() {
        let (mut a, mut b) = (Tracker::new(0, 2, MaskWidth::Narrow, 10), Tracker::new(1, 2, MaskWidth::Narrow, 10));
        a.on_receive(0, 1, rx(7, 3), None);
        let _ = b.on_transmit(0, Rate::R1);
        let h = a.on_transmit(1, Rate::R1);
        b.on_receive(1, 0, rx(6, 3), None); // header frame lost
        let h2 = b.on_transmit(2, Rate::R1);
        assert_eq!(h2.entries, vec![HeaderEntry { cycles_ago: 1, frames: 6 }]);
        a.on_receive(2, 1, rx(7, 3), Some(&h2));
        assert_eq!(a.queue_len(), 2, "B never saw the header of slot 1, so A keeps reporting slot 0");
        assert_eq!(h.entries.len(), 1);
    }

    #[test]
    fn truncated_header_limits_implicit_failures() {
        let mut a = Tracker::new(0, 2, MaskWidth::Narrow, 1);
        for k in [0u64, 2, 4] {
            let _ = a.on_transmit(k, Rate::R1);
        }
        // B received slots 0 and 4 but can list one entry: newest (4, cycles_ago 1 at k = 5).
        let h = TrackingHeader { entries: vec![HeaderEntry { cycles_ago: 1, frames: 7 }], truncated: true };
        let res = a.on_receive(5, 1, rx(7, 3), Some(&h));
        assert_eq!(res, vec![Resolution { slot: 4, peer: 1, delivery: Delivery::Received { frames: 7 } }]);
        assert_eq!(a.db()[&0].status[1], Delivery::Unknown);
        let mut b = Tracker::new(1, 2, MaskWidth::Narrow, 1);
        b.on_receive(0, 0, rx(7, 3), None);
        b.on_receive(4, 0, rx(7, 3), None);
        let hb = b.on_transmit(5, Rate::R1);
        assert_eq!(hb, h);
    }

    #[test]
    fn feedback_older_than_horizon_is_dropped() {
        let mut b = Tracker::new(1, 2, MaskWidth::Narrow, 63);
        b.on_receive(0, 0, rx(1, 1), None);
        assert_eq!(b.on_transmit(63, Rate::R0).entries.len(), 1);
        assert_eq!(b.on_transmit(65, Rate::R0).entries.len(), 0);
        assert_eq!(b.queue_len(), 0);
    }

    fn header() -> impl Strategy<Value = (TrackingHeader, MaskWidth)> {
        (any::<bool>(), proptest::collection::btree_map(1u8..=63, 1u16..=255, 0..20), any::<bool>()).prop_map(
            |(wide, m, truncated)| {
                let w = if wide { MaskWidth::Wide } else { MaskWidth::Narrow };
                let max = if wide { 255 } else { 7 };
                let entries =
                    m.into_iter().map(|(c, f)| HeaderEntry { cycles_ago: c, frames: (f % max).max(1) }).collect();
                (TrackingHeader { entries, truncated }, w)
            },
        )
    }

    proptest! {
        #[test]
        fn header_round_trip((h, w) in header()) {
            let b = h.encode(w).unwrap();
            prop_assert_eq!(b.len(), h.bits(w).div_ceil(8));
            prop_assert_eq!(TrackingHeader::decode(&b, w).unwrap(), h);
        }
    }
}
