//! The phases of one engine step, in the order [`super::Engine::step`] runs them:
//! decide (the CNA's policy every τ), advance (truth of every vehicle), transmit (the slots due:
//! the CNA's broadcast, a buoy's position, an AUV's status: encode, channel draw, travel time,
//! into the water), deliver (packets whose arrival ended, in
//! time order, with their fate), sense (filter prediction and dead-reckoning sensors) and observe
//! (metrics and the observer, once per second).

use super::inflight::Arrival;
use super::observe::{
    BuoyFix, CnaChoice, CnaFix, CnaStatusHeard, CommsEvent, DeadReckoning, Decision, LinkArrival, Observer, RangeHeard,
    RangeUpdate, ShadowSample, ShipPose, StatusChoice, StatusFrames, StatusSent, TraceRow,
};
use super::peer::PeerLink;
use super::vehicles::lerp;
use super::vehicles::SurveyAuv;
use super::{Engine, FleetView};
use crate::models::channel::{air_time, Clock};
use crate::models::channel::{RECEIVER_AT_CNA, RECEIVER_AT_SURVEY_AUV};
use crate::models::finish::Finish;
use crate::models::health::nees_2d;
use crate::models::minipacket::SUCCESS_RATE;
use crate::models::peer::{StatusFormat, StatusTo};
use crate::models::schedule::{Message, Owner};
use crate::models::surfacing::Step;
use crate::policy::belief::read_node_status;
use crate::policy::ReportedCov;
use crate::policy::{CnaCommand, PolicyContext};
use crate::scenario::world::Scenario;
use coopnav_acomms::codec::EncodeError;
use coopnav_acomms::selector::{Choice, Outcome};
use coopnav_acomms::status::{CovTrailer, CovarianceReport};
use coopnav_acomms::status::{Frame0, LocalOrigin, NextWaypoint};
use coopnav_acomms::{Rate, Reception};
use coopnav_core::{Heading, Vec3};
use coopnav_nav::{RangeMeasurement, StateKind};
use coopnav_plan::predict::StatusReport;
use coopnav_plan::{AuvForecast, CnaPose};
use rand_chacha::ChaCha8Rng;

/// What a packet carries to its addressee.
#[derive(Clone)]
pub enum Payload {
    /// The CNA's broadcast: its position as it knows it, the travel time the receiver measured
    /// (None: decoded without a usable range), and the statuses it acknowledges.
    /// `id` counts the CNA's broadcast slots.
    Broadcast { id: u64, rate: Rate, fix: Vec3, travel_time: Option<f64>, acked: Vec<u64>, decoded: bool },
    /// A buoy's position broadcast: its GPS fix and the travel time the receiver measured.
    Position { rate: Rate, fix: Vec3, travel_time: Option<f64>, decoded: bool },
    /// A survey AUV's status message through the wire format, and which of its frames the
    /// channel let through to this receiver; to the CNA, the broadcasts it acknowledges.
    Status { rate: Rate, slot_id: u64, bytes: Vec<u8>, decoded: bool, reception: Reception, heard_broadcasts: Vec<u64> },
    /// A ship's or buoy's 13-bit mini-packet: one decoded state component and the travel time
    /// the receiver measured (see [`super::mini`]).
    Mini { kind: StateKind, value: f64, travel_time: Option<f64>, decoded: bool },
}

impl Engine<'_> {
    /// Whether the CNA's next decision falls in the step ending at `t_next`.
    pub(super) fn decision_due(&self, t_next: f64) -> bool {
        (self.next_decision as f64) * self.sc.comms.tau < t_next - 1e-9
    }

    /// The CNA's decision at each m·τ: its position fix, then the policy's command.
    /// Reads: the scenario, the CNA's predictors and the statuses it was sent. Writes: the CNA's
    /// own navigation (its surfacing cycle, its navigation error and the GPS and navigation
    /// draws), its target, the policy's state and the decision counter. Reports the fix
    /// ([`Observer::on_cna_fix`]) and the decision.
    pub(super) fn decide(&mut self, t_next: f64, obs: &mut dyn Observer) {
        let tau = self.sc.comms.tau;
        if !self.decision_due(t_next) {
            return;
        }
        let t_dec = self.next_decision as f64 * tau;
        self.next_decision += 1;
        let navigation = &self.sc.cna.navigation;
        let step = self.cna.own.step(navigation.surfacing(), t_dec, self.cna.craft.pos.z);
        let fix = self.cna_fix(t_dec, matches!(step, Step::Fix { .. } | Step::WorkWithFix));
        let transmits = self.policy.as_policy().transmits();
        let cna = &mut self.cna;
        let fleet = FleetView { predictors: &cna.predictors, min_reports: self.sc.policy.start_after_reports };
        let forecast: Vec<Option<Vec3>> =
            if transmits { (0..self.auvs.len()).map(|k| fleet.position(k, t_dec)).collect() } else { Vec::new() };
        obs.on_cna_fix(&CnaFix { t: t_dec, fix, transmits, forecast: &forecast });
        let pose = CnaPose { pos: fix, heading: Heading::from_radians(cna.craft.heading), pitch: 0.0 };
        let ctx = PolicyContext {
            t: t_dec,
            tau,
            cna: pose,
            speed: self.sc.cna.speed,
            fleet: &fleet,
            reported: &cna.reported,
            cna_variance: navigation.variance(&cna.own, t_dec),
        };
        let here = cna.craft.pos;
        // The policy decides even while the CNA surfaces, so its own models keep stepping.
        let command = self.policy.as_policy().decide(&ctx);
        cna.craft.target = target(step, command, here, fix, here, None);
        cna.last_decision = Some((step, here, fix));
        obs.on_decision(&Decision { t: t_dec, from: here, to: cna.craft.target });
    }

    /// Draws the CNA's navigation error for this cycle (its `cna.navigation` model, over the τ
    /// since the last decision) and returns the position it broadcasts (`surfaced`: it takes its
    /// GPS fix at the surface now).
    fn cna_fix(&mut self, t_dec: f64, surfaced: bool) -> Vec3 {
        let (cna, navigation) = (&mut self.cna, &self.sc.cna.navigation);
        let dt = if t_dec > 0.0 { self.sc.comms.tau } else { 0.0 };
        cna.nav_error = navigation.error(cna.nav_error, surfaced, dt, &mut cna.rng_gps, &mut cna.rng_nav);
        let (p, (de, dn)) = (cna.craft.pos, navigation.broadcast_error(cna.nav_error));
        Vec3::new(p.x + de, p.y + dn, p.z)
    }

    /// Truth to `t_next`: the CNA craft, the ships, then every survey AUV (after its finish
    /// behaviour's action). Reads: the scenario, the bathymetry, the CNA's target, each AUV's
    /// estimate (for its finish behaviour). Writes: every vehicle's true state and its truth draws.
    /// Reports every ship's pose.
    pub(super) fn advance(&mut self, t_next: f64, obs: &mut dyn Observer) {
        let sc = self.sc;
        self.cna.craft.step(sc.cna.speed, sc.cna.max_turn_rate_deg_s.to_radians(), sc.dt);
        for (i, (ship, spec)) in self.ships.iter_mut().zip(&sc.ships).enumerate() {
            ship.step(spec, sc.dt);
            obs.on_ship_pose(&ShipPose { t: t_next, ship: i, pos: ship.pos, heading: ship.psi });
        }
        for a in self.auvs.iter_mut() {
            let action = sc.fleet.finish.act(a.ctrl.is_complete(), a.ekf.position(), a.station);
            a.step_truth(sc, &self.bathy, action);
        }
    }

    /// Every slot starting in [t, t_next): its owner transmits. Reads: the scenario, the slots,
    /// every vehicle's truth and the senders' estimates and plans. Writes: the packets in the
    /// water, the slot counter, the senders' rate selectors, acknowledgement lists and link draws,
    /// the CNA's rate policy. Reports each slot's choices and every message sent.
    pub(super) fn transmit(&mut self, t: f64, t_next: f64, obs: &mut dyn Observer) {
        let per_cycle = self.slots.len() as u64;
        if per_cycle == 0 {
            return;
        }
        loop {
            let slot = self.slots[(self.next_slot % per_cycle) as usize];
            let t_tx = (self.next_slot / per_cycle) as f64 * self.sc.comms.tau + slot.start_s;
            if t_tx >= t_next - 1e-9 {
                return;
            }
            self.next_slot += 1;
            let frac = ((t_tx - t) / self.sc.dt).clamp(0.0, 1.0);
            match (slot.message, slot.owner) {
                (Message::Mini(kind), owner) => self.mini_broadcast(owner, kind, t_tx, frac, obs),
                (Message::Packet, Owner::Cna) => self.broadcast(t_tx, frac, obs),
                (Message::Packet, Owner::Buoy(b)) => self.buoy_broadcast(b, t_tx, frac, obs),
                (Message::Packet, Owner::Auv(j)) => self.send_status(j, self.next_slot - 1, t_tx, frac, obs),
                // Validation refuses a ship slot without a component.
                (Message::Packet, Owner::Ship(..)) => {}
            }
        }
    }

    /// The CNA's broadcast: one packet, an arrival (with its own range) at every survey AUV, at
    /// `comms.cna_rate` or its rate policy's choice.
    fn broadcast(&mut self, t_tx: f64, frac: f64, obs: &mut dyn Observer) {
        if !self.policy.as_policy().transmits() {
            return;
        }
        let sc = self.sc;
        let from = lerp(self.cna.craft.prev, self.cna.craft.pos, frac);
        let (de, dn) = sc.cna.navigation.broadcast_error(self.cna.nav_error);
        let fix = Vec3::new(from.x + de, from.y + dn, from.z);
        let (id, rate) = match self.cna_choice(fix, t_tx, obs) {
            (id, Choice::Transmit(rate)) => (id, rate),
            (_, Choice::Silent) => return,
        };
        let air = air_time(rate);
        self.air.transmit(Owner::Cna, t_tx, t_tx + air);
        for k in 0..self.auvs.len() {
            let silent = self.silent(k, t_tx);
            let p0 = lerp(self.auvs[k].prev, self.auvs[k].truth, frac);
            let tl = self.tl_db(&from, &p0);
            let a = &mut self.auvs[k];
            let decoded =
                sc.comms.success.draw(rate, tl, RECEIVER_AT_SURVEY_AUV, &mut a.modem.rng_down).frame0() && !silent;
            let (v, clock) = (a.velocity(sc.dt), a.clock);
            let (tt, travel_time) =
                measured_travel(sc, from, t_tx, &self.cna.clock, (p0, v, &clock), &mut a.modem.rng_range);
            let acked = self.cna.acked[k].clone();
            let payload = Payload::Broadcast { id, rate, fix, travel_time, acked, decoded };
            self.air.push(arrival(Owner::Cna, Owner::Auv(k), t_tx, tt, air, tl, Some(payload)));
        }
        self.cna.acked.iter_mut().for_each(Vec::clear);
    }

    /// The CNA's rate for this broadcast (and the broadcast's id): its policy's choice on the
    /// distance from its `fix` to the farthest AUV it has a forecast of, or `comms.cna_rate`.
    fn cna_choice(&mut self, fix: Vec3, t_tx: f64, obs: &mut dyn Observer) -> (u64, Choice) {
        let sc = self.sc;
        let cna = &mut self.cna;
        let Some(policy) = cna.rate.as_mut() else { return (0, Choice::Transmit(sc.comms.cna_rate)) };
        let distances = cna.predictors.iter().enumerate().filter_map(|(k, p)| {
            let at = p.position_at(t_tx)?;
            Some((k, (at.x - fix.x).hypot(at.y - fix.y)))
        });
        let farthest = distances.max_by(|a, b| a.1.total_cmp(&b.1));
        let longest_air = policy.rates().into_iter().map(air_time).fold(0.0, f64::max);
        let settled_s = longest_air + sc.comms.max_range_m / sc.channel.sound_speed.slowest();
        let (id, choice) = policy.choose(farthest, t_tx, settled_s);
        obs.on_cna_choice(&CnaChoice { t: t_tx, distance: farthest.map(|f| f.1), choice });
        (id, choice)
    }

    /// Buoy `b`'s slot: its GPS position, one packet, an arrival (with its own range) at every
    /// survey AUV; it reaches the CNA as interference.
    fn buoy_broadcast(&mut self, b: usize, t_tx: f64, frac: f64, obs: &mut dyn Observer) {
        let sc = self.sc;
        let buoy = &mut self.buoys[b];
        let (rate, from, fix) = (buoy.rate, buoy.position(t_tx), buoy.gps_fix(t_tx));
        obs.on_buoy_fix(&BuoyFix { t: t_tx, buoy: b, fix });
        let air = air_time(rate);
        self.air.transmit(Owner::Buoy(b), t_tx, t_tx + air);
        for k in 0..self.auvs.len() {
            let silent = self.silent(k, t_tx);
            let a = &self.auvs[k];
            let (p0, v, clock) = (lerp(a.prev, a.truth, frac), a.velocity(sc.dt), a.clock);
            let tl = self.tl_db(&from, &p0);
            let buoy = &mut self.buoys[b];
            let decoded =
                sc.comms.success.draw(rate, tl, RECEIVER_AT_SURVEY_AUV, &mut buoy.rng_link).frame0() && !silent;
            let (tt, travel_time) = measured_travel(sc, from, t_tx, &buoy.clock, (p0, v, &clock), &mut buoy.rng_link);
            let payload = Payload::Position { rate, fix, travel_time, decoded };
            self.air.push(arrival(Owner::Buoy(b), Owner::Auv(k), t_tx, tt, air, tl, Some(payload)));
        }
        let craft = &self.cna.craft;
        let (c0, cv) = (lerp(craft.prev, craft.pos, frac), (craft.pos - craft.prev) * (1.0 / sc.dt));
        let tt = sc.channel.sound_speed.travel_time(from, |d| c0 + cv * d);
        let tl = self.tl_db(&from, &c0);
        self.air.push(arrival(Owner::Buoy(b), Owner::Cna, t_tx, tt, air, tl, None));
    }

    /// Survey AUV `j`'s status slot (network slot `net_slot`): its selector picks the rate (or
    /// silence); the message goes to the CNA (and, with `comms.status_to = "cna_and_auvs"`, to
    /// every other survey AUV; otherwise it reaches them as interference).
    fn send_status(&mut self, j: usize, net_slot: u64, t_tx: f64, frac: f64, obs: &mut dyn Observer) {
        let sc = self.sc;
        let nams = !self.peers.is_empty();
        // Nams's tracker counts network slots; the CNA's acks count each AUV's own.
        let slot_id = if nams { net_slot } else { self.status_sent[j] };
        self.status_sent[j] += 1;
        let silent = self.silent(j, t_tx);
        let distance = if nams {
            self.peer_distance(j, t_tx, frac, obs)
        } else {
            let a = &self.auvs[j];
            let (ex, ey) = a.ekf.position();
            a.modem.cna_heard.map(|c| (c.x - ex).hypot(c.y - ey))
        };
        let a = &mut self.auvs[j];
        let choice = a.modem.selector.choose(slot_id, distance);
        obs.on_status_choice(&StatusChoice { t: t_tx, auv: j, distance, choice });
        let Choice::Transmit(rate) = choice else { return };
        let encoded = match self.peers.get_mut(j) {
            Some(link) => nams_frame0(link, a, slot_id, rate),
            None => status_with_covariance(a, j, t_tx).map(|bytes| (bytes, 0, 0)),
        };
        let (bytes, header_entries, header_bits) = match encoded {
            Ok(b) => b,
            Err(e) => {
                tracing::warn!(t = t_tx, auv = j, error = %e, "status message cannot be encoded; not sent");
                return;
            }
        };
        obs.on_status_sent(&StatusSent { t: t_tx, auv: j, rate, header_entries, header_bits });
        if !nams {
            a.modem.unacked.push(slot_id);
        }
        let from = lerp(a.prev, a.truth, frac);
        let craft = &self.cna.craft;
        let (c0, cv) = (lerp(craft.prev, craft.pos, frac), (craft.pos - craft.prev) * (1.0 / sc.dt));
        let tl = self.tl_db(&from, &c0);
        let air = air_time(rate);
        let tt = sc.channel.sound_speed.travel_time(from, |d| c0 + cv * d);
        let rng_up = &mut self.auvs[j].modem.rng_up;
        let reception = sc.comms.success.draw(rate, tl, RECEIVER_AT_CNA, rng_up);
        let decoded = reception.frame0() && !silent;
        self.air.transmit(Owner::Auv(j), t_tx, t_tx + air);
        let to_peers = sc.comms.status_to == StatusTo::CnaAndAuvs;
        let heard_broadcasts = std::mem::take(&mut self.auvs[j].modem.heard_broadcasts);
        let payload = Payload::Status { rate, slot_id, bytes: bytes.clone(), decoded, reception, heard_broadcasts };
        self.air.push(arrival(Owner::Auv(j), Owner::Cna, t_tx, tt, air, tl, Some(payload)));
        for m in (0..self.auvs.len()).filter(|m| *m != j) {
            let other = &self.auvs[m];
            let (p0, v) = (lerp(other.prev, other.truth, frac), other.velocity(sc.dt));
            let tt = sc.channel.sound_speed.travel_time(from, |d| p0 + v * d);
            let tl = self.tl_db(&from, &p0);
            let payload = to_peers.then(|| {
                let lost = silent || self.silent(m, t_tx);
                let drawn = sc.comms.success.draw(rate, tl, sc.comms.peer_receiver, &mut self.peer_draws[j]);
                let reception = if lost { Reception { frames: 0, ..drawn } } else { drawn };
                let decoded = reception.frame0();
                Payload::Status {
                    rate,
                    slot_id,
                    bytes: bytes.clone(),
                    decoded,
                    reception,
                    heard_broadcasts: Vec::new(),
                }
            });
            self.air.push(arrival(Owner::Auv(j), Owner::Auv(m), t_tx, tt, air, tl, payload));
        }
    }

    /// Before AUV `j`'s Nams slot: its rate policy hears what its tracker resolved, and the
    /// distance it decides on is the one to its farthest shadowed peer (from its own estimate).
    fn peer_distance(&mut self, j: usize, t_tx: f64, frac: f64, obs: &mut dyn Observer) -> Option<f64> {
        let (outcomes, heard) = self.peers[j].take_feedback();
        self.auvs[j].modem.selector.feedback(&outcomes, heard);
        let (ex, ey) = self.auvs[j].ekf.position();
        let mut farthest: Option<f64> = None;
        for m in (0..self.auvs.len()).filter(|m| *m != j) {
            let Some(e) = self.peers[j].estimate(m, t_tx, &self.bathy) else { continue };
            let truth = lerp(self.auvs[m].prev, self.auvs[m].truth, frac);
            obs.on_shadow(&ShadowSample { t: t_tx, auv: j, peer: m, error: (e.x - truth.x).hypot(e.y - truth.y) });
            let d = (e.x - ex).hypot(e.y - ey);
            farthest = Some(farthest.map_or(d, |f| f.max(d)));
        }
        farthest
    }

    /// Every addressed packet whose arrival ended by `t_next`, in time order. Reads: the packets
    /// in the water. Writes: the receivers' filters, selectors and peer trackers, the CNA's
    /// predictors, acknowledgements, reported covariances and rate policy. Reports every packet's
    /// fate ([`Observer::on_packet`], [`Observer::on_link`]), every usable range and every
    /// filter update.
    pub(super) fn deliver(&mut self, t_next: f64, obs: &mut dyn Observer) {
        for (meta, payload, survived) in self.air.due(t_next) {
            match (payload, meta.to) {
                (Payload::Broadcast { id, rate, fix, travel_time, acked, decoded }, Owner::Auv(k)) => {
                    let received = decoded && survived;
                    obs.on_link(&link(&meta, k, rate.index(), (decoded, survived), received));
                    obs.on_packet(&event(&meta, "down", k, decoded, survived));
                    if received {
                        if self.cna.rate.is_some() {
                            self.auvs[k].modem.heard_broadcasts.push(id);
                        }
                        heard(obs, &meta, k, travel_time, Some(fix));
                        self.hear_broadcast(k, &meta, fix, travel_time, &acked, obs);
                    }
                }
                (Payload::Status { rate, slot_id, bytes, decoded, heard_broadcasts, .. }, Owner::Cna) => {
                    let Owner::Auv(j) = meta.from else { continue };
                    if decoded && survived {
                        obs.on_cna_status(&CnaStatusHeard { t_tx: meta.t_tx, t_rx: meta.end, auv: j, bytes: &bytes });
                    }
                    let message = (decoded && survived).then(|| self.read_at_cna(j, &bytes, meta.t_tx)).flatten();
                    obs.on_link(&link(&meta, j, rate.index(), (decoded, survived), message.is_some()));
                    obs.on_packet(&event(&meta, "up", j, decoded, survived));
                    if let Some((report, cov)) = message {
                        if let Some(policy) = self.cna.rate.as_mut() {
                            policy.on_status(j, meta.t_tx, &heard_broadcasts);
                        }
                        self.cna.acked[j].push(slot_id);
                        if let Some(cov) = cov {
                            self.cna.reported[j] = Some(cov);
                        }
                        self.cna.predictors[j].receive(report);
                    }
                }
                (Payload::Status { rate, slot_id, bytes, reception, .. }, Owner::Auv(m)) => {
                    let Owner::Auv(j) = meta.from else { continue };
                    let rx = if survived { reception } else { Reception { frames: 0, ..reception } };
                    self.hear_status(m, j, (rate, slot_id), rx, &bytes, meta.t_tx, obs);
                }
                (Payload::Position { rate, fix, travel_time, decoded }, Owner::Auv(k)) => {
                    let received = decoded && survived;
                    obs.on_link(&link(&meta, k, rate.index(), (decoded, survived), received));
                    obs.on_packet(&event(&meta, "buoy", k, decoded, survived));
                    if received {
                        heard(obs, &meta, k, travel_time, Some(fix));
                        self.apply_range(k, &meta, fix, travel_time, obs);
                    }
                }
                (Payload::Mini { kind, value, travel_time, decoded }, Owner::Auv(k)) => {
                    let received = decoded && survived;
                    let direction = if matches!(meta.from, Owner::Ship(..)) { "ship" } else { "buoy" };
                    obs.on_link(&link(&meta, k, SUCCESS_RATE.index(), (decoded, survived), received));
                    obs.on_packet(&event(&meta, direction, k, decoded, survived));
                    if received {
                        heard(obs, &meta, k, travel_time, None);
                        self.hear_mini(k, &meta, kind, value, travel_time, obs);
                    }
                }
                (Payload::Broadcast { .. } | Payload::Position { .. } | Payload::Mini { .. }, _)
                | (Payload::Status { .. }, Owner::Buoy(_) | Owner::Ship(..)) => {}
            }
        }
    }

    /// What the CNA reads of AUV `j`'s status sent at `t_tx`: the report its predictor takes and,
    /// from a node report's trailer, the AUV's covariance (None: not decodable).
    fn read_at_cna(&self, j: usize, bytes: &[u8], t_tx: f64) -> Option<(StatusReport, Option<ReportedCov>)> {
        let Some(link) = self.peers.get(j) else {
            return read_node_status(bytes, t_tx).map(|(report, cov)| (report, Some(cov)));
        };
        let status = Frame0::decode(bytes, link.width()).ok()?.status;
        // The CNA knows the plans: a waypoint id names the next three of AUV j's.
        let waypoints = match status.next {
            NextWaypoint::Id(id) => {
                self.auvs[j].ctrl.waypoints().iter().skip(id as usize).take(3).map(|w| (w.x, w.y)).collect()
            }
            NextWaypoint::LatLon { lat, lon } => vec![LocalOrigin::default().to_local(lat, lon)],
        };
        let s = status;
        Some((StatusReport { t: t_tx, pos: s.pos, speed: s.speed, heading: s.heading, waypoints }, None))
    }

    /// AUV `m` received `rx` of AUV `j`'s status (`rate`, slot `slot_id`) sent at `t_tx`: with Nams's
    /// frame 0 its tracker and shadow of `j` learn from it; the observer counts the frames.
    #[allow(clippy::too_many_arguments)]
    fn hear_status(
        &mut self,
        m: usize,
        j: usize,
        (rate, slot_id): (Rate, u64),
        rx: Reception,
        bytes: &[u8],
        t_tx: f64,
        obs: &mut dyn Observer,
    ) {
        let frame0_bytes = match self.peers.get(j).map(PeerLink::width) {
            Some(width) => match self.peers[m].on_packet(j, slot_id, rx, bytes, width, t_tx) {
                Ok(heard) => heard.frame0_bytes,
                Err(e) => {
                    tracing::warn!(t = t_tx, from = j, to = m, error = %e, "a peer's frame 0 does not decode");
                    None
                }
            },
            None => rx.frame0().then_some(bytes.len()),
        };
        obs.on_status_frames(&StatusFrames {
            t: t_tx,
            from: j,
            to: m,
            rate,
            frames_received: rx.count(),
            frames_sent: u32::from(rx.n_frames),
            frame_bytes: rate.spec().frame_bytes,
            frame0_bytes,
        });
    }

    /// AUV `k` decoded the CNA's broadcast at the end of its arrival: the acknowledgements feed
    /// its rate selector, and the range updates its filter.
    fn hear_broadcast(
        &mut self,
        k: usize,
        meta: &Arrival<()>,
        fix: Vec3,
        travel_time: Option<f64>,
        acked: &[u64],
        obs: &mut dyn Observer,
    ) {
        let a = &mut self.auvs[k];
        let outcomes: Vec<Outcome> =
            a.modem.unacked.drain(..).map(|slot| Outcome { slot, success: acked.contains(&slot) }).collect();
        a.modem.selector.feedback(&outcomes, true);
        a.modem.cna_heard = Some(fix);
        self.apply_range(k, meta, fix, travel_time, obs);
    }

    /// AUV `k`'s filter applies the range of a decoded broadcast from a transponder at `fix`. The
    /// range was measured at the start of the arrival; the modem driver moves the transponder by
    /// the AUV's own dead-reckoned motion over the decode delay, so the filter can apply it now.
    /// The travel time becomes a range at the speed `filter.sound_speed` gives between the
    /// transponder's reported depth and the AUV's measured one.
    pub(super) fn apply_range(
        &mut self,
        k: usize,
        meta: &Arrival<()>,
        fix: Vec3,
        travel_time: Option<f64>,
        obs: &mut dyn Observer,
    ) {
        let a = &mut self.auvs[k];
        let Some(travel_time) = travel_time else { return };
        a.ekf.predict_to(meta.end, a.yaw_measured);
        let (speed, psi) = a.ekf.speed_heading();
        let (ce, cn) = a.ekf.current();
        let delay = meta.end - meta.start;
        let shift = Vec3::new((speed * psi.cos() + ce) * delay, (speed * psi.sin() + cn) * delay, 0.0);
        let sound = self.range_speed.between(fix.z, a.truth.z);
        let m = RangeMeasurement { range: sound * travel_time, travel_time, transponder: fix + shift };
        // The arrival starts when the true signal reaches the AUV.
        let error_m = m.range - sound * (meta.start - meta.t_tx);
        let recoveries = a.ekf.recoveries().count;
        let outcome = a.ekf.update_range(&m, Some(a.truth.z));
        let recovered = a.ekf.recoveries().count > recoveries;
        if recovered {
            tracing::info!(t = meta.end, auv = k, "the filter's ranges left their NIS bounds: it recovered");
        }
        obs.on_range_update(&RangeUpdate { t: meta.end, auv: k, outcome, error_m, recovered });
    }

    /// Filters to `t_next` at the end of truth step `step` (every step, or every few with a
    /// decimated filter rate): prediction, speed and compass; a surfaced AUV's GPS once a second.
    /// Reads: the scenario, each AUV's truth. Writes: each AUV's filter, its sensor draws and its
    /// yaw-rate sum. Reports every filter step's dead reckoning.
    pub(super) fn sense(&mut self, step: u64, t_next: f64, obs: &mut dyn Observer) {
        let whole_second = (t_next - t_next.round()).abs() < 1e-6;
        let every = self.sc.filter.rate.steps(self.sc.dt);
        let filter_step = (step + 1) % every == 0;
        for (k, a) in self.auvs.iter_mut().enumerate() {
            let yaw_rate = if every == 1 {
                a.yaw_measured
            } else {
                a.yaw_sum += a.yaw_measured;
                if !filter_step {
                    continue;
                }
                std::mem::take(&mut a.yaw_sum) / every as f64
            };
            let (speed, heading) = a.sense(self.sc, t_next, yaw_rate);
            obs.on_dead_reckoning(&DeadReckoning { t: t_next, auv: k, yaw_rate, speed, heading, truth: a.truth });
            if let Finish::Surface { gps_sd_m, .. } = self.sc.fleet.finish {
                if whole_second && a.at_surface() {
                    a.gps_fix(gps_sd_m);
                }
            }
        }
    }

    /// Once a second: true error, the filter's σ and NEES, distances, and the observer.
    /// Reads: every vehicle's truth and every filter. Writes: only whether every filter stayed
    /// finite. Reports the ships, the buoys and one row per survey AUV.
    pub(super) fn observe(&mut self, t: f64, obs: &mut dyn Observer) {
        if !self.ships.is_empty() {
            let ships: Vec<Vec3> = self.ships.iter().map(|s| s.pos).collect();
            obs.on_ships(t, &ships);
        }
        if !self.ships.is_empty() {
            obs.on_ship_samples(t, &self.ship_samples(t));
        }
        if !self.buoys.is_empty() {
            obs.on_buoys(t, &self.buoy_samples(t));
        }
        let cna = self.cna.craft.pos;
        let mut rows = Vec::with_capacity(self.auvs.len());
        for (k, a) in self.auvs.iter().enumerate() {
            self.finite &= a.finite();
            let (ex, ey) = a.ekf.position();
            let [p_ee, p_en, p_nn] = a.ekf.position_cov();
            let (dx, dy) = (ex - a.truth.x, ey - a.truth.y);
            let sigma = (p_ee + p_nn).max(0.0).sqrt();
            let nees = nees_2d(dx, dy, p_ee, p_en, p_nn);
            let error = dx.hypot(dy);
            let d = (a.truth.x - cna.x).hypot(a.truth.y - cna.y);
            rows.push(TraceRow {
                t,
                auv: k,
                true_x: a.truth.x,
                true_y: a.truth.y,
                true_z: a.truth.z,
                est_x: ex,
                est_y: ey,
                error,
                est_sd: sigma,
                p_ee,
                p_en,
                p_nn,
                nees,
                modelled: None,
                cna_x: cna.x,
                cna_y: cna.y,
                cna_z: cna.z,
                distance: d,
            });
        }
        obs.on_sample(t, cna, &rows);
    }
}

/// A broadcast from `from`, sent at `t_tx` by a modem with clock `sender`, reaching a receiver at
/// `p0` moving at `v` with its own clock: the true travel time, and the one the receiver measures
/// (None: no usable range). The range error is drawn whatever the packet's fate, so losses do
/// not shift the stream.
pub(super) fn measured_travel(
    sc: &Scenario,
    from: Vec3,
    t_tx: f64,
    sender: &Clock,
    (p0, v, receiver): (Vec3, Vec3, &Clock),
    rng_range: &mut ChaCha8Rng,
) -> (f64, Option<f64>) {
    let tt = sc.channel.sound_speed.travel_time(from, |d| p0 + v * d);
    let error = sc.channel.range_error.draw(sc.filter.params.range_noise.variance(tt), rng_range);
    let clocks = receiver.error_at(t_tx + tt) - sender.error_at(t_tx);
    (tt, error.map(|e| tt + e + clocks))
}

/// The CNA's target for `command` at a decision of surfacing step `step` taken at true position
/// `here` on fix `fix` (the command is relative to the fix the policy saw), the CNA now at `now`
/// with target `current` (at the decision itself, `now` is `here`; a climb keeps climbing).
pub(super) fn target(
    step: Step,
    command: CnaCommand,
    here: Vec3,
    fix: Vec3,
    now: Vec3,
    current: Option<Vec3>,
) -> Option<Vec3> {
    let steer = |p: Vec3, z: f64| Some(Vec3::new(here.x + p.x - fix.x, here.y + p.y - fix.y, z));
    match (step, command) {
        (Step::Climb, _) if now == here => Some(Vec3::new(here.x, here.y, 0.0)),
        (Step::Climb, _) => current,
        (Step::Fix { to }, CnaCommand::GoTo(p)) => steer(p, to),
        (Step::Fix { to }, CnaCommand::Hold) => Some(Vec3::new(now.x, now.y, to)),
        (Step::Work | Step::WorkWithFix, CnaCommand::GoTo(p)) => steer(p, p.z),
        (Step::Work | Step::WorkWithFix, CnaCommand::Hold) => None,
    }
}

pub(super) fn arrival(
    from: Owner,
    to: Owner,
    t_tx: f64,
    travel: f64,
    air: f64,
    tl: f64,
    payload: Option<Payload>,
) -> Arrival<Payload> {
    Arrival { from, to, t_tx, start: t_tx + travel, end: t_tx + travel + air, level_db: -tl, payload }
}

/// Reports AUV `k`'s decoded packet with a usable range.
fn heard(obs: &mut dyn Observer, meta: &Arrival<()>, k: usize, travel_time: Option<f64>, fix: Option<Vec3>) {
    if let Some(travel_time) = travel_time {
        obs.on_range(&RangeHeard { t_tx: meta.t_tx, auv: k, from: meta.from, travel_time, fix });
    }
}

/// A packet's fate on AUV `auv`'s link, for [`Observer::on_link`].
fn link(meta: &Arrival<()>, auv: usize, rate: u8, (decoded, survived): (bool, bool), received: bool) -> LinkArrival {
    LinkArrival { auv, from: meta.from, rate, decoded, survived, received }
}

fn event(meta: &Arrival<()>, direction: &'static str, auv: usize, decoded: bool, survived: bool) -> CommsEvent {
    let lost_to = match (decoded, survived) {
        (true, true) => "",
        (false, _) => "channel",
        (true, false) => "collision or half-duplex",
    };
    CommsEvent { t: meta.t_tx, direction, auv, received: decoded && survived, lost_to }
}

/// A survey AUV's status: the Appendix C node report from its estimate, then the covariance
/// trailer with its filter's horizontal covariance (docs/models.md#estimator-cost: the CNA plans on what the AUVs'
/// filters report, not on a model of them).
fn status_with_covariance(a: &SurveyAuv, k: usize, t: f64) -> Result<Vec<u8>, EncodeError> {
    let mut bytes = a.status(k, t).encode()?;
    bytes.extend(CovTrailer::encode(&CovarianceReport::from_cov(a.ekf.position_cov()))?);
    Ok(bytes)
}

/// AUV `a`'s Nams frame 0 for its network slot `slot` at `rate` (the status from its own estimate),
/// with the header's entries and bits.
fn nams_frame0(
    link: &mut PeerLink,
    a: &SurveyAuv,
    slot: u64,
    rate: Rate,
) -> Result<(Vec<u8>, usize, usize), EncodeError> {
    let (ex, ey) = a.ekf.position();
    let (speed, psi) = a.ekf.speed_heading();
    let next = a.ctrl.next_waypoint();
    let wp = a.ctrl.waypoints().get(next).or(a.ctrl.waypoints().last()).map_or((ex, ey), |w| (w.x, w.y));
    let pos = Vec3::new(ex, ey, a.truth.z);
    let latlon = LocalOrigin::default().to_latlon(wp.0, wp.1);
    let status = StatusFormat::nams_status(link.mode(), pos, Heading::from_radians(psi), speed, (next, latlon));
    let f = link.frame0(slot, rate, status)?;
    Ok((f.bytes, f.header_entries, f.header_bits))
}
