//! Decoder fuzzing: arbitrary bytes into every decoder, 100 000 cases each run. A decoder may
//! reject input (typed error) but must never panic, and whatever it accepts must re-encode to the
//! very same bytes (the wire format is canonical).

use coopnav_acomms::status::Frame0;
use coopnav_acomms::tracker::{MaskWidth, TrackingHeader};
use proptest::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

static CASES: AtomicU64 = AtomicU64::new(0);

fn width(wide: bool) -> MaskWidth {
    if wide {
        MaskWidth::Wide
    } else {
        MaskWidth::Narrow
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100_000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..48), wide in any::<bool>()) {
        let w = width(wide);
        CASES.fetch_add(1, Ordering::Relaxed);
        if let Ok(h) = TrackingHeader::decode(&bytes, w) {
            prop_assert_eq!(h.encode(w).unwrap(), bytes.clone());
        }
        if let Ok(f) = Frame0::decode(&bytes, w) {
            prop_assert_eq!(f.encode(w, 256).unwrap(), bytes);
        }
    }
}

#[test]
fn at_least_1e5_cases_ran() {
    // The proptest above runs in the same binary; run it here explicitly to count its cases.
    arbitrary_bytes_never_panic();
    assert!(CASES.load(Ordering::Relaxed) >= 100_000, "{} cases", CASES.load(Ordering::Relaxed));
}

/// Mostly-valid inputs reach the deeper validation paths far more often than random bytes.
#[test]
fn mutated_valid_headers_never_panic() {
    use coopnav_acomms::tracker::HeaderEntry;
    let h = TrackingHeader {
        entries: (1..=6).map(|c| HeaderEntry { cycles_ago: c * 2, frames: 1 + u16::from(c) }).collect(),
        truncated: false,
    };
    let good = h.encode(MaskWidth::Narrow).unwrap();
    let mut accepted = 0;
    for i in 0..good.len() * 8 {
        let mut b = good.clone();
        b[i / 8] ^= 1 << (i % 8);
        if let Ok(d) = TrackingHeader::decode(&b, MaskWidth::Narrow) {
            accepted += 1;
            assert_eq!(d.encode(MaskWidth::Narrow).unwrap(), b);
        }
        for cut in 0..b.len() {
            assert!(TrackingHeader::decode(&b[..cut], MaskWidth::Narrow).is_err() || cut == b.len());
        }
    }
    assert!(accepted < good.len() * 8, "some flips must be rejected");
}
