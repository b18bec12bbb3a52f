//! The CNA's start pose, from the scenario's CNA section (the engine's CNA, the planners and the
//! transmission-loss grid's layout all start from it), and each survey AUV's launch from its
//! lawnmower (the engine's AUVs and the CNA's knowledge of their mission plans start from it).

use super::world::Scenario;
use coopnav_core::{Bathymetry, CompassDeg, Heading, Vec3};
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

/// Where survey AUV `k` is launched: its lawnmower's waypoints (x east, y north, m), its true
/// start (the first waypoint at its mission depth over the water there) and its math heading
/// towards the second waypoint (rad).
#[derive(Debug, Clone, PartialEq)]
pub struct Launch {
    pub waypoints: Vec<(f64, f64)>,
    pub pos: Vec3,
    pub heading: f64,
    /// Water depth under the start, m.
    pub bottom: f64,
}

/// Survey AUV `k`'s launch over `bathy` (the scenario's bathymetry).
pub fn auv_launch(sc: &Scenario, k: usize, bathy: &Bathymetry) -> Launch {
    let waypoints = sc.lawnmower(k).waypoints();
    let start = waypoints[0];
    let heading = waypoints.get(1).map_or(0.0, |b| (b.1 - start.1).atan2(b.0 - start.0));
    let bottom = bathy.depth_at(start.0, start.1);
    let pos = Vec3::new(start.0, start.1, sc.fleet.depth.depth_over(bottom));
    Launch { waypoints, pos, heading, bottom }
}
