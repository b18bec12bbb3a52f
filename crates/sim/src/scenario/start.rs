//! The CNA's start pose, from the scenario's CNA section (the engine's CNA, the planners and the
//! transmission-loss grid's layout all start from it).

use super::world::Scenario;
use coopnav_core::{CompassDeg, Heading, Vec3};
use coopnav_plan::CnaPose;

/// The CNA's start pose.
pub fn cna_start(sc: &Scenario) -> CnaPose {
    let z = sc.cna_cruise_depth();
    CnaPose {
        pos: Vec3::new(sc.cna.x, sc.cna.y, z),
        heading: Heading::from(CompassDeg(sc.cna.heading_compass_deg)),
        pitch: 0.0,
    }
}
