//! One survey AUV's side of Nams's link (`comms.status_format = "nams_frame0"`): its
//! packet-success tracker, whose header rides in frame 0 ahead of the thesis status message; a
//! shadow estimator of every other survey AUV, reset by each status decoded from it; and the
//! outcomes its rate policy has yet to hear (handed over at its next status slot, as Nams's
//! vehicles do).

use crate::models::peer::{mask_width, EstimatorMode, StatusFormat};
use coopnav_acomms::codec::{DecodeError, EncodeError};
use coopnav_acomms::estimator::{Knowledge, ShadowEstimator};
use coopnav_acomms::selector::Outcome;
use coopnav_acomms::status::{Frame0, LocalOrigin, StatusMessage};
use coopnav_acomms::tracker::{Delivery, MaskWidth, Tracker};
use coopnav_acomms::{Rate, Reception};
use coopnav_core::{Bathymetry, DepthTarget, Iver2Params, Iver2State, Vec3, Waypoint};

/// What the mission plans tell every vehicle about the others: each survey AUV's waypoints and
/// its start, and how it holds depth and speed.
pub struct Plans {
    pub waypoints: Vec<Vec<Waypoint>>,
    pub starts: Vec<Iver2State>,
    pub target: DepthTarget,
    pub speed: f64,
    pub vehicle: Iver2Params,
}

/// Stream ids of the channel draws of AUV k's statuses at the other survey AUVs: this + k.
pub const STREAM_BASE: u64 = 30_000;

#[derive(Clone)]
pub struct PeerLink {
    mode: EstimatorMode,
    tracker: Tracker,
    /// Per survey AUV (own entry None): the shadow of that vehicle.
    shadows: Vec<Option<ShadowEstimator>>,
    outcomes: Vec<Outcome>,
    heard: bool,
}

/// A status packet from a peer, as this vehicle received it.
#[derive(Debug, Clone, PartialEq)]
pub struct Heard {
    /// Frames that arrived.
    pub frames: u32,
    /// The status, when frame 0 arrived (with it the header).
    pub status: Option<StatusMessage>,
    /// Bytes frame 0 spent on header and status (when it arrived).
    pub frame0_bytes: Option<usize>,
}

/// A frame 0 ready to send.
pub struct Frame0Bytes {
    pub bytes: Vec<u8>,
    pub header_entries: usize,
    pub header_bits: usize,
}

impl PeerLink {
    /// AUV `me` of the fleet, whose rate policy may use `rates`.
    pub fn new(me: usize, rates: &[Rate], mode: EstimatorMode, plans: &Plans) -> Self {
        let width = mask_width(rates);
        let smallest_frame = rates.iter().map(|r| r.spec().frame_bytes).min().unwrap_or(32);
        let n = plans.waypoints.len();
        let tracker = Tracker::new(me, n, width, StatusFormat::max_header_entries(mode, smallest_frame, width));
        let shadows = (0..n).map(|k| (k != me).then(|| shadow(k, mode, plans))).collect();
        PeerLink { mode, tracker, shadows, outcomes: Vec::new(), heard: false }
    }

    pub fn width(&self) -> MaskWidth {
        self.tracker.width()
    }

    pub fn mode(&self) -> EstimatorMode {
        self.mode
    }

    /// What was learnt since the last own slot: resolved own transmissions, and whether anyone
    /// was heard at all.
    pub fn take_feedback(&mut self) -> (Vec<Outcome>, bool) {
        (std::mem::take(&mut self.outcomes), std::mem::take(&mut self.heard))
    }

    /// The shadow estimate of survey AUV `peer` at `t` (None: nothing known of it yet).
    pub fn estimate(&mut self, peer: usize, t: f64, bathy: &Bathymetry) -> Option<Vec3> {
        self.shadows.get_mut(peer)?.as_mut()?.estimate(t, bathy)
    }

    /// Frame 0 of own network slot `slot` at `rate`: the tracker's header (the transmission is
    /// recorded as unresolved), then `status`.
    pub fn frame0(&mut self, slot: u64, rate: Rate, status: StatusMessage) -> Result<Frame0Bytes, EncodeError> {
        let header = self.tracker.on_transmit(slot, rate);
        let width = self.tracker.width();
        let (header_entries, header_bits) = (header.entries.len(), header.bits(width));
        let bytes = Frame0 { header, status }.encode(width, rate.spec().frame_bytes)?;
        Ok(Frame0Bytes { bytes, header_entries, header_bits })
    }

    /// A status packet of `src`'s network slot `slot` arrived as `rx` (its frame 0 in `bytes`,
    /// encoded with the sender's mask `width`), sent at `t_tx`: the tracker learns from its header,
    /// the shadow of `src` resets to its status. Nothing of the header or status without frame 0.
    pub fn on_packet(
        &mut self,
        src: usize,
        slot: u64,
        rx: Reception,
        bytes: &[u8],
        width: MaskWidth,
        t_tx: f64,
    ) -> Result<Heard, DecodeError> {
        self.heard |= rx.received();
        let decoded = if rx.frame0() { Some(Frame0::decode(bytes, width)?) } else { None };
        let resolved = self.tracker.on_receive(slot, src, rx, decoded.as_ref().map(|f| &f.header));
        self.outcomes.extend(
            resolved.iter().map(|r| Outcome { slot: r.slot, success: matches!(r.delivery, Delivery::Received { .. }) }),
        );
        let status = decoded.map(|f| f.status);
        if let (Some(s), Some(Some(shadow))) = (&status, self.shadows.get_mut(src)) {
            shadow.on_status(s, t_tx);
        }
        Ok(Heard { frames: rx.count(), frame0_bytes: status.is_some().then_some(bytes.len()), status })
    }
}

/// The shadow of AUV `k`: pre-planned, it knows `k`'s plan and start; dynamic, nothing until a
/// report.
fn shadow(k: usize, mode: EstimatorMode, plans: &Plans) -> ShadowEstimator {
    match mode {
        EstimatorMode::PrePlanned => ShadowEstimator::new(
            Knowledge::PrePlanned { plan: plans.waypoints[k].clone() },
            plans.vehicle,
            Some(plans.starts[k]),
        ),
        EstimatorMode::Dynamic => ShadowEstimator::new(
            Knowledge::Dynamic { target: plans.target, speed: plans.speed, origin: LocalOrigin::default() },
            plans.vehicle,
            None,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::Heading;

    fn plans() -> Plans {
        let wp = |x, y| Waypoint { x, y, target: DepthTarget::Depth { depth: 10.0 }, speed: 1.5 };
        let at = |x, y| Iver2State::at_rest(Vec3::new(x, y, 10.0), Heading::from_radians(0.0));
        Plans {
            waypoints: vec![vec![wp(0.0, 0.0), wp(500.0, 0.0)], vec![wp(500.0, 500.0), wp(0.0, 500.0)]],
            starts: vec![at(0.0, 0.0), at(500.0, 500.0)],
            target: DepthTarget::Depth { depth: 10.0 },
            speed: 1.5,
            vehicle: Iver2Params::default(),
        }
    }

    fn status(x: f64) -> StatusMessage {
        let pos = Vec3::new(x, 500.0, 10.0);
        StatusFormat::nams_status(EstimatorMode::Dynamic, pos, Heading::from_radians(0.0), 1.5, (1, (44.6, -63.6)))
    }

    /// AUV 1 receives AUV 0's slot-2 packet, first whole and then without frame 0: the second
    /// teaches nothing of header or status, yet its two other frames are counted and reported
    /// back in AUV 1's next header, which resolves AUV 0's slot as received with mask 0b110.
    #[test]
    fn losing_frame_0_loses_the_header_and_status_but_the_other_frames_count() {
        let rates = [Rate::R1];
        let (mut a0, mut a1) = (
            PeerLink::new(0, &rates, EstimatorMode::Dynamic, &plans()),
            PeerLink::new(1, &rates, EstimatorMode::Dynamic, &plans()),
        );
        let sent = a0.frame0(0, Rate::R1, status(100.0)).unwrap();
        let whole = Reception { frames: 0b111, n_frames: 3 };
        let heard = a1.on_packet(0, 0, whole, &sent.bytes, a0.width(), 0.0).unwrap();
        assert_eq!((heard.frames, heard.frame0_bytes), (3, Some(sent.bytes.len())));
        assert_eq!(heard.status.unwrap().pos.x, 100.0);
        let bathy = Bathymetry::new(-1e4, -1e4, 2e4, 2e4, 2, 2, vec![100.0; 4]).unwrap();
        assert!((a1.estimate(0, 0.0, &bathy).unwrap().x - 100.0).abs() < 1e-9);

        let sent = a0.frame0(2, Rate::R1, status(300.0)).unwrap();
        let partial = Reception { frames: 0b110, n_frames: 3 };
        let heard = a1.on_packet(0, 2, partial, &sent.bytes, a0.width(), 20.0).unwrap();
        assert_eq!(heard, Heard { frames: 2, status: None, frame0_bytes: None });
        // The shadow still flies from the first report: nowhere near x = 300.
        assert!(a1.estimate(0, 20.0, &bathy).unwrap().x < 200.0);
        assert!(a1.take_feedback().1, "a partial packet is still heard");

        // AUV 1 reports both receptions in its slot 3; AUV 0 decodes the header.
        let reply = a1.frame0(3, Rate::R1, status(0.0)).unwrap();
        assert_eq!(reply.header_entries, 2);
        a0.on_packet(1, 3, whole, &reply.bytes, a1.width(), 30.0).unwrap();
        let (outcomes, heard) = a0.take_feedback();
        assert!(heard);
        assert_eq!(outcomes, [Outcome { slot: 0, success: true }, Outcome { slot: 2, success: true }]);
        assert_eq!(a0.tracker.db()[&2].status[1], Delivery::Received { frames: 0b110 });
        // The same reply without its frame 0 resolves nothing.
        let mut a0_again = PeerLink::new(0, &rates, EstimatorMode::Dynamic, &plans());
        a0_again.frame0(0, Rate::R1, status(100.0)).unwrap();
        a0_again.on_packet(1, 3, partial, &reply.bytes, a1.width(), 30.0).unwrap();
        assert!(a0_again.take_feedback().0.is_empty());
    }
}
