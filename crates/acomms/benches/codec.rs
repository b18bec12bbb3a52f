//! Criterion benches: frame-0 encode/decode, a two-vehicle tracker exchange, analytic TL.

use coopnav_acomms::status::{Frame0, NextWaypoint, StatusMessage};
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::tracker::{MaskWidth, Tracker};
use coopnav_acomms::{Rate, Reception, TransmissionLoss};
use coopnav_core::{Heading, Vec3};
use criterion::{black_box, criterion_group, criterion_main, Criterion};

fn frame() -> Frame0 {
    let mut tr = Tracker::new(0, 2, MaskWidth::Narrow, 11);
    for k in [1u64, 3, 5] {
        tr.on_receive(k, 1, Reception { frames: 7, n_frames: 3 }, None);
    }
    let header = tr.on_transmit(6, Rate::R1);
    Frame0 {
        header,
        status: StatusMessage {
            pos: Vec3::new(123.4, 456.7, 28.2),
            heading: Heading::from_radians(0.7),
            speed: 1.54,
            next: NextWaypoint::Id(7),
        },
    }
}

fn benches(c: &mut Criterion) {
    let f = frame();
    let bytes = f.encode(MaskWidth::Narrow, 64).unwrap();
    c.bench_function("frame0_encode", |b| b.iter(|| black_box(&f).encode(MaskWidth::Narrow, 64).unwrap()));
    c.bench_function("frame0_decode", |b| b.iter(|| Frame0::decode(black_box(&bytes), MaskWidth::Narrow).unwrap()));
    c.bench_function("tracker_exchange", |b| {
        let (mut a, mut z, mut k) =
            (Tracker::new(0, 2, MaskWidth::Narrow, 11), Tracker::new(1, 2, MaskWidth::Narrow, 11), 0u64);
        b.iter(|| {
            let h = a.on_transmit(k, Rate::R1);
            z.on_receive(k, 0, Reception { frames: 7, n_frames: 3 }, Some(&h));
            let h = z.on_transmit(k + 1, Rate::R1);
            a.on_receive(k + 1, 1, Reception { frames: 7, n_frames: 3 }, Some(&h));
            k += 2;
        })
    });
    let t = Thorp::default();
    c.bench_function("thorp_tl", |b| {
        b.iter(|| t.tl(black_box(&Vec3::new(0.0, 0.0, 10.0)), black_box(&Vec3::new(700.0, 300.0, 25.0))).unwrap())
    });
}

criterion_group!(g, benches);
criterion_main!(g);
