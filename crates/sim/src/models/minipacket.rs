//! The WHOI 13-bit mini-packet as an engine message (Gill 2013, §2.1.2 and App. B): a ranging ping that
//! carries one state component of its sender (East, North, speed or heading), quantised to a box
//! of the sender's zone and decoded by the receiver to the box centre — the codec of
//! `coopnav_nav::codec`. Its air time and the channel's success curve it uses are here.

use coopnav_acomms::Rate;
use coopnav_core::validation::Problems;
use coopnav_core::{CompassDeg, Heading};
use coopnav_nav::codec::{decode_heading_deg, encode_heading_deg, Zone, SPEED_AXIS};
use coopnav_nav::StateKind;

/// Air time of a mini-packet, s. Invented (configurable as `comms.mini_packet_air_s`): the thesis
/// gives a 2 s window per mini-packet (Gill 2013, §2.1.2) that also holds the travel time, which
/// its OWTT ranging keeps under 1 s (§2.1.3); 0.5 s of FH-FSK leaves the rest of the window to
/// ranges up to about 2 km.
pub const DEFAULT_AIR_S: f64 = 0.5;

/// The success curve a mini-packet is drawn from: rate 0's, the FH-FSK rate it shares with the
/// modem's mini-packet (invented: no thesis gives a mini-packet curve; Gill's 90 % success in
/// past tests, Gill 2013, §2.1.2, is a rate-0 figure at short range; docs/models.md#gill-mini-packets).
pub const SUCCESS_RATE: Rate = Rate::R0;

/// The value a receiver decodes from a mini-packet carrying `kind` of a vehicle at `pos` with
/// `speed` and math heading `psi` (SI, radians): quantised into `zone` (saturating at its edge)
/// and decoded to the box centre.
pub fn quantised(kind: StateKind, pos: [f64; 2], speed: f64, psi: f64, zone: &Zone) -> f64 {
    match kind {
        StateKind::East => zone.east.decode(zone.east.encode(pos[0]).index),
        StateKind::North => zone.north.decode(zone.north.encode(pos[1]).index),
        StateKind::Speed => SPEED_AXIS.decode(SPEED_AXIS.encode(speed).index),
        StateKind::Heading => {
            let compass = CompassDeg::from(Heading::from_radians(psi)).0;
            Heading::from(CompassDeg(decode_heading_deg(encode_heading_deg(compass)))).radians()
        }
    }
}

/// Checks a quantisation zone's fields under `prefix` (`ships[0].zone.`). A function, not a
/// [`CheckFields`](coopnav_core::validation::CheckFields) impl: the zone is the navigation crate's type.
pub fn check_zone(prefix: &str, zone: &Zone, p: &mut Problems) {
    for (axis, a) in [("east", zone.east), ("north", zone.north)] {
        p.finite(&format!("{prefix}{axis}.origin"), a.origin);
        p.positive(&format!("{prefix}{axis}.resolution"), a.resolution);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_component_decodes_to_its_box_centre_and_saturates_at_the_zone_edge() {
        let zone = Zone::with_resolution(0.0, -50.0, 1.6, 0.6);
        // East boxes of 1.6 m from −204.8 m: 10.0 m lies in [9.6, 11.2), centre 10.4.
        assert!((quantised(StateKind::East, [10.0, 0.0], 0.0, 0.0, &zone) - 10.4).abs() < 1e-9);
        // North beyond the zone's 153.6 m is clamped into its last box.
        let far = quantised(StateKind::North, [0.0, 500.0], 0.0, 0.0, &zone);
        assert!((far - (-50.0 + 255.5 * 0.6)).abs() < 1e-9, "{far}");
        assert!((quantised(StateKind::Speed, [0.0; 2], 1.3, 0.0, &zone) - 1.3).abs() <= 4.0 / 512.0);
        let west = quantised(StateKind::Heading, [0.0; 2], 0.0, std::f64::consts::PI, &zone);
        assert!((west.abs() - std::f64::consts::PI).abs() <= (360.0f64 / 512.0).to_radians() + 1e-12, "{west}");
    }
}
