//! A cached TL field: any provider (BELLHOP above all) is run once per bearing from one anchor
//! source position over a range × receiver-depth grid; lookups interpolate bilinearly in
//! (range, depth) and linearly between the two nearest bearings.
//!
//! Approximation (the thesis's "preparation mode" cached per transmission instead, Nams 2014,
//! §4.4.4; docs/models.md#nams-transmission-loss): a lookup for a source elsewhere uses the field
//! of the anchor with the same relative
//! geometry (horizontal range and bearing from source to receiver, receiver depth), i.e. it
//! assumes the environment varies slowly across the mission area. Ranges beyond the grid hold the
//! last column.

use super::{TlError, TransmissionLoss};
use coopnav_core::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Grid layout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Number of bearings, evenly spaced from 0 (east), ≥ 1.
    pub bearings: usize,
    pub range_step: f64,
    pub max_range: f64,
    pub depth_step: f64,
    pub max_depth: f64,
}

impl GridSpec {
    fn validate(&self) -> Result<(), TlError> {
        let ok = self.bearings >= 1
            && self.range_step > 0.0
            && self.max_range >= self.range_step
            && self.depth_step > 0.0
            && self.max_depth >= self.depth_step
            && [self.range_step, self.max_range, self.depth_step, self.max_depth].iter().all(|v| v.is_finite());
        if ok {
            Ok(())
        } else {
            Err(TlError::Invalid(format!(
                "grid spec {self:?}: need bearings ≥ 1 and 0 < step ≤ max for range and depth"
            )))
        }
    }
    /// Ranges from one step out (range 0 has no field).
    fn ranges(&self) -> Vec<f64> {
        let n = (self.max_range / self.range_step).round() as usize;
        (1..=n).map(|i| i as f64 * self.range_step).collect()
    }
    /// Depths from the surface: a receiver at an ASC's or a buoy's shallow transducer reads its
    /// own row, not the first row one step down (that reads an uplink to the surface well off a
    /// direct run; BELLHOP places a receiver above 0.5 m at 0.5 m).
    fn depths(&self) -> Vec<f64> {
        let n = (self.max_depth / self.depth_step).round() as usize;
        (0..=n).map(|i| i as f64 * self.depth_step).collect()
    }
}

/// The cached field.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CachedGrid {
    pub anchor: Vec3,
    pub spec: GridSpec,
    ranges: Vec<f64>,
    depths: Vec<f64>,
    /// One field per bearing, row-major by depth.
    fields: Vec<Vec<f32>>,
}

impl CachedGrid {
    /// Runs `provider` once per bearing (in parallel), calling `progress(1)` after each.
    pub fn build(
        provider: &dyn TransmissionLoss,
        anchor: Vec3,
        spec: GridSpec,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self, TlError> {
        spec.validate()?;
        let (ranges, depths) = (spec.ranges(), spec.depths());
        let fields = (0..spec.bearings)
            .into_par_iter()
            .map(|b| {
                let f = provider.field(&anchor, b as f64 * TAU / spec.bearings as f64, &ranges, &depths)?;
                progress(1);
                Ok(f.into_iter().map(|v| v as f32).collect())
            })
            .collect::<Result<Vec<Vec<f32>>, TlError>>()?;
        Ok(CachedGrid { anchor, spec, ranges, depths, fields })
    }

    fn bilinear(&self, field: &[f32], r: f64, z: f64) -> f64 {
        let pos = |axis: &[f64], step: f64, v: f64| {
            let f = ((v - axis[0]) / step).clamp(0.0, (axis.len() - 1) as f64);
            let i = (f as usize).min(axis.len().saturating_sub(2));
            (i, (f - i as f64).min(1.0))
        };
        let (ir, tr) = pos(&self.ranges, self.spec.range_step, r);
        let (iz, tz) = pos(&self.depths, self.spec.depth_step, z);
        let nr = self.ranges.len();
        let at = |i: usize, j: usize| field[j.min(self.depths.len() - 1) * nr + i.min(nr - 1)] as f64;
        let lo = at(ir, iz) * (1.0 - tr) + at(ir + 1, iz) * tr;
        let hi = at(ir, iz + 1) * (1.0 - tr) + at(ir + 1, iz + 1) * tr;
        lo * (1.0 - tz) + hi * tz
    }

    /// Interpolated TL for a receiver at horizontal range `r`, bearing `bearing` (rad), depth `z`.
    pub fn lookup(&self, r: f64, bearing: f64, z: f64) -> f64 {
        let n = self.fields.len();
        let f = bearing.rem_euclid(TAU) / TAU * n as f64;
        let (b0, t) = ((f as usize) % n, f.fract());
        let b1 = (b0 + 1) % n;
        self.bilinear(&self.fields[b0], r, z) * (1.0 - t) + self.bilinear(&self.fields[b1], r, z) * t
    }

    /// Heap size of the cached values, bytes.
    pub fn bytes(&self) -> usize {
        self.fields.iter().map(|f| f.len() * 4).sum()
    }

    /// The cached values, one field per bearing, row-major by depth (for storing on disk).
    pub fn fields(&self) -> &[Vec<f32>] {
        &self.fields
    }

    /// A grid from stored values; refuses fields that do not match the spec's axes.
    pub fn from_fields(anchor: Vec3, spec: GridSpec, fields: Vec<Vec<f32>>) -> Result<Self, TlError> {
        spec.validate()?;
        let (ranges, depths) = (spec.ranges(), spec.depths());
        let cells = ranges.len() * depths.len();
        if fields.len() != spec.bearings || fields.iter().any(|f| f.len() != cells) {
            return Err(TlError::Invalid(format!(
                "stored grid: expected {} bearings of {cells} values each",
                spec.bearings
            )));
        }
        Ok(CachedGrid { anchor, spec, ranges, depths, fields })
    }
}

/// Where the sources of an [`AnchorLattice`] sit: `nx × ny` anchors at `origin + (i, j)·spacing`,
/// repeated at every depth of `source_depths` (one layer per depth).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeSpec {
    pub origin: (f64, f64),
    pub spacing: f64,
    pub nx: usize,
    pub ny: usize,
    /// Source depths of the layers, m, strictly increasing.
    pub source_depths: Vec<f64>,
    /// How far (m) a source may sit above the first layer or below the last and still read it.
    pub depth_tolerance: f64,
}

impl LatticeSpec {
    fn anchor(&self, i: usize, j: usize, depth: f64) -> Vec3 {
        Vec3::new(self.origin.0 + i as f64 * self.spacing, self.origin.1 + j as f64 * self.spacing, depth)
    }
    /// The corner opposite the origin.
    pub fn anchor_extent(&self) -> (f64, f64) {
        let a = self.anchor(self.nx - 1, self.ny - 1, 0.0);
        (a.x, a.y)
    }
    /// Anchors layer by layer (shallowest first), each layer row by row (j outer).
    pub fn anchors(&self) -> Vec<Vec3> {
        let per_layer = |&d: &f64| (0..self.ny).flat_map(move |j| (0..self.nx).map(move |i| self.anchor(i, j, d)));
        self.source_depths.iter().flat_map(per_layer).collect()
    }

    fn problem(&self, grids: usize) -> Option<String> {
        let layers = &self.source_depths;
        let depths_ok =
            !layers.is_empty() && layers.iter().all(|d| d.is_finite()) && layers.windows(2).all(|w| w[1] > w[0]);
        let ok = self.nx >= 1
            && self.ny >= 1
            && self.spacing > 0.0
            && self.spacing.is_finite()
            && depths_ok
            && self.depth_tolerance >= 0.0
            && self.depth_tolerance.is_finite()
            && grids == self.nx * self.ny * layers.len();
        (!ok).then(|| {
            format!(
                "lattice {self:?} with {grids} grids: need nx, ny ≥ 1, spacing > 0, source depths finite and \
                 strictly increasing, depth_tolerance ≥ 0 and one grid per anchor and layer"
            )
        })
    }

    /// The layer at or above `z` and the weight of the one below it; a depth beyond the layers
    /// by more than the tolerance is refused, naming it.
    fn layer(&self, z: f64) -> Result<(usize, f64), TlError> {
        let d = &self.source_depths;
        let (first, last) = (d[0], d[d.len() - 1]);
        if !(z >= first - self.depth_tolerance && z <= last + self.depth_tolerance) {
            return Err(TlError::Invalid(format!(
                "a source at {z} m depth: the grid was built for sources at {d:?} m (± {} m); \
                 build it with a layer at that depth",
                self.depth_tolerance
            )));
        }
        let k = d.partition_point(|&l| l <= z).saturating_sub(1).min(d.len().saturating_sub(2));
        let t = if d.len() > 1 { ((z - d[k]) / (d[k + 1] - d[k])).clamp(0.0, 1.0) } else { 0.0 };
        Ok((k, t))
    }
}

/// Cached fields from a lattice of source positions, for sources that move over an environment
/// that changes across the mission area (a sloping shelf): a lookup blends the fields of the four
/// anchors around the source bilinearly, each read at the receiver's geometry relative to the
/// source (range, bearing, depth), so a source on an anchor reads that anchor's own field.
///
/// The transmitter is always the source: BELLHOP applies the beam pattern at the source only, so
/// swapping the ends (reciprocity) reads an uplink off a direct run by more than the test below
/// allows. Sources between two layers blend them linearly in depth (invented: Nams 2014, §4.2.2
/// computes every link directly; docs/models.md#nams-transmission-loss); a source outside the
/// layers is refused.
#[derive(Debug, Clone)]
pub struct AnchorLattice {
    pub lattice: LatticeSpec,
    grids: Vec<CachedGrid>,
}

impl AnchorLattice {
    /// Runs `provider` for every anchor and bearing (in parallel), `progress(1)` after each field.
    pub fn build(
        provider: &dyn TransmissionLoss,
        lattice: LatticeSpec,
        spec: GridSpec,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self, TlError> {
        if let Some(problem) = lattice.problem(lattice.nx * lattice.ny * lattice.source_depths.len()) {
            return Err(TlError::Invalid(problem));
        }
        let grids = lattice
            .anchors()
            .into_par_iter()
            .map(|a| CachedGrid::build(provider, a, spec.clone(), progress))
            .collect::<Result<Vec<_>, _>>()?;
        Self::from_grids(lattice, grids)
    }

    /// A lattice from stored grids, one per anchor in [`LatticeSpec::anchors`] order.
    pub fn from_grids(lattice: LatticeSpec, grids: Vec<CachedGrid>) -> Result<Self, TlError> {
        match lattice.problem(grids.len()) {
            Some(problem) => Err(TlError::Invalid(problem)),
            None => Ok(AnchorLattice { lattice, grids }),
        }
    }

    pub fn grids(&self) -> &[CachedGrid] {
        &self.grids
    }

    /// Index and weight along one lattice axis (held at the edges).
    fn axis(n: usize, v: f64) -> (usize, f64) {
        let f = v.clamp(0.0, (n - 1) as f64);
        let i = (f as usize).min(n.saturating_sub(2));
        (i, if n > 1 { f - i as f64 } else { 0.0 })
    }

    /// The four anchors around `src` in layer `k`, blended bilinearly.
    fn in_layer(&self, k: usize, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
        let l = &self.lattice;
        let (i, ti) = Self::axis(l.nx, (src.x - l.origin.0) / l.spacing);
        let (j, tj) = Self::axis(l.ny, (src.y - l.origin.1) / l.spacing);
        let at = |i: usize, j: usize| self.grids[(k * l.ny + j.min(l.ny - 1)) * l.nx + i.min(l.nx - 1)].tl(src, rx);
        let lo = at(i, j)? * (1.0 - ti) + at(i + 1, j)? * ti;
        let hi = at(i, j + 1)? * (1.0 - ti) + at(i + 1, j + 1)? * ti;
        Ok(lo * (1.0 - tj) + hi * tj)
    }
}

impl TransmissionLoss for AnchorLattice {
    fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
        let (k, t) = self.lattice.layer(src.z)?;
        let upper = self.in_layer(k, src, rx)?;
        if t == 0.0 {
            return Ok(upper);
        }
        Ok(upper * (1.0 - t) + self.in_layer(k + 1, src, rx)? * t)
    }
}

impl TransmissionLoss for CachedGrid {
    fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
        let (dx, dy) = (rx.x - src.x, rx.y - src.y);
        if !(dx.is_finite() && dy.is_finite() && rx.z.is_finite()) {
            return Err(TlError::Invalid(format!("non-finite positions {src:?} → {rx:?}")));
        }
        Ok(self.lookup(dx.hypot(dy), dy.atan2(dx), rx.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tl::analytic::Thorp;

    /// A provider whose TL is linear in range, depth and (away from the wrap) bearing, so
    /// interpolation must reproduce it exactly.
    struct Plane;
    impl TransmissionLoss for Plane {
        fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
            let r = (rx.x - src.x).hypot(rx.y - src.y);
            Ok(30.0 + 0.01 * r + 0.5 * rx.z)
        }
    }

    fn spec() -> GridSpec {
        GridSpec { bearings: 4, range_step: 50.0, max_range: 3000.0, depth_step: 5.0, max_depth: 60.0 }
    }

    #[test]
    fn interpolation_is_exact_for_linear_fields() {
        let g = CachedGrid::build(&Plane, Vec3::new(0.0, 0.0, 5.0), spec(), &|_| {}).unwrap();
        for (r, z) in [(50.0, 5.0), (123.0, 17.5), (2999.0, 59.0), (777.7, 33.3)] {
            let want = 30.0 + 0.01 * r + 0.5 * z;
            assert!((g.lookup(r, 1.0, z) - want).abs() < 1e-3, "{r} {z}: {} vs {want}", g.lookup(r, 1.0, z));
        }
        // Held beyond the grid.
        assert!((g.lookup(5000.0, 0.0, 60.0) - g.lookup(3000.0, 0.0, 60.0)).abs() < 1e-9);
        assert_eq!(g.bytes(), 4 * 60 * 13 * 4, "60 ranges × 13 depths (0 to 60 m) × 4 bearings");
    }

    #[test]
    fn matches_the_analytic_model_closely() {
        let t = Thorp::default();
        let anchor = Vec3::new(0.0, 0.0, 10.0);
        let g = CachedGrid::build(&t, anchor, spec(), &|_| {}).unwrap();
        // (Below ~150 m the 50 m grid under-samples the log curve; the test starts above.)
        for r in [160.0, 333.0, 1234.0, 2800.0] {
            let rx = Vec3::new(r * 0.6, r * 0.8, 10.0);
            let exact = t.tl(&anchor, &rx).unwrap();
            let cached = g.tl(&anchor, &rx).unwrap();
            assert!((exact - cached).abs() < 0.2, "{r}: {exact} vs {cached}");
        }
    }

    #[test]
    fn a_lattice_reads_each_anchors_field_at_the_sources_relative_geometry() {
        // Thorp depends on the geometry only, so every anchor holds the same field and a source
        // anywhere (between anchors, or off the lattice) reads the analytic value.
        let t = Thorp::default();
        let lattice = LatticeSpec {
            origin: (0.0, 0.0),
            spacing: 500.0,
            nx: 3,
            ny: 2,
            source_depths: vec![1.0],
            depth_tolerance: 0.5,
        };
        let l = AnchorLattice::build(&t, lattice.clone(), spec(), &|_| {}).unwrap();
        assert_eq!(l.grids().len(), 6);
        assert_eq!(lattice.anchor_extent(), (1000.0, 500.0));
        for src in [Vec3::new(130.0, 420.0, 1.0), Vec3::new(-300.0, 900.0, 1.4)] {
            let rx = Vec3::new(src.x + 400.0, src.y - 300.0, 1.0);
            let (exact, cached) = (t.tl(&src, &rx).unwrap(), l.tl(&src, &rx).unwrap());
            assert!((exact - cached).abs() < 0.2, "{src:?}: {exact} vs {cached}");
        }
        assert!(AnchorLattice::from_grids(lattice, Vec::new()).is_err());
    }

    /// A provider whose TL grows with the source's depth, to tell the layers apart.
    struct DepthPlane;
    impl TransmissionLoss for DepthPlane {
        fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
            Ok(40.0 + 0.01 * (rx.x - src.x).hypot(rx.y - src.y) + 0.3 * src.z + 0.5 * rx.z)
        }
    }

    /// 2 × 2 anchors 500 m apart from `origin`, one layer per source depth, 1 m tolerance.
    fn square_lattice(origin: (f64, f64), source_depths: &[f64]) -> LatticeSpec {
        LatticeSpec {
            origin,
            spacing: 500.0,
            nx: 2,
            ny: 2,
            source_depths: source_depths.to_vec(),
            depth_tolerance: 1.0,
        }
    }

    #[test]
    fn the_transmitter_is_the_source_layers_blend_in_depth_and_a_depth_not_built_is_refused() {
        let lattice = square_lattice((0.0, 0.0), &[0.0, 20.0, 30.0]);
        let l = AnchorLattice::build(&DepthPlane, lattice.clone(), spec(), &|_| {}).unwrap();
        assert_eq!(l.grids().len(), 12);
        let (ship, auv) = (Vec3::new(200.0, 100.0, 0.0), Vec3::new(600.0, 400.0, 20.0));
        for (src, rx) in
            [(ship, auv), (auv, ship), (Vec3::new(100.0, 300.0, 25.0), ship), (auv, Vec3::new(100.0, 100.0, 30.0))]
        {
            let rx = Vec3::new(rx.x + 10.0, rx.y, rx.z);
            let (exact, cached) = (DepthPlane.tl(&src, &rx).unwrap(), l.tl(&src, &rx).unwrap());
            assert!((exact - cached).abs() < 1e-3, "{src:?} → {rx:?}: {exact} vs {cached}");
        }
        // Uplink and downlink differ (10 dB vs 6 dB of depth terms): no reciprocity swap.
        assert!((l.tl(&ship, &auv).unwrap() - l.tl(&auv, &ship).unwrap() - 4.0).abs() < 1e-3);
        for z in [-1.5, 31.5, f64::NAN] {
            let err = l.tl(&Vec3::new(0.0, 0.0, z), &auv).unwrap_err().to_string();
            assert!(err.contains(&format!("{z} m depth")) && err.contains("[0.0, 20.0, 30.0]"), "{err}");
        }
        let unordered = LatticeSpec { source_depths: vec![20.0, 0.0], ..lattice.clone() };
        assert!(AnchorLattice::build(&DepthPlane, unordered, spec(), &|_| {}).is_err());
        let none = LatticeSpec { source_depths: Vec::new(), ..lattice };
        assert!(AnchorLattice::build(&DepthPlane, none, spec(), &|_| {}).is_err());
    }

    /// The cached grid must read within 1 dB of a direct BELLHOP run at the same point,
    /// for the CNA's downlink, the AUVs' uplink, and a buoy's 1 m transducer on a grid built at
    /// the ASC's 0 m. Grid: 16 bearings, 10 m × 2 m cells, anchors 500 m apart, layers at the ASC's
    /// 0 m and the AUVs' 20 m and 28 m; sources off the anchors, nodes and bearings (one AUV 390 m
    /// beyond the lattice). The uplink must read its own field, not the downlink's (no
    /// reciprocity swap), and the surface receiver its own row; a source blended between two
    /// layers reads further off, so layers must sit at the transmitters' depths.
    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn a_lattice_grid_agrees_with_direct_bellhop_runs_within_1_db() {
        use crate::tl::bellhop::{AcousticEnv, Bellhop};
        use coopnav_core::{Bathymetry, Shelf};
        let bathy = std::sync::Arc::new(Bathymetry::shelf(&Shelf::default()).unwrap());
        let bh = Bellhop::new(AcousticEnv::nams(bathy)).expect("build.rs found BELLHOP installed");
        let lattice = square_lattice((500.0, 500.0), &[0.0, 20.0, 28.0]);
        let spec = GridSpec { bearings: 16, range_step: 10.0, max_range: 1200.0, depth_step: 2.0, max_depth: 60.0 };
        let l = AnchorLattice::build(&bh, lattice, spec, &|_| {}).unwrap();
        // (ASC position, range m, bearing deg, AUV depth m).
        let cases = [
            (Vec3::new(730.0, 860.0, 0.0), 333.0, 17.0, 20.0),
            (Vec3::new(980.0, 520.0, 0.0), 150.0, 100.0, 28.0),
            (Vec3::new(600.0, 990.0, 0.0), 512.0, 300.0, 20.0),
            (Vec3::new(750.0, 750.0, 0.0), 905.0, 45.0, 28.0),
            (Vec3::new(500.0, 500.0, 0.0), 381.0, 23.2, 28.0),
        ];
        for (asc, r, deg, z) in cases {
            let b = f64::to_radians(deg);
            let auv = Vec3::new(asc.x + r * b.cos(), asc.y + r * b.sin(), z);
            let buoy = Vec3::new(asc.x, asc.y, 1.0);
            for (link, src, rx) in [("downlink", asc, auv), ("uplink", auv, asc), ("buoy", buoy, auv)] {
                let (direct, cached) = (bh.tl(&src, &rx).unwrap(), l.tl(&src, &rx).unwrap());
                assert!(
                    (direct - cached).abs() <= 1.0,
                    "{link} {src:?} → {rx:?}: direct {direct:.2} dB, grid {cached:.2} dB"
                );
            }
        }
    }

    #[test]
    fn bad_spec_is_rejected() {
        let bad = GridSpec { bearings: 0, ..spec() };
        assert!(CachedGrid::build(&Plane, Vec3::zeros(), bad, &|_| {}).is_err());
        let bad = GridSpec { range_step: -1.0, ..spec() };
        assert!(CachedGrid::build(&Plane, Vec3::zeros(), bad, &|_| {}).is_err());
    }
}
