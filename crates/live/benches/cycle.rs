//! One live cycle of the AUV navigator: a message's payload decoded and checked, buffered, the
//! message the reorder window releases applied (prediction, speed and compass updates, or the
//! range update), and its `auv_estimate_t` encoded — everything `coopnav live auv` does per
//! message except the socket calls. Over a synthetic hour at 10 Hz (one range per 150 messages).

use coopnav_live::synthetic::stream;
use coopnav_live::{AuvNavigator, LiveConfig};
use coopnav_nav::synthetic::SyntheticSpec;
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use std::time::{Duration, Instant};

fn bench(c: &mut Criterion) {
    let messages = stream(&SyntheticSpec::default(), 1).messages;
    c.bench_function("live_auv_message_update_estimate", |b| {
        b.iter_custom(|iters| {
            let mut spent = Duration::ZERO;
            let mut left = iters;
            while left > 0 {
                // A fresh navigator per pass over the hour (not timed).
                let mut nav = AuvNavigator::new(1, LiveConfig::default()).unwrap();
                let n = (left as usize).min(messages.len());
                let start = Instant::now();
                for m in &messages[..n] {
                    black_box(nav.handle(&m.channel, &m.payload).unwrap());
                }
                spent += start.elapsed();
                left -= n as u64;
            }
            spent
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
