//! Criterion benches: frame-0 encode/decode, a two-vehicle tracker exchange, analytic TL.

use coopnav_acomms::status::Frame0;
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::tracker::MaskWidth;
use coopnav_acomms::workload::{sample_frame0, TrackerExchange};
use coopnav_acomms::TransmissionLoss;
use coopnav_core::Vec3;
use criterion::{black_box, criterion_group, criterion_main, Criterion};

fn benches(c: &mut Criterion) {
    let f = sample_frame0();
    let bytes = f.encode(MaskWidth::Narrow, 64).unwrap();
    c.bench_function("frame0_encode", |b| b.iter(|| black_box(&f).encode(MaskWidth::Narrow, 64).unwrap()));
    c.bench_function("frame0_decode", |b| b.iter(|| Frame0::decode(black_box(&bytes), MaskWidth::Narrow).unwrap()));
    c.bench_function("tracker_exchange", |b| {
        let mut exchange = TrackerExchange::default();
        b.iter(|| exchange.step())
    });
    let t = Thorp::default();
    c.bench_function("thorp_tl", |b| {
        b.iter(|| t.tl(black_box(&Vec3::new(0.0, 0.0, 10.0)), black_box(&Vec3::new(700.0, 300.0, 25.0))).unwrap())
    });
}

criterion_group!(g, benches);
criterion_main!(g);
