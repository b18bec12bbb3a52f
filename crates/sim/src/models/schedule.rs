//! The comms schedule as data: one TDMA cycle of period τ, a list of slots each owned by the CNA
//! (its broadcast), a buoy (its position broadcast) or one survey AUV (its status message).
//! `broadcast_then_status` is Hudson's preset (the CNA at m·τ, then AUV j at m·τ + (j + 1)·τ/(N + 1));
//! with B buoys their slots follow the CNA's, every slot τ/(1 + B + N); `tdma` lists the slots.
//! Validation refuses a slot shorter than its packet's air time plus the longest expected travel
//! time plus a guard, naming the slot, and a message too long for its rate.

use super::channel::{air_time, capacity};
use coopnav_acomms::Rate;
use serde::{Deserialize, Serialize};

/// Who transmits in a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Owner {
    Cna,
    Buoy(usize),
    Auv(usize),
}

/// One slot of the cycle, seconds after the cycle start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    pub owner: Owner,
    pub start_s: f64,
    pub length_s: f64,
}

/// A slot as written in the file: `who = "cna"`, `"buoy0"`, … or `"auv0"`, `"auv1"`, …
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlotSpec {
    pub who: String,
    pub start_s: f64,
    pub length_s: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Schedule {
    BroadcastThenStatus {},
    Tdma { slots: Vec<SlotSpec> },
}

impl Default for Schedule {
    fn default() -> Self {
        Schedule::BroadcastThenStatus {}
    }
}

/// What a slot must hold: the packet's rates and sizes, and the margins around it.
pub struct Fit {
    pub tau: f64,
    pub n_auvs: usize,
    pub n_buoys: usize,
    /// Longest air time any rate the CNA / a buoy / an AUV may use takes.
    pub cna_air_s: f64,
    pub buoy_air_s: f64,
    pub status_air_s: f64,
    /// Longest expected travel time, s.
    pub travel_s: f64,
    pub guard_s: f64,
}

impl Schedule {
    /// The slots of one cycle in start order.
    pub fn slots(&self, tau: f64, n_auvs: usize, n_buoys: usize) -> Vec<Slot> {
        let mut slots = match self {
            Schedule::BroadcastThenStatus {} => {
                let length_s = tau / (1 + n_buoys + n_auvs) as f64;
                std::iter::once(Owner::Cna)
                    .chain((0..n_buoys).map(Owner::Buoy))
                    .chain((0..n_auvs).map(Owner::Auv))
                    .enumerate()
                    .map(|(i, owner)| Slot { owner, start_s: i as f64 * length_s, length_s })
                    .collect::<Vec<_>>()
            }
            Schedule::Tdma { slots } => slots
                .iter()
                .filter_map(|s| Some(Slot { owner: parse_owner(&s.who)?, start_s: s.start_s, length_s: s.length_s }))
                .collect(),
        };
        slots.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        slots
    }

    /// Every problem, as (field under `prefix`, value, allowed).
    pub fn problems(&self, prefix: &str, fit: &Fit) -> Vec<(String, String, String)> {
        let mut out = Vec::new();
        if let Schedule::Tdma { slots } = self {
            if slots.is_empty() {
                out.push((format!("{prefix}slots"), "[]".into(), "at least one slot".into()));
            }
            for (i, s) in slots.iter().enumerate() {
                let field = |f: &str| format!("{prefix}slots[{i}].{f}");
                let known = match parse_owner(&s.who) {
                    Some(Owner::Cna) => true,
                    Some(Owner::Auv(k)) => k < fit.n_auvs,
                    Some(Owner::Buoy(b)) => b < fit.n_buoys,
                    None => false,
                };
                if !known {
                    out.push((field("who"), s.who.clone(), owners_allowed(fit)));
                }
                if !(s.start_s.is_finite() && s.start_s >= 0.0 && s.length_s.is_finite() && s.length_s > 0.0) {
                    out.push((
                        field("start_s"),
                        format!("{} + {}", s.start_s, s.length_s),
                        "start >= 0, length > 0".into(),
                    ));
                } else if s.start_s + s.length_s > fit.tau + 1e-9 {
                    out.push((
                        field("length_s"),
                        s.length_s.to_string(),
                        format!("the slot to end by comms.tau = {}", fit.tau),
                    ));
                }
            }
        }
        let slots = self.slots(fit.tau, fit.n_auvs, fit.n_buoys);
        for (i, pair) in slots.windows(2).enumerate() {
            if pair[0].start_s + pair[0].length_s > pair[1].start_s + 1e-9 {
                out.push((
                    format!("{prefix}slot {}", i + 1),
                    format!("{:?}", pair[1].owner),
                    "slots that do not overlap".into(),
                ));
            }
        }
        for (i, s) in slots.iter().enumerate() {
            let (who, air) = match s.owner {
                Owner::Cna => ("cna".to_string(), fit.cna_air_s),
                Owner::Buoy(b) => (format!("buoy{b}"), fit.buoy_air_s),
                Owner::Auv(k) => (format!("auv{k}"), fit.status_air_s),
            };
            let need = air + fit.travel_s + fit.guard_s;
            if s.length_s + 1e-9 < need {
                out.push((
                    format!("{prefix}slot {i} ({who}, at {:.2} s)", s.start_s),
                    format!("{:.2} s long", s.length_s),
                    format!(
                        ">= {need:.2} s: air time {air:.2} s + longest travel {:.2} s + guard {:.2} s (lengthen comms.tau, \
                         use faster rates or fewer slots)",
                        fit.travel_s, fit.guard_s
                    ),
                ));
            }
        }
        out
    }
}

fn parse_owner(who: &str) -> Option<Owner> {
    let numbered = |prefix: &str| who.strip_prefix(prefix)?.parse().ok();
    match who {
        "cna" => Some(Owner::Cna),
        _ => numbered("auv").map(Owner::Auv).or_else(|| numbered("buoy").map(Owner::Buoy)),
    }
}

/// The owners a slot may name, for an error message.
fn owners_allowed(fit: &Fit) -> String {
    let auvs = format!("auv0..auv{}", fit.n_auvs.saturating_sub(1));
    match fit.n_buoys {
        0 => format!("cna or {auvs}"),
        b => format!("cna, buoy0..buoy{} or {auvs}", b - 1),
    }
}

/// The message at `rate` carrying `bytes`: a problem unless the rate's frames hold it.
pub fn payload_problem(field: &str, rate: Rate, bytes: usize) -> Option<(String, String, String)> {
    (bytes > capacity(rate)).then(|| {
        (field.to_string(), format!("rate {rate}"), format!("a rate whose frames hold the {bytes}-byte message"))
    })
}

/// Longest air time of any of `rates`.
pub fn longest_air(rates: impl IntoIterator<Item = Rate>) -> f64 {
    rates.into_iter().map(air_time).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit(tau: f64, n: usize) -> Fit {
        Fit {
            tau,
            n_auvs: n,
            n_buoys: 0,
            cna_air_s: 3.9,
            buoy_air_s: 3.9,
            status_air_s: 3.9,
            travel_s: 0.7,
            guard_s: 0.2,
        }
    }

    #[test]
    fn hudsons_preset_spreads_the_cycle_evenly() {
        let s = Schedule::default().slots(30.0, 2, 0);
        assert_eq!(
            s.iter().map(|s| (s.owner, s.start_s)).collect::<Vec<_>>(),
            [(Owner::Cna, 0.0), (Owner::Auv(0), 10.0), (Owner::Auv(1), 20.0)]
        );
        assert!(Schedule::default().problems("comms.schedule.", &fit(30.0, 5)).is_empty());
    }

    #[test]
    fn buoy_slots_follow_the_cnas_and_a_missing_buoy_is_refused() {
        let s = Schedule::default().slots(40.0, 2, 2);
        assert_eq!(
            s.iter().map(|s| (s.owner, s.start_s)).collect::<Vec<_>>(),
            [
                (Owner::Cna, 0.0),
                (Owner::Buoy(0), 8.0),
                (Owner::Buoy(1), 16.0),
                (Owner::Auv(0), 24.0),
                (Owner::Auv(1), 32.0)
            ]
        );
        let slot = |who: &str, start_s| SlotSpec { who: who.into(), start_s, length_s: 10.0 };
        let tdma = Schedule::Tdma { slots: vec![slot("cna", 0.0), slot("buoy0", 10.0), slot("buoy2", 20.0)] };
        let p = tdma.problems("s.", &Fit { n_buoys: 2, ..fit(30.0, 1) });
        assert_eq!(p.len(), 1, "{p:?}");
        assert_eq!((p[0].0.as_str(), p[0].2.as_str()), ("s.slots[2].who", "cna, buoy0..buoy1 or auv0..auv0"));
    }

    #[test]
    fn a_schedule_that_cannot_fit_is_refused_naming_the_slot() {
        // Eight AUVs in 30 s: 3.33 s slots, shorter than 3.9 s of air time alone.
        let p = Schedule::default().problems("comms.schedule.", &fit(30.0, 8));
        assert_eq!(p.len(), 9, "{p:?}");
        assert!(p[3].0.contains("slot 3 (auv2"), "{p:?}");
        assert!(p[3].2.contains("air time 3.90 s") && p[3].2.contains("travel 0.70 s"), "{p:?}");
        let tdma = Schedule::Tdma {
            slots: vec![
                SlotSpec { who: "cna".into(), start_s: 0.0, length_s: 6.0 },
                SlotSpec { who: "auv0".into(), start_s: 6.0, length_s: 4.0 },
                SlotSpec { who: "auv7".into(), start_s: 10.0, length_s: 25.0 },
            ],
        };
        let p = tdma.problems("s.", &fit(30.0, 1));
        let fields: Vec<&str> = p.iter().map(|x| x.0.as_str()).collect();
        assert!(fields.contains(&"s.slots[2].who") && fields.contains(&"s.slots[2].length_s"), "{p:?}");
        assert!(fields.iter().any(|f| f.starts_with("s.slot 1 (auv0")), "{p:?}");
    }

    #[test]
    fn a_message_longer_than_the_rate_is_refused() {
        assert!(payload_problem("comms.status_rate", Rate::R0, 26).is_none());
        let p = payload_problem("comms.status_rate", Rate::R0, 40).unwrap();
        assert!(p.0 == "comms.status_rate" && p.2.contains("40-byte"), "{p:?}");
    }
}
