//! A live navigator's LCM log read back as a post-processing log (docs/log-format.md, version 2,
//! relative time): what `coopnav live auv --auv K --log FILE` received becomes the rows
//! `coopnav hbl postprocess` reads, so a live run is post-processed and viewed unchanged.
//!
//! | logged message (channel of AUV K) | rows |
//! |-----------------------------------|------|
//! | the first `auv_sensors_t`          | `init` at its time: the config's `[start]`, its speed and compass heading |
//! | every `auv_sensors_t`              | `speed`, `heading` (compass deg), `depth` at its time |
//! | `owtt_range_t`                     | `beacon_fix` of beacon `src` at its transmit time (its transponder), `range` at its receive time |
//! | `auv_estimate_t` (published)       | kept apart: the live estimates ([`Imported::estimates`]) |
//!
//! and, when the caller has them, `truth` rows (the world's truth once a second). A range's
//! beacon id is its `src` plus 128 (an id is unsigned; `src` is a signed byte). The navigator
//! starts its filter on the first sensors message and holds the heading rate at zero, as
//! post-processing does on a log without `yaw_rate` rows; so the forward pass over these rows is
//! the live navigator's filter (the reorder buffer, in time order, is the log's own ordering).
//! Payloads that do not decode, sensors of another AUV and repeated payloads (the navigator
//! counted and dropped them) are left out and counted.

use crate::auv::{Channels, LiveError, Start};
use coopnav_lcm::messages::{AuvEstimate, AuvSensors, Message, OwttRange};
use coopnav_lcm::{LogReader, Schema};
use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::Read;

/// A navigator's log as rows, its published estimates and what was left out.
#[derive(Debug, Clone, Default)]
pub struct Imported {
    /// The post-processing log's text.
    pub log: String,
    pub sensors: u64,
    pub ranges: u64,
    pub estimates: Vec<AuvEstimate>,
    /// Payloads that do not decode, of another AUV, or repeated.
    pub left_out: u64,
}

/// The beacon id of a range's `src`.
pub fn beacon_id(src: i8) -> u32 {
    (i32::from(src) + 128) as u32
}

/// Reads the LCM log `input` of AUV `auv`'s navigator, started at `start`; `truth`: (t, e, n)
/// rows to add.
pub fn field_log(input: impl Read, auv: i16, start: Start, truth: &[(f64, f64, f64)]) -> Result<Imported, LiveError> {
    let schema = Schema::coopnav();
    let ch = Channels::for_auv(auv);
    let mut out = Imported::default();
    let mut rows: Vec<(f64, String)> = Vec::new();
    let mut seen = HashSet::new();
    let mut started = false;
    for event in LogReader::new(input) {
        let event = event.map_err(|source| LiveError::Log { path: format!("LCM log of AUV {auv}"), source })?;
        let fresh = seen.insert((event.channel.clone(), event.data.clone()));
        if event.channel == ch.sensors {
            match AuvSensors::decode(&schema, &event.data) {
                Ok(s) if fresh && s.auv == auv => {
                    let t = s.utime as f64 / 1e6;
                    let compass = s.heading.to_degrees();
                    let speed = f64::from(s.speed);
                    if !started {
                        started = true;
                        rows.push((t, format!("{t},init,,{},{},{speed},{compass},", start.e, start.n)));
                    }
                    rows.push((t, format!("{t},speed,,{speed},,,,")));
                    rows.push((t, format!("{t},heading,,{compass},,,,")));
                    rows.push((t, format!("{t},depth,,{},,,,", f64::from(s.depth))));
                    out.sensors += 1;
                }
                _ => out.left_out += 1,
            }
        } else if event.channel == ch.range {
            match OwttRange::decode(&schema, &event.data) {
                Ok(r) if fresh => {
                    let id = beacon_id(r.src);
                    let p = r.transponder;
                    rows.push((
                        r.transmit_time,
                        format!("{},beacon_fix,{id},{},{},{},,", r.transmit_time, p.x, p.y, p.z),
                    ));
                    rows.push((r.receive_time, format!("{},range,{id},{},,,,", r.receive_time, r.travel_time)));
                    out.ranges += 1;
                }
                _ => out.left_out += 1,
            }
        } else if event.channel == ch.estimate {
            if let Ok(e) = AuvEstimate::decode(&schema, &event.data) {
                out.estimates.push(e);
            }
        }
    }
    for &(t, e, n) in truth {
        rows.push((t, format!("{t},truth,,{e},{n},,,")));
    }
    // Time order, stably: rows of one time keep the order they were read in (init first).
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut log = String::from("# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4,sigma\n");
    for (_, row) in rows {
        let _ = writeln!(log, "{row}");
    }
    out.log = log;
    Ok(out)
}
