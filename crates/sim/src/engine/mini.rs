//! Mini-packets in the engine (Gill's hybrid baseline, Gill 2013, §2.2 Fig. 8 and §2.3.2): a ship's outrigger
//! modem or a buoy sends one quantised state component per slot; every survey AUV that decodes
//! it updates its own filter of that vehicle with the component at the transmit time, then applies
//! the one-way travel time as a range to the transponder where that filter puts it (single,
//! moving or hybrid baseline follows from which vehicles the cycle has transmit). Air time,
//! half-duplex, collisions and the channel's success draw apply as to every packet.

use super::inflight::Arrival;
use super::observe::{BuoyFix, BuoySample, Observer, ShipSample};
use super::phases::{arrival, measured_travel, Payload};
use super::vehicles::lerp;
use super::Engine;
use crate::models::channel::Clock;
use crate::models::channel::RECEIVER_AT_SURVEY_AUV;
use crate::models::minipacket::{quantised, SUCCESS_RATE};
use crate::models::schedule::Owner;
use crate::scenario::world::Scenario;
use coopnav_core::Vec3;
use coopnav_nav::{StateKind, SurfaceEkf};
use std::f64::consts::FRAC_PI_2;

/// What every survey AUV knows of the ships and buoys from their mini-packets: one filter per
/// vehicle (ships first, then buoys), started from the vehicle's nominal start — the state a
/// mission start hands over by radio (Gill 2013, §2.1).
#[derive(Clone)]
pub struct SurfaceFilters {
    filters: Vec<SurfaceEkf>,
    n_ships: usize,
}

impl SurfaceFilters {
    pub fn new(sc: &Scenario) -> Self {
        let ships = sc.ships.iter().map(|s| SurfaceEkf::new(0.0, s.x, s.y, s.speed, s.track(), s.filter.clone()));
        let buoys = sc.buoys.iter().map(|b| SurfaceEkf::new(0.0, b.x, b.y, 0.0, FRAC_PI_2, b.filter.clone()));
        SurfaceFilters { filters: ships.chain(buoys).collect(), n_ships: sc.ships.len() }
    }

    /// Where this filter of buoy `b` puts it at `t` (extrapolated, the filter untouched).
    pub fn buoy_at(&self, b: usize, t: f64) -> [f64; 2] {
        self.filters[self.n_ships + b].position_at(t)
    }

    /// Where this filter of ship `i` puts its reference point at `t` (extrapolated).
    pub fn ship_at(&self, i: usize, t: f64) -> [f64; 2] {
        self.filters[i].position_at(t)
    }

    fn of(&mut self, owner: Owner) -> Option<&mut SurfaceEkf> {
        let i = match owner {
            Owner::Ship(i, _) => i,
            Owner::Buoy(b) => self.n_ships + b,
            Owner::Cna | Owner::Auv(_) => return None,
        };
        self.filters.get_mut(i)
    }
}

impl Engine<'_> {
    /// Every buoy's truth at `t` and every survey AUV's estimate of it.
    pub(super) fn buoy_samples(&self, t: f64) -> Vec<BuoySample> {
        let estimates = |b| self.surface.iter().map(|s| s.buoy_at(b, t)).collect();
        self.buoys
            .iter()
            .enumerate()
            .map(|(b, buoy)| BuoySample { truth: buoy.position(t), estimates: estimates(b) })
            .collect()
    }

    /// Every ship's truth at `t` and every survey AUV's estimate of it.
    pub(super) fn ship_samples(&self, t: f64) -> Vec<ShipSample> {
        let estimates = |i| self.surface.iter().map(|s| s.ship_at(i, t)).collect();
        self.ships.iter().enumerate().map(|(i, ship)| ShipSample { truth: ship.pos, estimates: estimates(i) }).collect()
    }

    /// `owner`'s mini-packet carrying `kind`, sent at `t_tx` (fraction `frac` of the step): an
    /// arrival with its own range at every survey AUV; it reaches the CNA as interference.
    pub(super) fn mini_broadcast(
        &mut self,
        owner: Owner,
        kind: StateKind,
        t_tx: f64,
        frac: f64,
        obs: &mut dyn Observer,
    ) {
        let sc = self.sc;
        let (from, value, sender_clock) = match owner {
            Owner::Ship(i, side) => {
                let (spec, ship) = (&sc.ships[i], &mut self.ships[i]);
                (ship.modem(spec, side, frac), ship.mini_value(spec, kind, frac), ship.clock)
            }
            Owner::Buoy(b) => {
                let fix = self.buoys[b].gps_fix(t_tx);
                obs.on_buoy_fix(&BuoyFix { t: t_tx, buoy: b, fix });
                let value = quantised(kind, [fix.x, fix.y], 0.0, 0.0, &sc.buoys[b].zone());
                (self.buoys[b].position(t_tx), value, self.buoys[b].clock)
            }
            Owner::Cna | Owner::Auv(_) => return,
        };
        let air = sc.comms.mini_packet_air_s;
        self.air.transmit(owner, t_tx, t_tx + air);
        // Each receiver's geometry first; then the sender's link stream draws fate and range error.
        let receivers: Vec<(bool, Vec3, Vec3, Clock, f64)> = (0..self.auvs.len())
            .map(|k| {
                let a = &self.auvs[k];
                let p0 = lerp(a.prev, a.truth, frac);
                (self.silent(k, t_tx), p0, a.velocity(sc.dt), a.clock, self.tl_db(&from, &p0))
            })
            .collect();
        let rng = match owner {
            Owner::Ship(i, _) => &mut self.ships[i].rng_link,
            Owner::Buoy(b) => &mut self.buoys[b].rng_link,
            Owner::Cna | Owner::Auv(_) => return,
        };
        for (k, (silent, p0, v, clock, tl)) in receivers.into_iter().enumerate() {
            let decoded = sc.comms.success.draw(SUCCESS_RATE, tl, RECEIVER_AT_SURVEY_AUV, rng).frame0() && !silent;
            let (tt, travel_time) = measured_travel(sc, from, t_tx, &sender_clock, (p0, v, &clock), rng);
            let payload = Payload::Mini { kind, value, travel_time, decoded };
            self.air.push(arrival(owner, Owner::Auv(k), t_tx, tt, air, tl, Some(payload)));
        }
        let craft = &self.cna.craft;
        let (c0, cv) = (lerp(craft.prev, craft.pos, frac), (craft.pos - craft.prev) * (1.0 / sc.dt));
        let tt = sc.channel.sound_speed.travel_time(from, |d| c0 + cv * d);
        let tl = self.tl_db(&from, &c0);
        self.air.push(arrival(owner, Owner::Cna, t_tx, tt, air, tl, None));
    }

    /// AUV `k` received a mini-packet: its filter of the sender takes the component at the
    /// transmit time, and the range goes to the transponder where that filter puts it.
    pub(super) fn hear_mini(
        &mut self,
        k: usize,
        meta: &Arrival<()>,
        kind: StateKind,
        value: f64,
        travel_time: Option<f64>,
        obs: &mut dyn Observer,
    ) {
        let sc = self.sc;
        let Some(filter) = self.surface[k].of(meta.from) else { return };
        filter.predict_to(meta.t_tx);
        filter.update(kind, value);
        let s = filter.state();
        let transponder = match meta.from {
            Owner::Ship(i, side) => sc.ships[i].outriggers.position(side, s[0], s[1], s[3]),
            Owner::Buoy(b) => Vec3::new(s[0], s[1], sc.buoys[b].modem_depth_m),
            Owner::Cna | Owner::Auv(_) => return,
        };
        self.apply_range(k, meta, transponder, travel_time, obs);
    }
}
