//! Transmission loss as the sea plays it (`[comms] tl`), a named model: `analytic` (spreading +
//! Thorp absorption), `bellhop` (one real BELLHOP run per arrival, over the scenario's bathymetry
//! and sound-speed profile: the reference, slow) or `bellhop_grid` (BELLHOP fields from a lattice
//! of source positions over the mission area, computed once per scenario, cached on disk keyed
//! by every input, and interpolated: what Monte Carlo runs use). A table without `kind` is
//! `analytic` (the files written before the models existed).
//!
//! The planner's lost-ping likelihood keeps an analytic model ([`TlModel::assumed`]): what the
//! CNA believes, apart from the truth (unless `policy.link = "scenario_channel"` gives it this
//! provider).

use super::tl_spec::{GridModel, TlModel, MAX_GRID_FIELDS};
use crate::models::channel::SoundSpeed;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::tl::cached::{AnchorLattice, CachedGrid, GridSpec, LatticeSpec};
use coopnav_acomms::tl::{TlError, TransmissionLoss};
use coopnav_core::{Bathymetry, DepthTarget};
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, OnceLock};

/// What a transmission-loss provider reads of a mission: the water, and where packets leave
/// from. The scenario builds it (`Scenario::tl_site`); the models know nothing else of a scenario.
#[derive(Debug, Clone)]
pub struct TlSite {
    /// The seafloor.
    pub bathymetry: Bathymetry,
    /// The water's true sound-speed profile.
    pub sound_speed: SoundSpeed,
    /// Every point a grid's lattice covers: the survey AUVs' waypoints, the CNA's start, the
    /// buoys' deployments.
    pub points: Vec<(f64, f64)>,
    /// The CNA's depth at its start, m.
    pub cna_depth: f64,
    /// The depths of the other fixed transmitters, m: each buoy's modem, then each ship's
    /// outriggers.
    pub transponder_depths: Vec<f64>,
    /// An AUV CNA's depth span, m: from its top (the surface, when it climbs there for its fixes)
    /// to the deepest its planner may take it. `None` for a surface CNA.
    pub cna_span: Option<(f64, f64)>,
    /// The survey AUVs' depth or altitude.
    pub fleet_depth: DepthTarget,
    /// The schedule's longest range, m.
    pub max_range_m: f64,
}

impl TlModel {
    /// The provider a run uses, `site` asked for only by the kinds that read it. BELLHOP kinds
    /// need the program; a grid is computed at most once per process and once per machine (disk
    /// cache), whichever run asks first.
    pub fn provider(&self, site: impl FnOnce() -> TlSite) -> Result<Arc<dyn TransmissionLoss>, TlError> {
        match self {
            TlModel::Analytic(t) => Ok(Arc::new(*t)),
            TlModel::Bellhop => Ok(Arc::new(Bellhop::new(environment(&site()))?)),
            TlModel::BellhopGrid(g) => grid(g, &site()).map(|l| l as Arc<dyn TransmissionLoss>),
        }
    }
}

/// The thesis's acoustic environment (Nams 2014, §4.2 and App. A: mud half-space, 25 kHz, BT-1 pattern) over
/// the site's bathymetry, with its true sound-speed profile.
fn environment(site: &TlSite) -> AcousticEnv {
    let mut env = AcousticEnv::nams(Arc::new(site.bathymetry.clone()));
    env.ssp = match &site.sound_speed {
        SoundSpeed::Constant { c } => vec![(0.0, *c)],
        s @ SoundSpeed::Profile { points } => {
            let below = points.iter().filter(|p| p[0] > 0.0).map(|p| (p[0], p[1]));
            std::iter::once((0.0, s.at(0.0))).chain(below).collect()
        }
    };
    env
}

/// Everything a grid depends on, as the disk cache's key.
#[derive(Serialize)]
struct GridInputs<'a> {
    format: u32,
    bathymetry: &'a coopnav_core::Bathymetry,
    ssp: &'a [(f64, f64)],
    freq_hz: f64,
    beam: &'a [(f64, f64)],
    lattice: &'a LatticeSpec,
    spec: &'a GridSpec,
    bellhop_bytes: u64,
}

fn grid(g: &GridModel, site: &TlSite) -> Result<Arc<AnchorLattice>, TlError> {
    let env = environment(site);
    let (lattice, spec) = layout(g, site);
    let layers = lattice.source_depths.len();
    let fields = lattice.nx * lattice.ny * layers * spec.bearings;
    if fields > MAX_GRID_FIELDS {
        return Err(TlError::Invalid(format!(
            "the grid needs {fields} BELLHOP runs ({} × {} anchors × {layers} source depths {:?} m × {} bearings), \
             more than {MAX_GRID_FIELDS}: widen anchor_spacing_m or source_depth_step_m, or lower bearings",
            lattice.nx, lattice.ny, lattice.source_depths, spec.bearings
        )));
    }
    let exe = Bellhop::locate()?;
    let inputs = GridInputs {
        format: 2,
        bathymetry: &env.bathymetry,
        ssp: &env.ssp,
        freq_hz: env.freq_hz,
        beam: &env.beam,
        lattice: &lattice,
        spec: &spec,
        bellhop_bytes: std::fs::metadata(&exe).map(|m| m.len()).unwrap_or(0),
    };
    let key_text = serde_json::to_string(&inputs).map_err(|e| TlError::Invalid(e.to_string()))?;
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    key_text.hash(&mut hasher);
    let key = format!("{:016x}", hasher.finish());
    // The key's own slot, locked while its grid is read or computed: callers of one key compute
    // it once, callers of other keys go on.
    let slot = memo_slot(&key);
    let mut held = slot.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(l) = held.as_ref() {
        return Ok(l.clone());
    }
    let dir = g.cache_dir.clone().unwrap_or_else(|| std::env::temp_dir().join("coopnav-tl"));
    let path = dir.join(format!("grid-{key}.bin"));
    let lattice_grids = match disk::read(&path, &key_text, &lattice, &spec) {
        Some(l) => l,
        None => {
            tracing::info!(fields, path = %path.display(), "computing the BELLHOP grid");
            let l = build_apart(&Bellhop::with_exe(exe, env)?, lattice, spec)?;
            if let Err(e) = disk::write(&dir, &path, &key_text, &l) {
                tracing::warn!(path = %path.display(), error = %e, "BELLHOP grid not cached on disk");
            }
            l
        }
    };
    let l = Arc::new(lattice_grids);
    *held = Some(l.clone());
    Ok(l)
}

/// A grid computed in this process (`None` until one is, or after a failed attempt: the next
/// caller tries again).
type Slot = Arc<Mutex<Option<Arc<AnchorLattice>>>>;

/// The slot of `key`, handed out under a lock held only for the lookup.
fn memo_slot(key: &str) -> Slot {
    static SLOTS: OnceLock<Mutex<HashMap<String, Slot>>> = OnceLock::new();
    let mut slots = SLOTS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    slots.entry(key.to_string()).or_default().clone()
}

/// Computes the lattice on a rayon pool of its own, driven from a thread of its own. The caller
/// may be a rayon job (an experiment's runs in a pool) holding its key's slot while other jobs wait
/// on it: run on the caller's pool, the build's parallel work could wait on a worker blocked on
/// that slot, or the caller, waiting for its stolen work, could pick up a run asking for the slot
/// it holds. A plain thread waits without running other jobs, and the grid's own pool (as many
/// threads as the caller's) runs nothing but the grid.
fn build_apart(bellhop: &Bellhop, lattice: LatticeSpec, spec: GridSpec) -> Result<AnchorLattice, TlError> {
    let threads = rayon::current_num_threads();
    std::thread::scope(|s| {
        let builder = s.spawn(|| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("bellhop-grid-{i}"))
                .build()
                .map_err(|e| TlError::Invalid(format!("no thread pool for the BELLHOP grid: {e}")))?;
            pool.install(|| AnchorLattice::build(bellhop, lattice, spec, &|_| {}))
        });
        builder.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// The anchors over the survey blocks, the CNA start and the buoys' deployments (widened by the
/// margin), one layer per depth a transmitter sends from, and the field each one holds: to 1.2 ×
/// the schedule's longest range, over the deepest water there.
pub(crate) fn layout(g: &GridModel, site: &TlSite) -> (LatticeSpec, GridSpec) {
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for &(x, y) in &site.points {
        (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
    }
    let (lo, hi) = ((lo.0 - g.margin_m, lo.1 - g.margin_m), (hi.0 + g.margin_m, hi.1 + g.margin_m));
    let count = |span: f64| (span / g.anchor_spacing_m).ceil() as usize + 1;
    let lattice = LatticeSpec {
        origin: lo,
        spacing: g.anchor_spacing_m,
        nx: count(hi.0 - lo.0),
        ny: count(hi.1 - lo.1),
        source_depths: source_layers(g, site, (lo, hi)),
        depth_tolerance: SOURCE_DEPTH_TOLERANCE_M,
    };
    let max_range = (1.2 * site.max_range_m / g.range_step_m).ceil() * g.range_step_m;
    let max_depth = (site.bathymetry.max_depth() / g.depth_step_m).ceil() * g.depth_step_m;
    let spec =
        GridSpec { bearings: g.bearings, range_step: g.range_step_m, max_range, depth_step: g.depth_step_m, max_depth };
    (lattice, spec)
}

/// How far a source may sit from the layers' span, m. Invented; measured (acomms `tl::cached`
/// tests): a buoy's 1 m transducer read from the ASC's 0 m layer is within 0.81 dB of a direct run.
const SOURCE_DEPTH_TOLERANCE_M: f64 = 1.0;

/// Every depth a packet leaves from: the CNA's (an AUV CNA's whole reachable span: the planner's
/// depth limits down to the deepest water under the lattice), each buoy's modem, each ship's
/// outriggers, and the survey AUVs' (their status messages): their depth, or, keeping altitude,
/// the span the terrain under the lattice gives them. A span gets one layer every
/// `source_depth_step_m`. Sorted, without near-duplicates.
fn source_layers(g: &GridModel, site: &TlSite, (lo, hi): ((f64, f64), (f64, f64))) -> Vec<f64> {
    let mut depths: Vec<f64> = std::iter::once(site.cna_depth).chain(site.transponder_depths.iter().copied()).collect();
    let water = || water_span(&site.bathymetry, (lo, hi));
    let span = |top: f64, bottom: f64| {
        let layers = ((bottom - top) / g.source_depth_step_m).ceil().max(0.0) as usize;
        (0..=layers).map(move |i| (top + i as f64 * g.source_depth_step_m).min(bottom))
    };
    if let Some((top, deepest)) = site.cna_span {
        // Without these layers a depth change of more than the tolerance would leave every
        // later CNA packet without a transmission loss, i.e. lost.
        depths.extend(span(top, deepest.min(water().1)));
    }
    match site.fleet_depth {
        DepthTarget::Depth { depth } => depths.push(depth),
        DepthTarget::Altitude { altitude } => {
            let (shallow, deep) = water();
            depths.extend(span((shallow - altitude).max(0.0), (deep - altitude).max(0.0)));
        }
    }
    depths.sort_by(f64::total_cmp);
    depths.dedup_by(|b, a| *b - *a < 0.5 * SOURCE_DEPTH_TOLERANCE_M);
    depths
}

/// The shallowest and deepest water under the lattice's box, m, sampled every
/// [`TERRAIN_SAMPLE_M`].
fn water_span(bathymetry: &Bathymetry, (lo, hi): ((f64, f64), (f64, f64))) -> (f64, f64) {
    let (nx, ny) =
        (((hi.0 - lo.0) / TERRAIN_SAMPLE_M).ceil() as usize, ((hi.1 - lo.1) / TERRAIN_SAMPLE_M).ceil() as usize);
    (0..=nx)
        .flat_map(|i| (0..=ny).map(move |j| (lo.0 + i as f64 * TERRAIN_SAMPLE_M, lo.1 + j as f64 * TERRAIN_SAMPLE_M)))
        .map(|(x, y)| bathymetry.depth_at(x, y))
        .fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)))
}

/// Terrain sampling for the altitude-keeping AUVs' depth span, m.
const TERRAIN_SAMPLE_M: f64 = 50.0;

/// The disk cache: one file per grid, its key text on the first line (checked on reading, so a
/// hash collision or a changed format recomputes), then every field's f32 values, little-endian.
mod disk {
    use super::*;
    use std::io::Write;

    pub fn read(
        path: &std::path::Path,
        key_text: &str,
        lattice: &LatticeSpec,
        spec: &GridSpec,
    ) -> Option<AnchorLattice> {
        let bytes = std::fs::read(path).ok()?;
        let newline = bytes.iter().position(|&b| b == b'\n')?;
        if &bytes[..newline] != key_text.as_bytes() {
            return None;
        }
        let values: Vec<f32> =
            bytes[newline + 1..].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        // One field per bearing of every anchor of every layer.
        let per_field = values.len() / (lattice.anchors().len() * spec.bearings).max(1);
        let mut fields = values.chunks(per_field.max(1)).map(<[f32]>::to_vec);
        let grids = lattice
            .anchors()
            .into_iter()
            .map(|a| CachedGrid::from_fields(a, spec.clone(), fields.by_ref().take(spec.bearings).collect()))
            .collect::<Result<Vec<_>, _>>()
            .ok()?;
        AnchorLattice::from_grids(lattice.clone(), grids).ok()
    }

    pub fn write(
        dir: &std::path::Path,
        path: &std::path::Path,
        key_text: &str,
        l: &AnchorLattice,
    ) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        // Written beside, then renamed: a reader never sees half a file.
        let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
        tmp.write_all(key_text.as_bytes())?;
        tmp.write_all(b"\n")?;
        for v in l.grids().iter().flat_map(|g| g.fields()).flatten() {
            tmp.write_all(&v.to_le_bytes())?;
        }
        tmp.persist(path).map(|_| ()).map_err(|e| e.error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::tl_spec::kind_defaults_to_analytic;
    use coopnav_acomms::tl::analytic::Thorp;
    use coopnav_core::validation::CheckFields;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    struct Holder {
        #[serde(deserialize_with = "kind_defaults_to_analytic")]
        tl: TlModel,
    }

    fn parse(text: &str) -> Result<TlModel, String> {
        toml::from_str::<Holder>(text).map(|h| h.tl).map_err(|e| e.to_string())
    }

    #[test]
    fn each_kind_parses_and_a_table_without_kind_is_analytic() {
        assert_eq!(
            parse("tl = { k = 2.0, freq_hz = 12000.0 }").unwrap(),
            TlModel::Analytic(Thorp { k: 2.0, freq_hz: 12_000.0 })
        );
        assert_eq!(parse("tl = { kind = \"bellhop\" }").unwrap(), TlModel::Bellhop);
        let grid = parse("tl = { kind = \"bellhop_grid\", bearings = 32 }").unwrap();
        assert_eq!(grid, TlModel::BellhopGrid(GridModel { bearings: 32, ..GridModel::default() }));
        assert!(parse("tl = { kind = \"bellhop_grid\", bearing = 32 }").unwrap_err().contains("bearing"));
        assert!(parse("tl = { kind = \"ray\" }").unwrap_err().contains("ray"));
        // The planner keeps an analytic belief whatever the sea does.
        assert_eq!(grid.assumed(), Thorp::default());
    }

    #[test]
    fn bad_fields_are_all_named() {
        let bad = TlModel::BellhopGrid(GridModel { bearings: 0, anchor_spacing_m: 10.0, ..GridModel::default() });
        let fields = bad.validate("comms.tl.").unwrap_err().fields();
        assert_eq!(fields, ["comms.tl.bearings", "comms.tl.anchor_spacing_m"]);
        let flat = TlModel::BellhopGrid(GridModel { source_depth_step_m: 0.1, ..GridModel::default() });
        assert_eq!(flat.validate("comms.tl.").unwrap_err().fields(), ["comms.tl.source_depth_step_m"]);
        assert_eq!(
            TlModel::Analytic(Thorp { k: -1.0, freq_hz: 25_000.0 }).validate("t.").unwrap_err().fields(),
            ["t.k"]
        );
    }

    /// A flat 100 m sea with a constant sound speed, an ASC at the surface and AUVs at 20 m,
    /// ranging 1 km over a 1 km square: a site no scenario file gives.
    fn flat_site() -> TlSite {
        let bathymetry =
            Bathymetry::new(-20_000.0, -20_000.0, 40_000.0, 40_000.0, 2, 2, vec![100.0; 4]).expect("a valid grid");
        TlSite {
            bathymetry,
            sound_speed: SoundSpeed::Constant { c: 1500.0 },
            points: vec![(0.0, 0.0), (1000.0, 0.0), (1000.0, 1000.0), (0.0, 1000.0)],
            cna_depth: 0.0,
            transponder_depths: vec![],
            cna_span: None,
            fleet_depth: DepthTarget::Depth { depth: 20.0 },
            max_range_m: 1000.0,
        }
    }

    #[test]
    fn the_lattice_covers_every_point_the_transmitters_depths_and_the_range() {
        let site =
            TlSite { transponder_depths: vec![1.0, 5.0], points: vec![(-250.0, 40.0), (900.0, 1310.0)], ..flat_site() };
        let g = GridModel { anchor_spacing_m: 500.0, margin_m: 100.0, ..GridModel::default() };
        let (lattice, spec) = layout(&g, &site);
        // The box (−250, 40)–(900, 1310) widened by 100 m: origin (−350, −60), 1350 × 1470 m,
        // so ⌈1350/500⌉ + 1 = 4 by ⌈1470/500⌉ + 1 = 4 anchors.
        assert_eq!(lattice.origin, (-350.0, -60.0));
        assert_eq!((lattice.nx, lattice.ny, lattice.spacing), (4, 4, 500.0));
        assert_eq!(lattice.source_depths, [0.0, 1.0, 5.0, 20.0], "the CNA, the transponders, the AUVs");
        // 1.2 × 1000 m on the range step, the 100 m floor on the depth step.
        assert_eq!(spec.max_range, (1200.0 / g.range_step_m).ceil() * g.range_step_m);
        assert_eq!(spec.max_depth, (100.0 / g.depth_step_m).ceil() * g.depth_step_m);
    }

    #[test]
    fn an_auv_cnas_span_gets_a_layer_every_step_down_to_the_water_under_the_lattice() {
        let g = GridModel { source_depth_step_m: 10.0, ..GridModel::default() };
        // A span deeper than the 100 m sea stops at the sea floor.
        let site = TlSite { cna_depth: 5.0, cna_span: Some((0.0, 250.0)), ..flat_site() };
        let (lattice, _) = layout(&g, &site);
        let want: Vec<f64> = (0..=10).map(|i| 10.0 * i as f64).collect();
        assert_eq!(lattice.source_depths, [&want[..1], &[5.0], &want[1..]].concat());
        // Near-duplicates (within half the tolerance) collapse into one layer.
        let site = TlSite { cna_depth: 20.2, ..flat_site() };
        assert_eq!(layout(&g, &site).0.source_depths, [20.0]);
    }

    #[test]
    fn a_grid_of_several_layers_reads_back_from_disk() {
        let lattice = LatticeSpec {
            origin: (0.0, 0.0),
            spacing: 100.0,
            nx: 2,
            ny: 1,
            source_depths: vec![0.0, 20.0],
            depth_tolerance: 1.0,
        };
        // 3 ranges × 3 depths per field, every value distinct.
        let spec = GridSpec { bearings: 2, range_step: 10.0, max_range: 30.0, depth_step: 5.0, max_depth: 10.0 };
        let mut next = 0.0f32;
        let grids: Vec<CachedGrid> = lattice
            .anchors()
            .into_iter()
            .map(|a| {
                let fields = (0..2).map(|_| (0..9).map(|_| (next += 1.0, next).1).collect()).collect();
                CachedGrid::from_fields(a, spec.clone(), fields).unwrap()
            })
            .collect();
        let written = AnchorLattice::from_grids(lattice.clone(), grids).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grid.bin");
        disk::write(dir.path(), &path, "key", &written).unwrap();
        let read = disk::read(&path, "key", &lattice, &spec).expect("the stored grid reads back");
        let fields = |l: &AnchorLattice| l.grids().iter().map(|g| g.fields().to_vec()).collect::<Vec<_>>();
        assert_eq!(fields(&read), fields(&written));
        assert!(disk::read(&path, "another key", &lattice, &spec).is_none());
    }

    /// A grid of a few short BELLHOP runs: the lattice's 4 anchors × 2 source layers × `bearings`,
    /// to `range_m` (part of the key: each round of a test gets keys of its own).
    fn small_grid(site: &TlSite, bearings: usize, range_m: f64, cache_dir: &std::path::Path) -> (GridModel, TlSite) {
        let g = GridModel {
            bearings,
            range_step_m: 20.0,
            anchor_spacing_m: 10_000.0,
            margin_m: 0.0,
            cache_dir: Some(cache_dir.to_path_buf()),
            ..GridModel::default()
        };
        (g, TlSite { max_range_m: range_m, ..site.clone() })
    }

    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn grids_asked_for_from_inside_a_pools_jobs_are_built_once_per_key_without_deadlock() {
        use rayon::prelude::*;
        let dir = tempfile::tempdir().unwrap();
        let example = flat_site();
        let (done, finished) = std::sync::mpsc::channel();
        let cache = dir.path().to_path_buf();
        // An experiment's runs: each does uneven parallel work of its own (so workers wait in
        // joins and steal), then asks for its grid, on a pool smaller than the jobs. Three rounds,
        // two keys each.
        std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(4).build().unwrap();
            let rounds: Vec<Vec<Result<Arc<AnchorLattice>, String>>> = (0..3)
                .map(|round| {
                    let keys =
                        [1, 2].map(|bearings| small_grid(&example, bearings, 200.0 + 20.0 * round as f64, &cache));
                    pool.install(|| {
                        (0..16)
                            .into_par_iter()
                            .map(|job| {
                                (0..4).into_par_iter().for_each(|i| {
                                    std::thread::sleep(std::time::Duration::from_millis(
                                        ((job * 7 + i * 13) % 20) as u64,
                                    ))
                                });
                                let (g, site) = &keys[job % 2];
                                grid(g, site).map_err(|e| e.to_string())
                            })
                            .collect()
                    })
                })
                .collect();
            done.send(rounds).unwrap();
        });
        let rounds = finished
            .recv_timeout(std::time::Duration::from_secs(600))
            .expect("every job got its grid within 10 minutes (a deadlock otherwise)");
        for grids in rounds {
            let grids: Vec<Arc<AnchorLattice>> = grids.into_iter().collect::<Result<_, _>>().unwrap();
            for (job, g) in grids.iter().enumerate() {
                assert!(Arc::ptr_eq(g, &grids[job % 2]), "job {job} got its key's one grid");
                assert_eq!(g.grids()[0].spec.bearings, 1 + job % 2);
            }
            assert!(!Arc::ptr_eq(&grids[0], &grids[1]), "two keys, two grids");
        }
        let files = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(files, 6, "each key computed and cached on disk once");
    }

    #[test]
    fn the_environment_carries_the_scenarios_profile_from_the_surface() {
        let site =
            TlSite { sound_speed: SoundSpeed::Profile { points: vec![[5.0, 1500.0], [50.0, 1480.0]] }, ..flat_site() };
        assert_eq!(environment(&site).ssp, vec![(0.0, 1500.0), (5.0, 1500.0), (50.0, 1480.0)]);
    }
}
