//! The scenario seen by the transmission-loss models: the water and where packets leave from
//! ([`TlSite`]), and the provider of transmission loss a run uses.

use super::start::cna_start;
use super::world::Scenario;
use crate::models::tl::TlSite;
use coopnav_acomms::tl::{TlError, TransmissionLoss};
use coopnav_plan::CnaKind;
use std::sync::Arc;

impl Scenario {
    /// The site a BELLHOP model needs: the bathymetry and the true sound speed; every survey
    /// AUV's waypoint, the CNA's start and the buoys' deployments as the points to cover; the
    /// depths packets leave from.
    pub fn tl_site(&self) -> TlSite {
        let start = cna_start(self).pos;
        let points = (0..self.fleet.n_auvs)
            .flat_map(|k| self.lawnmower(k).waypoints())
            .chain([(start.x, start.y)])
            .chain(self.buoys.iter().map(|b| (b.x, b.y)))
            .collect();
        let transponder_depths =
            self.buoys.iter().map(|b| b.modem_depth_m).chain(self.ships.iter().map(|s| s.outriggers.depth)).collect();
        // An AUV CNA pings from every depth it can reach. From the surface even above a working
        // `min_depth` when it climbs there for its GPS fixes, and pings meanwhile.
        let cna_span = match self.platform().cna {
            CnaKind::Auv { min_depth, max_depth, .. } => {
                let top = if self.cna.navigation.surfacing().is_some() { 0.0 } else { min_depth.max(0.0) };
                Some((top, max_depth))
            }
            CnaKind::Asc {} => None,
        };
        TlSite {
            bathymetry: self.bathymetry(),
            sound_speed: self.channel.sound_speed.clone(),
            points,
            cna_depth: start.z,
            transponder_depths,
            cna_span,
            fleet_depth: self.fleet.depth,
            max_range_m: self.comms.max_range_m,
        }
    }

    /// The transmission-loss provider of `comms.tl` over this scenario's site.
    pub fn tl_provider(&self) -> Result<Arc<dyn TransmissionLoss>, TlError> {
        self.comms.tl.provider(|| self.tl_site())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::tl::layout;
    use crate::models::tl_spec::GridModel;

    #[test]
    fn the_lattice_covers_the_fleet_and_the_grid_the_schedules_range() {
        let sc = Scenario::example();
        let (lattice, spec) = layout(&GridModel::default(), &sc.tl_site());
        let far = lattice.anchor_extent();
        for k in 0..sc.fleet.n_auvs {
            for (x, y) in sc.lawnmower(k).waypoints() {
                assert!(x >= lattice.origin.0 && y >= lattice.origin.1 && x <= far.0 && y <= far.1, "({x}, {y})");
            }
        }
        assert!(spec.max_range >= sc.comms.max_range_m && spec.max_depth >= sc.bathymetry().max_depth());
        assert_eq!(lattice.source_depths, [0.0, 20.0], "the ASC's depth and the AUVs'");
    }

    /// A library scenario, parsed without validation (validating builds the grid), and the source
    /// layers its grid gets at 10 m steps.
    fn library_layers(file: &str) -> (Scenario, Vec<f64>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(file);
        let sc: Scenario = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let (lattice, _) = layout(&GridModel { source_depth_step_m: 10.0, ..GridModel::default() }, &sc.tl_site());
        (sc, lattice.source_depths)
    }

    #[test]
    fn every_transmitter_depth_has_a_layer() {
        let (sc, layers) = library_layers("full-stack.toml");
        // The ASC at 0 m, the buoys' 1 m modems, the AUVs at 15 m over 30–90 m of shelf.
        assert_eq!(&layers[..2], [0.0, 1.0]);
        assert_eq!(layers[2], 15.0, "over the shallowest 30 m");
        assert!(layers[2..].windows(2).all(|w| w[1] - w[0] <= 10.0 + 1e-9), "{layers:?}");
        let bathymetry = sc.bathymetry();
        for (x, y) in (0..sc.fleet.n_auvs).flat_map(|k| sc.lawnmower(k).waypoints()) {
            let z = bathymetry.depth_at(x, y) - 15.0;
            assert!(z >= layers[2] && z <= *layers.last().unwrap(), "an AUV at {z} m, layers {layers:?}");
        }
    }

    #[test]
    fn an_auv_cna_has_layers_over_every_depth_it_can_reach() {
        let (_, layers) = library_layers("sloping-auv-cna.toml");
        // From the surface (where the CNA climbs for its fixes) down to the shelf's deepest water, 90 m
        // (the lattice reaches past x = 1700 m), never more than a step apart: a lookup anywhere
        // in between is blended, never refused.
        assert_eq!((layers[0], *layers.last().unwrap()), (0.0, 90.0), "{layers:?}");
        assert!(layers.windows(2).all(|w| w[1] - w[0] <= 10.0 + 1e-9), "{layers:?}");
        // The ASC of the default mission still gets only its own depth.
        let g = GridModel { source_depth_step_m: 10.0, ..GridModel::default() };
        let (asc, _) = layout(&g, &Scenario::example().tl_site());
        assert_eq!(asc.source_depths, [0.0, 20.0]);
    }
}
