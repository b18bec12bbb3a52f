//! The comms schedule as data: one TDMA cycle of period τ, a list of slots each owned by the CNA
//! (its broadcast), a buoy (its position broadcast, or one state component as a mini-packet), a
//! ship's port or starboard modem (a mini-packet) or one survey AUV (its status message).
//! `broadcast_then_status` is Hudson's preset (the CNA at m·τ, then AUV j at m·τ + (j + 1)·τ/(N + 1));
//! with B buoys their slots follow the CNA's, every slot τ/(1 + B + N); `gill_cycle` is Gill's MSBL /
//! HBL Short / HBL Long cycle (Gill 2013, §2.3.2, Table 1) of 2 s mini-packet slots from ship0 and
//! buoy0; `tdma` lists the slots, and a survey AUV's slot may name the rate policy its status
//! messages use (`rate_policy`, a [`RatePolicySpec`]; otherwise the comms default), the CNA's slot
//! the rate policy of its broadcast (otherwise `comms.cna_rate`). Validation
//! refuses a slot shorter than its packet's air time plus the longest expected travel time plus a
//! guard, naming the slot, and a message too long for its rate.

use super::channel::{air_time, capacity};
use coopnav_acomms::selector::RatePolicySpec;
use coopnav_acomms::Rate;
use coopnav_core::validation::Problems;
use coopnav_nav::cycle::{Configuration, Cycle, Transmitter};
use coopnav_nav::{Side, StateKind};
use serde::{Deserialize, Serialize};

/// Who transmits in a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Owner {
    Cna,
    Buoy(usize),
    Auv(usize),
    /// One of ship i's two outrigger modems.
    Ship(usize, Side),
}

/// What a slot's owner sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Message {
    /// The owner's own packet at its WHOI rate (the CNA's broadcast, a buoy's position report,
    /// an AUV's status).
    Packet,
    /// A 13-bit mini-packet: a ranging ping carrying one quantised state component.
    Mini(StateKind),
}

/// One slot of the cycle, seconds after the cycle start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    pub owner: Owner,
    pub start_s: f64,
    pub length_s: f64,
    pub message: Message,
}

/// A slot as written in the file: `who = "cna"`, `"buoy0"`, …, `"ship0.port"`, `"ship0.starboard"`,
/// … or `"auv0"`, `"auv1"`, …; `message` (`east`, `north`, `speed` or `heading`) makes it a
/// mini-packet carrying that state component (a ship's slot must name one); `rate_policy` on a
/// survey AUV's slot picks the rate of its status messages, on the CNA's slot the rate of its
/// broadcast (every slot of one owner names the same).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlotSpec {
    pub who: String,
    pub start_s: f64,
    pub length_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<StateKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_policy: Option<RatePolicySpec>,
}

impl SlotSpec {
    /// `who`'s own packet at the comms default rate, `length_s` long from `start_s`.
    pub fn packet(who: &str, start_s: f64, length_s: f64) -> Self {
        SlotSpec { who: who.into(), start_s, length_s, message: None, rate_policy: None }
    }
}

/// Gill's cycle presets (Table 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GillCycle {
    Msbl,
    HblShort,
    HblLong,
}

impl GillCycle {
    pub fn cycle(self) -> Cycle {
        match self {
            GillCycle::Msbl => Cycle::msbl(),
            GillCycle::HblShort => Cycle::hbl_short(),
            GillCycle::HblLong => Cycle::hbl_long(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Schedule {
    BroadcastThenStatus {},
    Tdma {
        slots: Vec<SlotSpec>,
    },
    /// Gill's cycle: every slot a mini-packet from ship0's port or starboard modem or from buoy0,
    /// the ship's slots assigned to its modems by the navigation `configuration` (MSBL and HBL
    /// Two alternate port and starboard, HBL One uses port only; invented, docs/models.md#gill-cycles). The
    /// cycle's period must be `comms.tau`.
    GillCycle {
        cycle: GillCycle,
        configuration: Configuration,
    },
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
    pub n_ships: usize,
    /// Longest air time any rate the CNA / a buoy / an AUV may use takes (an AUV whose slot names
    /// its own rate policy: that policy's rates), and a mini-packet's.
    pub cna_air_s: f64,
    pub buoy_air_s: f64,
    pub status_air_s: f64,
    pub mini_air_s: f64,
    /// Size of a survey AUV's status message, bytes (every rate of a slot's policy must hold it).
    pub status_bytes: usize,
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
                    .map(|(i, owner)| Slot { owner, start_s: i as f64 * length_s, length_s, message: Message::Packet })
                    .collect::<Vec<_>>()
            }
            Schedule::Tdma { slots } => slots
                .iter()
                .filter_map(|s| {
                    Some(Slot {
                        owner: parse_owner(&s.who)?,
                        start_s: s.start_s,
                        length_s: s.length_s,
                        message: s.message.map_or(Message::Packet, Message::Mini),
                    })
                })
                .collect(),
            Schedule::GillCycle { cycle, configuration } => gill_slots(&cycle.cycle(), *configuration),
        };
        slots.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
        slots
    }

    /// The rate policy survey AUV `auv`'s slots name, if any (else the comms default applies).
    pub fn status_policy(&self, auv: usize) -> Option<&RatePolicySpec> {
        self.policy_of(Owner::Auv(auv))
    }

    /// The rate policy the CNA's slots name, if any (else its broadcast is at `comms.cna_rate`).
    pub fn cna_policy(&self) -> Option<&RatePolicySpec> {
        self.policy_of(Owner::Cna)
    }

    fn policy_of(&self, owner: Owner) -> Option<&RatePolicySpec> {
        let Schedule::Tdma { slots } = self else { return None };
        slots.iter().filter(|s| parse_owner(&s.who) == Some(owner)).find_map(|s| s.rate_policy.as_ref())
    }

    /// Checks the schedule under `prefix` against what it must carry (`fit`). It takes `fit`, so it
    /// is [`CheckFields`]'s shape with one more argument rather than an impl of it.
    pub fn check_fields(&self, prefix: &str, fit: &Fit, p: &mut Problems) {
        if let Schedule::GillCycle { cycle, configuration } = self {
            let period = cycle.cycle().period();
            if (period - fit.tau).abs() > 1e-9 {
                p.push("comms.tau", fit.tau.to_string(), format!("{period} s, the period of Gill's cycle"));
            }
            if fit.n_ships == 0 {
                p.push(format!("{prefix}kind"), "gill_cycle", "a scenario with a [[ships]] entry");
            }
            if configuration.has_buoy() && fit.n_buoys == 0 {
                p.push(
                    format!("{prefix}configuration"),
                    configuration.label(),
                    "msbl, or a scenario with a [[buoys]] entry (HBL ranges to buoy0)",
                );
            }
        }
        if let Schedule::Tdma { slots } = self {
            if slots.is_empty() {
                p.push(format!("{prefix}slots"), "[]", "at least one slot");
            }
            for (i, s) in slots.iter().enumerate() {
                let field = |f: &str| format!("{prefix}slots[{i}].{f}");
                let owner = parse_owner(&s.who);
                let known = match owner {
                    Some(Owner::Cna) => true,
                    Some(Owner::Auv(k)) => k < fit.n_auvs,
                    Some(Owner::Buoy(b)) => b < fit.n_buoys,
                    Some(Owner::Ship(i, _)) => i < fit.n_ships,
                    None => false,
                };
                if !known {
                    p.push(field("who"), s.who.clone(), owners_allowed(fit));
                }
                match (owner, s.message) {
                    (Some(Owner::Ship(..)), None) => p.push(field("message"), "none", "east, north, speed or heading"),
                    (Some(Owner::Cna | Owner::Auv(_)), Some(kind)) => p.push(
                        field("message"),
                        format!("{kind:?}").to_lowercase(),
                        "no message: mini-packets come from ships and buoys",
                    ),
                    _ => {}
                }
                if let Some(spec) = &s.rate_policy {
                    check_rate_policy(&field("rate_policy"), owner, spec, fit.status_bytes, p);
                    let first = match owner {
                        Some(o @ (Owner::Auv(_) | Owner::Cna)) => self.policy_of(o),
                        _ => Some(spec),
                    };
                    if first != Some(spec) {
                        p.push(
                            field("rate_policy"),
                            format!("{spec:?}"),
                            format!("the rate policy of {}'s first slot (one policy per transmitter)", s.who),
                        );
                    }
                }
                if !(s.start_s.is_finite() && s.start_s >= 0.0 && s.length_s.is_finite() && s.length_s > 0.0) {
                    p.push(field("start_s"), format!("{} + {}", s.start_s, s.length_s), "start >= 0, length > 0");
                } else if s.start_s + s.length_s > fit.tau + 1e-9 {
                    p.push(
                        field("length_s"),
                        s.length_s.to_string(),
                        format!("the slot to end by comms.tau = {}", fit.tau),
                    );
                }
            }
        }
        let slots = self.slots(fit.tau, fit.n_auvs, fit.n_buoys);
        for (i, pair) in slots.windows(2).enumerate() {
            if pair[0].start_s + pair[0].length_s > pair[1].start_s + 1e-9 {
                p.push(format!("{prefix}slot {}", i + 1), format!("{:?}", pair[1].owner), "slots that do not overlap");
            }
        }
        for (i, s) in slots.iter().enumerate() {
            let who = owner_name(s.owner);
            let air = match (s.message, s.owner) {
                (Message::Mini(_), _) | (Message::Packet, Owner::Ship(..)) => fit.mini_air_s,
                (Message::Packet, Owner::Cna) => match self.cna_policy().map(RatePolicySpec::rates) {
                    Some(Ok(rates)) => longest_air(rates),
                    _ => fit.cna_air_s,
                },
                (Message::Packet, Owner::Buoy(_)) => fit.buoy_air_s,
                (Message::Packet, Owner::Auv(k)) => match self.status_policy(k).map(RatePolicySpec::rates) {
                    Some(Ok(rates)) => longest_air(rates),
                    _ => fit.status_air_s,
                },
            };
            let need = air + fit.travel_s + fit.guard_s;
            if s.length_s + 1e-9 < need {
                p.push(
                    format!("{prefix}slot {i} ({who}, at {:.2} s)", s.start_s),
                    format!("{:.2} s long", s.length_s),
                    format!(
                        ">= {need:.2} s: air time {air:.2} s + longest travel {:.2} s + guard {:.2} s (lengthen comms.tau, \
                         use faster rates or fewer slots)",
                        fit.travel_s, fit.guard_s
                    ),
                );
            }
        }
    }
}

/// A slot's `rate_policy` (at `field`): only on a survey AUV's or the CNA's slot, a valid policy,
/// and (an AUV's) every rate holding the status message. The CNA's broadcast (its fix and one ack
/// per AUV) fits the smallest frame of every rate.
fn check_rate_policy(field: &str, owner: Option<Owner>, spec: &RatePolicySpec, status_bytes: usize, p: &mut Problems) {
    if !matches!(owner, Some(Owner::Auv(_) | Owner::Cna)) {
        return p.push(field, format!("{spec:?}"), "no rate policy: only a survey AUV's or the CNA's slot names one");
    }
    match (spec.rates(), owner) {
        (Ok(rates), Some(Owner::Auv(_))) => rates.into_iter().for_each(|r| check_payload(field, r, status_bytes, p)),
        (Ok(_), _) => {}
        (Err(e), _) => p.push(field, "rejected", e.to_string()),
    }
}

/// Gill's cycle as slots: each slot carrying a ship or buoy state becomes a mini-packet from the
/// modem the configuration assigns it (silent and fleet-leader slots, and buoy slots without a
/// buoy, send nothing).
fn gill_slots(cycle: &Cycle, configuration: Configuration) -> Vec<Slot> {
    let length_s = cycle.slot_seconds;
    configuration
        .assign(cycle)
        .into_iter()
        .zip(&cycle.slots)
        .enumerate()
        .filter_map(|(i, (from, content))| {
            let owner = match from? {
                Transmitter::Ship(side) => Owner::Ship(0, side),
                Transmitter::Buoy => Owner::Buoy(0),
            };
            let (_, kind) = content.state()?;
            Some(Slot { owner, start_s: i as f64 * length_s, length_s, message: Message::Mini(kind) })
        })
        .collect()
}

fn parse_owner(who: &str) -> Option<Owner> {
    let numbered = |prefix: &str| who.strip_prefix(prefix)?.parse().ok();
    let ship = || {
        let (ship, side) = who.strip_prefix("ship")?.split_once('.')?;
        let side = match side {
            "port" => Side::Port,
            "starboard" => Side::Starboard,
            _ => return None,
        };
        Some(Owner::Ship(ship.parse().ok()?, side))
    };
    match who {
        "cna" => Some(Owner::Cna),
        _ => numbered("auv").map(Owner::Auv).or_else(|| numbered("buoy").map(Owner::Buoy)).or_else(ship),
    }
}

/// A slot owner as a file names it.
pub fn owner_name(owner: Owner) -> String {
    match owner {
        Owner::Cna => "cna".into(),
        Owner::Buoy(b) => format!("buoy{b}"),
        Owner::Auv(k) => format!("auv{k}"),
        Owner::Ship(i, Side::Port) => format!("ship{i}.port"),
        Owner::Ship(i, Side::Starboard) => format!("ship{i}.starboard"),
    }
}

/// The owners a slot may name, for an error message.
fn owners_allowed(fit: &Fit) -> String {
    let mut named = vec!["cna".to_string()];
    if fit.n_buoys > 0 {
        named.push(format!("buoy0..buoy{}", fit.n_buoys - 1));
    }
    if fit.n_ships > 0 {
        named.push(format!("ship0..ship{}.port or .starboard", fit.n_ships - 1));
    }
    let auvs = format!("auv0..auv{}", fit.n_auvs.saturating_sub(1));
    format!("{} or {auvs}", named.join(", "))
}

/// The message at `rate` carrying `bytes`: a problem at `field` unless the rate's frames hold it.
pub fn check_payload(field: &str, rate: Rate, bytes: usize, p: &mut Problems) {
    if bytes > capacity(rate) {
        p.push(field, format!("rate {rate}"), format!("a rate whose frames hold the {bytes}-byte message"));
    }
}

/// Longest air time of any of `rates`.
pub fn longest_air(rates: impl IntoIterator<Item = Rate>) -> f64 {
    rates.into_iter().map(air_time).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_acomms::selector::AdaptiveConfig;
    use coopnav_core::validation::Problem;

    /// Every problem `schedule` has under `prefix`, in the order found.
    fn problems_of(schedule: &Schedule, prefix: &str, fit: &Fit) -> Vec<Problem> {
        let mut p = Problems::new();
        schedule.check_fields(prefix, fit, &mut p);
        p.finish().err().map(|e| e.0).unwrap_or_default()
    }

    fn fit(tau: f64, n: usize) -> Fit {
        Fit {
            tau,
            n_auvs: n,
            n_buoys: 0,
            n_ships: 0,
            cna_air_s: 3.9,
            buoy_air_s: 3.9,
            status_air_s: 3.9,
            mini_air_s: 0.5,
            status_bytes: 30,
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
        assert!(problems_of(&Schedule::default(), "comms.schedule.", &fit(30.0, 5)).is_empty());
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
        let slot = |who: &str, start_s| SlotSpec::packet(who, start_s, 10.0);
        let tdma = Schedule::Tdma { slots: vec![slot("cna", 0.0), slot("buoy0", 10.0), slot("buoy2", 20.0)] };
        let p = problems_of(&tdma, "s.", &Fit { n_buoys: 2, ..fit(30.0, 1) });
        assert_eq!(p.len(), 1, "{p:?}");
        assert_eq!((p[0].field.as_str(), p[0].allowed.as_str()), ("s.slots[2].who", "cna, buoy0..buoy1 or auv0..auv0"));
    }

    #[test]
    fn a_schedule_that_cannot_fit_is_refused_naming_the_slot() {
        // Eight AUVs in 30 s: 3.33 s slots, shorter than 3.9 s of air time alone.
        let p = problems_of(&Schedule::default(), "comms.schedule.", &fit(30.0, 8));
        assert_eq!(p.len(), 9, "{p:?}");
        assert!(p[3].field.contains("slot 3 (auv2"), "{p:?}");
        assert!(p[3].allowed.contains("air time 3.90 s") && p[3].allowed.contains("travel 0.70 s"), "{p:?}");
        let tdma = Schedule::Tdma {
            slots: vec![
                SlotSpec::packet("cna", 0.0, 6.0),
                SlotSpec::packet("auv0", 6.0, 4.0),
                SlotSpec::packet("auv7", 10.0, 25.0),
            ],
        };
        let p = problems_of(&tdma, "s.", &fit(30.0, 1));
        let fields: Vec<&str> = p.iter().map(|x| x.field.as_str()).collect();
        assert!(fields.contains(&"s.slots[2].who") && fields.contains(&"s.slots[2].length_s"), "{p:?}");
        assert!(fields.iter().any(|f| f.starts_with("s.slot 1 (auv0")), "{p:?}");
    }

    #[test]
    fn gills_cycles_are_mini_packet_slots_from_the_assigned_modems() {
        use Side::{Port, Starboard};
        let hbl_two = Schedule::GillCycle { cycle: GillCycle::HblLong, configuration: Configuration::HblTwo };
        let slots = hbl_two.slots(20.0, 1, 1);
        let seen: Vec<(Owner, f64, Message)> = slots.iter().map(|s| (s.owner, s.start_s, s.message)).collect();
        use StateKind::{East, Heading, North, Speed};
        assert_eq!(
            seen,
            [
                (Owner::Ship(0, Port), 0.0, Message::Mini(East)),
                (Owner::Ship(0, Starboard), 2.0, Message::Mini(North)),
                (Owner::Buoy(0), 4.0, Message::Mini(North)),
                (Owner::Ship(0, Port), 6.0, Message::Mini(Speed)),
                (Owner::Ship(0, Starboard), 8.0, Message::Mini(Heading)),
                (Owner::Buoy(0), 10.0, Message::Mini(East)),
                (Owner::Ship(0, Port), 14.0, Message::Mini(East)),
                (Owner::Buoy(0), 16.0, Message::Mini(North)),
            ]
        );
        assert!(slots.iter().all(|s| s.length_s == 2.0));
        // MSBL: the buoy's slots are silent; HBL One: the port modem only.
        let msbl = Schedule::GillCycle { cycle: GillCycle::Msbl, configuration: Configuration::Msbl }.slots(20.0, 1, 0);
        assert_eq!(msbl.len(), 5);
        assert!(msbl.iter().all(|s| matches!(s.owner, Owner::Ship(0, _))));
        let one = Schedule::GillCycle { cycle: GillCycle::HblLong, configuration: Configuration::HblOne };
        assert!(one.slots(20.0, 1, 1).iter().all(|s| s.owner != Owner::Ship(0, Starboard)));
        let with_ship = Fit { n_ships: 1, n_buoys: 1, travel_s: 0.67, guard_s: 0.1, ..fit(20.0, 1) };
        assert!(problems_of(&hbl_two, "comms.schedule.", &with_ship).is_empty());
    }

    #[test]
    fn a_mini_packet_fits_a_two_second_slot_and_a_rate_0_packet_does_not() {
        let fit = Fit { n_ships: 1, n_buoys: 1, travel_s: 0.67, guard_s: 0.1, ..fit(20.0, 1) };
        let slot = |who: &str, start_s, message| SlotSpec {
            who: who.into(),
            start_s,
            length_s: 2.0,
            message,
            rate_policy: None,
        };
        let tdma = Schedule::Tdma {
            slots: vec![
                slot("ship0.port", 0.0, Some(StateKind::East)),
                slot("buoy0", 2.0, Some(StateKind::North)),
                // The buoy's full position report at rate 0: 3.9 s of air time in a 2 s slot.
                slot("buoy0", 4.0, None),
            ],
        };
        let p = problems_of(&tdma, "s.", &fit);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].field.starts_with("s.slot 2 (buoy0, at 4.00 s)") && p[0].allowed.contains("air time 3.90 s"),
            "{p:?}"
        );
        // A ship slot must name its component, a CNA slot may not; a Gill cycle needs its period.
        let bad = Schedule::Tdma {
            slots: vec![
                slot("ship0.port", 0.0, None),
                slot("cna", 2.0, Some(StateKind::East)),
                slot("ship1.port", 4.0, None),
            ],
        };
        let fields: Vec<String> = problems_of(&bad, "s.", &fit).into_iter().map(|p| p.field).collect();
        assert_eq!(fields, ["s.slots[0].message", "s.slots[1].message", "s.slots[2].who", "s.slots[2].message"]);
        let gill = Schedule::GillCycle { cycle: GillCycle::HblShort, configuration: Configuration::HblTwo };
        let p = problems_of(&gill, "s.", &fit);
        assert_eq!(
            (p.len(), p[0].field.as_str(), p[0].allowed.as_str()),
            (1, "comms.tau", "16 s, the period of Gill's cycle")
        );
        assert!(problems_of(&gill, "s.", &Fit { tau: 16.0, ..fit }).is_empty());
        let p = problems_of(&gill, "s.", &Fit { tau: 16.0, n_buoys: 0, n_ships: 0, ..fit });
        let fields: Vec<&str> = p.iter().map(|p| p.field.as_str()).collect();
        assert_eq!(fields, ["s.kind", "s.configuration"], "{p:?}");
    }

    #[test]
    fn a_slots_rate_policy_sizes_its_slot_and_is_refused_where_it_does_not_belong() {
        let r5 = RatePolicySpec::Fixed { rate: Rate::R5 };
        let slot = |who: &str, start_s, length_s, rate_policy| SlotSpec {
            who: who.into(),
            start_s,
            length_s,
            message: None,
            rate_policy,
        };
        // 4 s holds rate 5's 3.04 s of air time + 0.9 s, not the comms default's 3.9 s.
        let short =
            |policy| Schedule::Tdma { slots: vec![slot("cna", 0.0, 10.0, None), slot("auv0", 10.0, 4.0, policy)] };
        assert!(problems_of(&short(Some(r5.clone())), "s.", &fit(30.0, 1)).is_empty());
        assert_eq!(short(Some(r5.clone())).status_policy(0), Some(&r5));
        let p = problems_of(&short(None), "s.", &fit(30.0, 1));
        assert!(
            p.len() == 1 && p[0].field.starts_with("s.slot 1 (auv0") && p[0].allowed.contains("air time 3.90 s"),
            "{p:?}"
        );
        // The CNA's slot too: sized by its policy's slowest rate, not by comms.cna_rate's.
        let cna = |length_s, policy| Schedule::Tdma { slots: vec![slot("cna", 0.0, length_s, policy)] };
        assert!(problems_of(&cna(4.0, Some(r5.clone())), "s.", &fit(30.0, 0)).is_empty());
        assert_eq!(cna(4.0, Some(r5.clone())).cna_policy(), Some(&r5));
        let p = problems_of(&cna(4.0, None), "s.", &fit(30.0, 0));
        assert!(
            p.len() == 1 && p[0].field.starts_with("s.slot 0 (cna") && p[0].allowed.contains("air time 3.90 s"),
            "{p:?}"
        );
        // A policy on a buoy's slot, two policies for one AUV, a rate too small for the
        // 40-byte status, and an invalid adaptive configuration are each named.
        let bad_adaptive = RatePolicySpec::Adaptive(AdaptiveConfig { memory: 0, ..AdaptiveConfig::default() });
        let bad = Schedule::Tdma {
            slots: vec![
                slot("buoy0", 0.0, 5.0, Some(r5.clone())),
                slot("auv0", 5.0, 5.0, Some(r5.clone())),
                slot("auv0", 10.0, 5.0, Some(RatePolicySpec::Fixed { rate: Rate::R0 })),
                slot("auv1", 15.0, 5.0, Some(bad_adaptive)),
            ],
        };
        let p = problems_of(&bad, "s.", &Fit { status_bytes: 40, n_buoys: 1, ..fit(30.0, 2) });
        let named: Vec<(&str, &str)> = p.iter().map(|p| (p.field.as_str(), p.allowed.as_str())).collect();
        assert_eq!(
            named,
            [
                ("s.slots[0].rate_policy", "no rate policy: only a survey AUV's or the CNA's slot names one"),
                ("s.slots[2].rate_policy", "a rate whose frames hold the 40-byte message"),
                ("s.slots[2].rate_policy", "the rate policy of auv0's first slot (one policy per transmitter)"),
                ("s.slots[3].rate_policy", "the adaptive selector: field memory = 0: allowed an integer >= 1"),
            ]
        );
    }

    #[test]
    fn a_file_names_a_slots_rate_policy_by_kind() {
        let text = r#"kind = "tdma"
slots = [{ who = "cna", start_s = 0.0, length_s = 10.0 },
         { who = "auv0", start_s = 10.0, length_s = 10.0, rate_policy = { kind = "adaptive", memory = 5 } },
         { who = "auv1", start_s = 20.0, length_s = 10.0, rate_policy = { kind = "alternating", rates = [0, 5] } }]"#;
        let s: Schedule = toml::from_str(text).unwrap();
        let adaptive = RatePolicySpec::Adaptive(AdaptiveConfig { memory: 5, ..AdaptiveConfig::default() });
        assert_eq!(s.status_policy(0), Some(&adaptive));
        assert_eq!(s.status_policy(1), Some(&RatePolicySpec::Alternating { rates: vec![Rate::R0, Rate::R5] }));
        assert_eq!(s.status_policy(2), None);
        let typo = text.replace("memory", "memroy");
        assert!(toml::from_str::<Schedule>(&typo).unwrap_err().to_string().contains("memroy"));
    }

    #[test]
    fn a_message_longer_than_the_rate_is_refused() {
        let payload = |bytes| {
            let mut p = Problems::new();
            check_payload("comms.status_rate", Rate::R0, bytes, &mut p);
            p.finish().err().map(|e| e.0).unwrap_or_default()
        };
        assert!(payload(26).is_empty());
        let p = payload(40);
        assert!(p.len() == 1 && p[0].field == "comms.status_rate" && p[0].allowed.contains("40-byte"), "{p:?}");
    }
}
