//! The LCM message stream a survey AUV's backseat would receive over a synthetic mission
//! (`coopnav_nav::synthetic::synthetic_log`), for the tests, the end-to-end run and the CPU
//! measurement: one `auv_sensors_t` per step (its speed and compass rows; the log's `yaw_rate`
//! rows have no field in the type and are left out), one `owtt_range_t` per range (the
//! transponder where the log's fix of that beacon at the transmit time put it), and the truth.
//!
//! The message fields quantise the log: times to whole microseconds (`utime`), speed to `f32`,
//! the compass to radians clockwise from north.

use crate::auv::Channels;
use coopnav_lcm::messages::{AuvSensors, Message, OwttRange, Position};
use coopnav_lcm::Schema;
use coopnav_nav::fieldlog::Observation;
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use std::collections::BTreeMap;

/// One message of the stream: its mission time (s), channel and payload.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamMessage {
    pub t: f64,
    pub channel: String,
    pub payload: Vec<u8>,
}

/// The stream and the truth (t, e, n) of the log's truth rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Stream {
    pub messages: Vec<StreamMessage>,
    pub truth: Vec<(f64, f64, f64)>,
}

/// Microseconds of a time in seconds.
pub fn utime(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// The stream of AUV `auv` over the synthetic log of `spec`, in the log's order.
pub fn stream(spec: &SyntheticSpec, auv: i16) -> Stream {
    let schema = Schema::coopnav();
    let ch = Channels::for_auv(auv);
    let rows = synthetic_log(spec);
    let mut messages = Vec::new();
    let mut truth = Vec::new();
    let mut fixes: BTreeMap<u32, Position> = BTreeMap::new();
    let mut speed: Option<(f64, f64)> = None;
    for row in &rows {
        match row.obs {
            Observation::Speed(s) => speed = Some((row.t, s)),
            Observation::Heading { compass_deg } => {
                let (t, s) = speed.take().expect("a speed row before each heading row");
                assert_eq!(t, row.t, "speed and heading rows of one step");
                let m = AuvSensors {
                    utime: utime(t),
                    auv,
                    heading: compass_deg.to_radians(),
                    speed: s as f32,
                    ..AuvSensors::default()
                };
                messages.push(StreamMessage { t, channel: ch.sensors.clone(), payload: m.encode(&schema).unwrap() });
            }
            Observation::BeaconFix { beacon, e, n, depth, .. } => {
                fixes.insert(beacon, Position { x: e, y: n, z: depth });
            }
            Observation::Range { beacon, travel_time } => {
                let m = OwttRange {
                    utime: utime(row.t),
                    src: beacon as i8,
                    transmit_time: row.t - travel_time,
                    receive_time: row.t,
                    transponder: fixes[&beacon],
                    travel_time,
                };
                messages.push(StreamMessage {
                    t: row.t,
                    channel: ch.range.clone(),
                    payload: m.encode(&schema).unwrap(),
                });
            }
            Observation::Truth { e, n } => truth.push((row.t, e, n)),
            _ => {}
        }
    }
    Stream { messages, truth }
}
