//! Criterion benches of coopnav's LCM layer: encoding and decoding of small, nested and large
//! messages, fragmenting and reassembling a 1 MB message, writing and reading a log, and, only when
//! run inside a private network namespace (`COOPNAV_LCM_IN_NETNS=1` under `unshare -n`, checked to
//! have loopback alone), the publish-to-receive message rate over loopback multicast.

use std::hint::black_box;
use std::net::SocketAddr;
use std::process::Command;
use std::time::{Duration, Instant};

use coopnav_lcm::sample::{self, Rng};
use coopnav_lcm::udpm::{encode_datagrams, parse_datagram, Limits, Packet, Reassembler};
use coopnav_lcm::{decode, encode, LogReader, LogWriter, Record, Schema, Udpm, Value};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn frame(len: usize) -> Record {
    Record::new("coopnav.status_frame_t")
        .with("utime", Value::Int64(1))
        .with("src", Value::Int16(2))
        .with("receive_time", Value::Double(3.0))
        .with("n", Value::Int32(len as i32))
        .with("data", Value::Bytes(vec![7; len]))
}

fn codec(c: &mut Criterion) {
    let schema = Schema::coopnav();
    let mut rng = Rng::new(1);
    let fix = sample::record(&schema, schema.index("coopnav.cna_fix_t").unwrap(), &mut rng, 0);
    // A team of eight AUVs (the first seed that draws n = 8).
    let team_index = schema.index("coopnav.team_estimate_t").unwrap();
    let team = (0..10_000)
        .map(|_| sample::record(&schema, team_index, &mut rng, 8))
        .find(|t| t.get("n") == Some(&Value::Int8(8)))
        .expect("n = 8 is drawn");
    let cases = [("cna_fix_t", fix), ("team_estimate_t", team), ("status_frame_t_200k", frame(200_000))];
    let mut g = c.benchmark_group("lcm_codec");
    for (name, record) in &cases {
        let bytes = encode(&schema, record).unwrap();
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(format!("encode/{name}"), |b| b.iter(|| encode(&schema, black_box(record)).unwrap()));
        g.bench_function(format!("decode/{name}"), |b| {
            b.iter(|| decode(&schema, &record.type_name, black_box(&bytes)).unwrap())
        });
    }
    g.finish();
}

fn fragments(c: &mut Criterion) {
    let payload = vec![3u8; 1_000_000];
    let from: SocketAddr = "127.0.0.1:1".parse().unwrap();
    let mut g = c.benchmark_group("lcm_udpm");
    g.throughput(Throughput::Bytes(payload.len() as u64));
    g.bench_function("fragment_1MB", |b| b.iter(|| encode_datagrams(1, "CH", black_box(&payload)).unwrap()));
    let datagrams = encode_datagrams(1, "CH", &payload).unwrap();
    g.bench_function("reassemble_1MB", |b| {
        b.iter(|| {
            let mut r = Reassembler::new(Limits::default());
            let now = Instant::now();
            let mut out = None;
            for d in &datagrams {
                if let Ok(Packet::Fragment(f)) = parse_datagram(d) {
                    out = r.push(from, &f, now).or(out);
                }
            }
            out.expect("complete")
        })
    });
    g.finish();
}

fn log(c: &mut Criterion) {
    let data = vec![1u8; 1000];
    let mut g = c.benchmark_group("lcm_log");
    g.throughput(Throughput::Elements(1000));
    g.bench_function("write_1000_events_1kB", |b| {
        b.iter(|| {
            let mut w = LogWriter::new(Vec::with_capacity(1_100_000));
            for i in 0..1000 {
                w.write(i, "CHANNEL", &data).unwrap();
            }
            w.into_inner().unwrap()
        })
    });
    let mut w = LogWriter::new(Vec::new());
    for i in 0..1000 {
        w.write(i, "CHANNEL", &data).unwrap();
    }
    let bytes = w.into_inner().unwrap();
    g.bench_function("read_1000_events_1kB", |b| b.iter(|| LogReader::new(black_box(bytes.as_slice())).count()));
    g.finish();
}

/// Inside a private namespace only: loopback is the only interface, multicast routed to it.
fn private_loopback() -> bool {
    if std::env::var_os("COOPNAV_LCM_IN_NETNS").is_none() {
        return false;
    }
    let links = Command::new("ip").args(["-o", "link"]).output().expect("ip");
    let links = String::from_utf8_lossy(&links.stdout);
    assert!(links.lines().count() == 1 && links.contains(": lo:"), "not a private namespace: {links}");
    let ok = |args: &[&str]| Command::new("ip").args(args).status().is_ok_and(|s| s.success());
    assert!(ok(&["link", "set", "lo", "up"]));
    let _ = ok(&["route", "add", "224.0.0.0/4", "dev", "lo"]);
    true
}

fn loopback(c: &mut Criterion) {
    if !private_loopback() {
        eprintln!("lcm_loopback skipped: run under `unshare -n` with COOPNAV_LCM_IN_NETNS=1");
        return;
    }
    let url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
    let mut g = c.benchmark_group("lcm_loopback");
    for size in [100usize, 200_000] {
        let mut lcm = Udpm::new(url).unwrap();
        lcm.subscribe("BENCH").unwrap();
        let payload = vec![5u8; size];
        g.throughput(Throughput::Elements(1));
        g.bench_function(format!("publish_receive_{size}B"), |b| {
            b.iter(|| {
                lcm.publish("BENCH", &payload).unwrap();
                lcm.recv_timeout(Duration::from_secs(1)).unwrap().expect("looped back")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, codec, fragments, log, loopback);
criterion_main!(benches);
