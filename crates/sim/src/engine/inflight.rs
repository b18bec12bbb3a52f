//! Packets in flight and the two rules that decide whether one survives the water besides the
//! channel's own success draw: half-duplex (a modem hears nothing while it transmits) and
//! collisions (arrivals overlapping at one receiver are lost, unless stronger than every other
//! overlapping arrival by the capture margin). Every transmission reaches every other node, so a
//! packet addressed elsewhere still interferes.

use crate::models::schedule::Owner;

/// How long a resolved arrival or a transmission is kept as possible interference, s (longer
/// than any air time plus travel time).
const KEEP_S: f64 = 60.0;

/// One packet's arrival at one node, occupying [start, end] there.
#[derive(Debug, Clone)]
pub struct Arrival<P> {
    pub from: Owner,
    pub to: Owner,
    pub t_tx: f64,
    pub start: f64,
    pub end: f64,
    /// Received level relative to the source, dB (−TL).
    pub level_db: f64,
    /// What the receiver gets if the packet survives; None for pure interference.
    pub payload: Option<P>,
}

#[derive(Debug, Clone)]
pub struct InFlight<P> {
    arrivals: Vec<Arrival<P>>,
    /// (transmitter, start, end) of every transmission.
    transmissions: Vec<(Owner, f64, f64)>,
    capture_margin_db: Option<f64>,
    /// The earliest end of an addressed arrival not yet delivered (∞: none): until then a step
    /// has nothing to deliver, and the pruning can wait (it only drops what can no longer
    /// overlap an arrival in flight).
    next_end: f64,
}

impl<P> InFlight<P> {
    pub fn new(capture_margin_db: Option<f64>) -> Self {
        InFlight { arrivals: Vec::new(), transmissions: Vec::new(), capture_margin_db, next_end: f64::INFINITY }
    }

    pub fn transmit(&mut self, from: Owner, start: f64, end: f64) {
        self.transmissions.push((from, start, end));
    }

    pub fn push(&mut self, arrival: Arrival<P>) {
        if arrival.payload.is_some() {
            self.next_end = self.next_end.min(arrival.end);
        }
        self.arrivals.push(arrival);
    }

    /// The addressed arrivals that end by `t`, in end-time order, each with whether it survived
    /// half-duplex and collisions. Call once every transmission starting before `t` is pushed.
    pub fn due(&mut self, t: f64) -> Vec<(Arrival<()>, P, bool)> {
        if self.next_end > t {
            return Vec::new();
        }
        let mut ready: Vec<usize> = (0..self.arrivals.len())
            .filter(|&i| self.arrivals[i].payload.is_some() && self.arrivals[i].end <= t)
            .collect();
        ready.sort_by(|&a, &b| self.arrivals[a].end.total_cmp(&self.arrivals[b].end));
        let out = ready
            .into_iter()
            .filter_map(|i| {
                let survived = !self.deaf(i) && !self.collided(i);
                let a = &mut self.arrivals[i];
                let payload = a.payload.take()?;
                let meta = Arrival {
                    from: a.from,
                    to: a.to,
                    t_tx: a.t_tx,
                    start: a.start,
                    end: a.end,
                    level_db: a.level_db,
                    payload: None,
                };
                Some((meta, payload, survived))
            })
            .collect();
        self.arrivals.retain(|a| a.payload.is_some() || a.end > t - KEEP_S);
        self.transmissions.retain(|tx| tx.2 > t - KEEP_S);
        self.next_end =
            self.arrivals.iter().filter(|a| a.payload.is_some()).map(|a| a.end).fold(f64::INFINITY, f64::min);
        out
    }

    /// The receiver was transmitting during the arrival.
    fn deaf(&self, i: usize) -> bool {
        let a = &self.arrivals[i];
        self.transmissions.iter().any(|&(who, s, e)| who == a.to && s < a.end && e > a.start)
    }

    /// Another arrival overlaps at the same receiver and this one does not capture over it.
    fn collided(&self, i: usize) -> bool {
        let a = &self.arrivals[i];
        self.arrivals.iter().enumerate().any(|(j, b)| {
            j != i
                && b.to == a.to
                && b.start < a.end
                && b.end > a.start
                && self.capture_margin_db.is_none_or(|m| a.level_db < b.level_db + m)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arrival(from: Owner, to: Owner, start: f64, level_db: f64, tag: u32) -> Arrival<u32> {
        Arrival { from, to, t_tx: start - 0.5, start, end: start + 3.9, level_db, payload: Some(tag) }
    }

    fn fates(f: &mut InFlight<u32>, t: f64) -> Vec<(u32, bool)> {
        f.due(t).into_iter().map(|(_, p, ok)| (p, ok)).collect()
    }

    #[test]
    fn two_packets_overlapping_at_one_receiver_are_both_lost() {
        let mut f = InFlight::new(None);
        f.push(arrival(Owner::Auv(0), Owner::Cna, 10.0, -60.0, 1));
        f.push(arrival(Owner::Auv(1), Owner::Cna, 12.0, -70.0, 2));
        // A third, later and clear of both, survives.
        f.push(arrival(Owner::Auv(1), Owner::Cna, 20.0, -70.0, 3));
        assert_eq!(fates(&mut f, 30.0), [(1, false), (2, false), (3, true)]);
    }

    #[test]
    fn with_a_capture_margin_the_much_stronger_packet_survives() {
        let mut f = InFlight::new(Some(6.0));
        f.push(arrival(Owner::Auv(0), Owner::Cna, 10.0, -60.0, 1));
        f.push(arrival(Owner::Auv(1), Owner::Cna, 12.0, -70.0, 2));
        assert_eq!(fates(&mut f, 30.0), [(1, true), (2, false)]);
        // 3 dB apart is inside the margin: both lost.
        let mut f = InFlight::new(Some(6.0));
        f.push(arrival(Owner::Auv(0), Owner::Cna, 10.0, -60.0, 1));
        f.push(arrival(Owner::Auv(1), Owner::Cna, 12.0, -63.0, 2));
        assert_eq!(fates(&mut f, 30.0), [(1, false), (2, false)]);
    }

    #[test]
    fn a_modem_transmitting_while_a_packet_arrives_hears_nothing() {
        let mut f = InFlight::new(None);
        f.push(arrival(Owner::Cna, Owner::Auv(0), 10.0, -60.0, 1));
        f.transmit(Owner::Auv(0), 13.0, 16.9);
        // Its own transmission does not deafen another receiver.
        f.push(arrival(Owner::Cna, Owner::Auv(1), 10.0, -60.0, 2));
        assert_eq!(fates(&mut f, 30.0), [(1, false), (2, true)]);
    }

    #[test]
    fn interference_addressed_elsewhere_still_collides_and_resolved_packets_still_interfere() {
        let mut f = InFlight::new(None);
        f.push(arrival(Owner::Cna, Owner::Auv(0), 10.0, -60.0, 1));
        assert_eq!(fates(&mut f, 14.0), [(1, true)]);
        // AUV 1's status, meant for the CNA, also reaches AUV 0 as noise over a later packet.
        f.push(Arrival { payload: None, ..arrival(Owner::Auv(1), Owner::Auv(0), 20.0, -50.0, 0) });
        f.push(arrival(Owner::Cna, Owner::Auv(0), 21.0, -60.0, 2));
        // A packet overlapping the one already delivered at 10–13.9 s is lost (and does not undo it).
        f.push(arrival(Owner::Cna, Owner::Auv(0), 13.0, -60.0, 3));
        assert_eq!(fates(&mut f, 30.0), [(3, false), (2, false)]);
        // Nothing is delivered before its end.
        f.push(arrival(Owner::Cna, Owner::Auv(0), 40.0, -60.0, 4));
        assert!(fates(&mut f, 43.0).is_empty());
        assert_eq!(fates(&mut f, 44.0), [(4, true)]);
    }
}
