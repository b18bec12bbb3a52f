//! coopnav's LCM codec and log files checked byte for byte against the official library (lcm 1.5.3
//! from PyPI, scripts/install-lcm.sh): lcm-gen's Python types from the repository's `.lcm` files
//! encode and decode, `lcm.EventLog` reads and writes. Ignored, with the reason, where that
//! library is not installed (crates/lcm/build.rs).

mod common;

use std::time::Duration;

use common::{hex, interop, lcm_files, lcm_gen_python, record_json, unhex};
use coopnav_lcm::messages::{
    AuvEstimate, AuvSensors, Clock, CnaCommand, CnaFix, Decision, Message, OwttRange, Position, StatusFrame,
    TeamEstimate,
};
use coopnav_lcm::sample::{self, Rng};
use coopnav_lcm::{decode, encode, Event, LogReader, LogWriter, Schema};
use serde_json::{json, Value as Json};

const T: Duration = Duration::from_secs(60);

#[cfg(lcm_python)]
fn tools() -> (&'static str, &'static str) {
    (env!("COOPNAV_LCM_PYTHON_FOUND"), env!("COOPNAV_LCM_GEN_FOUND"))
}
#[cfg(not(lcm_python))]
fn tools() -> (&'static str, &'static str) {
    unreachable!("the tests needing the official lcm are ignored without it")
}

/// Decodes into the type's typed view and encodes that again.
fn typed_round_trip(schema: &Schema, type_name: &str, bytes: &[u8]) -> Vec<u8> {
    fn via<M: Message>(schema: &Schema, bytes: &[u8]) -> Vec<u8> {
        M::decode(schema, bytes).unwrap().encode(schema).unwrap()
    }
    match type_name {
        "coopnav.position_t" => via::<Position>(schema, bytes),
        "coopnav.cna_fix_t" => via::<CnaFix>(schema, bytes),
        "coopnav.status_frame_t" => via::<StatusFrame>(schema, bytes),
        "coopnav.owtt_range_t" => via::<OwttRange>(schema, bytes),
        "coopnav.cna_command_t" => via::<CnaCommand>(schema, bytes),
        "coopnav.decision_t" => via::<Decision>(schema, bytes),
        "coopnav.auv_estimate_t" => via::<AuvEstimate>(schema, bytes),
        "coopnav.auv_sensors_t" => via::<AuvSensors>(schema, bytes),
        "coopnav.clock_t" => via::<Clock>(schema, bytes),
        "coopnav.team_estimate_t" => via::<TeamEstimate>(schema, bytes),
        other => panic!("no typed view of {other}"),
    }
}

fn read_json(path: &std::path::Path) -> Json {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read json")).expect("parse json")
}

#[test]
#[cfg_attr(not(lcm_python), ignore = "needs the official lcm Python package with lcm-gen (scripts/install-lcm.sh)")]
fn python_encoded_messages_decode_to_their_values_and_reencode_to_their_bytes() {
    let (python, lcm_gen) = tools();
    let dir = tempfile::tempdir().unwrap();
    lcm_gen_python(lcm_gen, &lcm_files(), dir.path());
    let out = dir.path().join("samples.json");
    interop(python, &[&"samples", &dir.path(), &out], T);
    let schema = Schema::coopnav();
    let samples = read_json(&out);
    let samples = samples.as_array().unwrap();
    let mut types = std::collections::BTreeSet::new();
    for s in samples {
        let type_name = s["type"].as_str().unwrap();
        types.insert(type_name.to_string());
        let bytes = unhex(s["bytes"].as_str().unwrap());
        let def = schema.get(type_name).unwrap();
        assert_eq!(format!("{:016x}", def.fingerprint), s["fingerprint"].as_str().unwrap(), "{type_name}");
        let record = decode(&schema, type_name, &bytes).unwrap_or_else(|e| panic!("{type_name}: {e}"));
        assert_eq!(record_json(&record), s["value"], "{type_name}");
        assert_eq!(hex(&encode(&schema, &record).unwrap()), s["bytes"].as_str().unwrap(), "{type_name}");
        assert_eq!(hex(&typed_round_trip(&schema, type_name, &bytes)), s["bytes"].as_str().unwrap(), "{type_name}");
    }
    // Every type of the schema is among the samples.
    let all: std::collections::BTreeSet<String> = schema.structs().iter().map(|s| s.name.clone()).collect();
    assert_eq!(types, all);
}

#[test]
#[cfg_attr(not(lcm_python), ignore = "needs the official lcm Python package with lcm-gen (scripts/install-lcm.sh)")]
fn rust_encoded_messages_decode_in_python_to_the_same_values() {
    let (python, lcm_gen) = tools();
    let dir = tempfile::tempdir().unwrap();
    lcm_gen_python(lcm_gen, &lcm_files(), dir.path());
    let schema = Schema::coopnav();
    let mut rng = Rng::new(0x5eed_1c3a);
    let mut items = Vec::new();
    let mut expected = Vec::new();
    for round in 0..8 {
        for i in 0..schema.structs().len() {
            let record = sample::record(&schema, i, &mut rng, round % 5);
            let bytes = encode(&schema, &record).unwrap();
            items.push(json!({"type": record.type_name, "bytes": hex(&bytes)}));
            expected.push((record_json(&record), hex(&bytes)));
        }
    }
    let input = dir.path().join("in.json");
    let output = dir.path().join("out.json");
    std::fs::write(&input, serde_json::to_string(&items).unwrap()).unwrap();
    interop(python, &[&"decode", &dir.path(), &input, &output], T);
    let decoded = read_json(&output);
    let decoded = decoded.as_array().unwrap();
    assert_eq!(decoded.len(), expected.len());
    for (i, (d, (value, bytes))) in decoded.iter().zip(&expected).enumerate() {
        assert_eq!(&d["value"], value, "message {i} ({})", items[i]["type"]);
        assert_eq!(d["reencoded"].as_str().unwrap(), bytes, "message {i}");
    }
}

#[test]
#[cfg_attr(not(lcm_python), ignore = "needs the official lcm Python package with lcm-gen (scripts/install-lcm.sh)")]
fn recursive_and_constant_sized_types_fingerprint_as_lcm_gen() {
    let (python, lcm_gen) = tools();
    let dir = tempfile::tempdir().unwrap();
    // lcm-type-ref's mutually recursive example, and a constant used as an array size.
    let src = "package rec;\n\
               struct A { int8_t nb; B b[nb]; int8_t nc; C c[nc]; }\n\
               struct B { int8_t na; A a[na]; }\n\
               struct C { int8_t nb; B b[nb]; B again; }\n\
               struct K { const int16_t N = 0x3; double v[N][2]; K2 inner[N]; }\n\
               struct K2 { const int8_t M = 2; string s[M]; boolean b; }\n";
    let file = dir.path().join("rec.lcm");
    std::fs::write(&file, src).unwrap();
    lcm_gen_python(lcm_gen, &[file], dir.path());
    let names = ["rec.A", "rec.B", "rec.C", "rec.K", "rec.K2"];
    let out = dir.path().join("fp.json");
    let gen_dir = dir.path();
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"fingerprints", &gen_dir, &out];
    args.extend(names.iter().map(|n| n as &dyn AsRef<std::ffi::OsStr>));
    interop(python, &args, T);
    let fps = read_json(&out);
    let schema = Schema::from_sources([("rec.lcm", src)]).unwrap();
    for n in names {
        assert_eq!(format!("{:016x}", schema.get(n).unwrap().fingerprint), fps[n].as_str().unwrap(), "{n}");
    }
}

fn some_events() -> Vec<Event> {
    let schema = Schema::coopnav();
    let mut rng = Rng::new(77);
    (0..40)
        .map(|i| {
            let index = i % schema.structs().len();
            let record = sample::record(&schema, index, &mut rng, 4);
            let mut data = encode(&schema, &record).unwrap();
            if i == 39 {
                data = vec![0xAB; 300_000]; // a large event
            }
            Event {
                event_number: i as i64,
                timestamp: 1_700_000_000_000_000 + 1000 * i as i64,
                channel: format!("COOPNAV_{}", schema.at(index).name.rsplit('.').next().unwrap().to_uppercase()),
                data,
            }
        })
        .collect()
}

#[test]
#[cfg_attr(not(lcm_python), ignore = "needs the official lcm Python package with lcm-gen (scripts/install-lcm.sh)")]
fn a_log_written_here_is_read_by_lcm_eventlog() {
    let (python, _) = tools();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rust.lcmlog");
    let events = some_events();
    let mut w = LogWriter::new(std::io::BufWriter::new(std::fs::File::create(&path).unwrap()));
    for e in &events {
        assert_eq!(w.write(e.timestamp, &e.channel, &e.data).unwrap(), e.event_number);
    }
    w.into_inner().unwrap();
    let out = dir.path().join("read.json");
    interop(python, &[&"log-read", &path, &out], T);
    let read = read_json(&out);
    let read = read.as_array().unwrap();
    assert_eq!(read.len(), events.len());
    for (r, e) in read.iter().zip(&events) {
        assert_eq!(r["eventnum"], json!(e.event_number));
        assert_eq!(r["timestamp"], json!(e.timestamp));
        assert_eq!(r["channel"], json!(e.channel));
        assert_eq!(r["data"].as_str().unwrap(), hex(&e.data));
    }
}

#[test]
#[cfg_attr(not(lcm_python), ignore = "needs the official lcm Python package with lcm-gen (scripts/install-lcm.sh)")]
fn a_log_written_by_lcm_eventlog_is_read_here() {
    let (python, _) = tools();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("python.lcmlog");
    let events = some_events();
    let input = dir.path().join("events.json");
    let items: Vec<Json> =
        events.iter().map(|e| json!({"channel": e.channel, "timestamp": e.timestamp, "data": hex(&e.data)})).collect();
    std::fs::write(&input, serde_json::to_string(&items).unwrap()).unwrap();
    interop(python, &[&"log-write", &path, &input], T);
    let read: Vec<Event> = LogReader::new(std::fs::File::open(&path).unwrap()).collect::<Result<_, _>>().unwrap();
    assert_eq!(read, events);
}
