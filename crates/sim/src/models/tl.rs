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
use crate::scenario::start::cna_start;
use crate::scenario::world::Scenario;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::tl::cached::{AnchorLattice, CachedGrid, GridSpec, LatticeSpec};
use coopnav_acomms::tl::{TlError, TransmissionLoss};
use coopnav_core::DepthTarget;
use coopnav_plan::CnaKind;
use serde::Serialize;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, OnceLock};

impl TlModel {
    /// The provider a run uses. BELLHOP kinds need the program; a grid is computed at most once
    /// per process and once per machine (disk cache), whichever run asks first.
    pub fn provider(&self, sc: &Scenario) -> Result<Arc<dyn TransmissionLoss>, TlError> {
        match self {
            TlModel::Analytic(t) => Ok(Arc::new(*t)),
            TlModel::Bellhop => Ok(Arc::new(Bellhop::new(environment(sc))?)),
            TlModel::BellhopGrid(g) => grid(g, sc).map(|l| l as Arc<dyn TransmissionLoss>),
        }
    }
}

/// The thesis's acoustic environment (Nams 2014, §4.2 and App. A: mud half-space, 25 kHz, BT-1 pattern) over
/// the scenario's bathymetry, with the scenario's true sound-speed profile.
fn environment(sc: &Scenario) -> AcousticEnv {
    let mut env = AcousticEnv::nams(Arc::new(sc.bathymetry()));
    env.ssp = match &sc.channel.sound_speed {
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

fn grid(g: &GridModel, sc: &Scenario) -> Result<Arc<AnchorLattice>, TlError> {
    let env = environment(sc);
    let (lattice, spec) = layout(g, sc);
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
fn layout(g: &GridModel, sc: &Scenario) -> (LatticeSpec, GridSpec) {
    let start = cna_start(sc).pos;
    let points = (0..sc.fleet.n_auvs)
        .flat_map(|k| sc.lawnmower(k).waypoints())
        .chain([(start.x, start.y)])
        .chain(sc.buoys.iter().map(|b| (b.x, b.y)));
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for (x, y) in points {
        (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
    }
    let (lo, hi) = ((lo.0 - g.margin_m, lo.1 - g.margin_m), (hi.0 + g.margin_m, hi.1 + g.margin_m));
    let count = |span: f64| (span / g.anchor_spacing_m).ceil() as usize + 1;
    let lattice = LatticeSpec {
        origin: lo,
        spacing: g.anchor_spacing_m,
        nx: count(hi.0 - lo.0),
        ny: count(hi.1 - lo.1),
        source_depths: source_layers(g, sc, start.z, (lo, hi)),
        depth_tolerance: SOURCE_DEPTH_TOLERANCE_M,
    };
    let max_range = (1.2 * sc.comms.max_range_m / g.range_step_m).ceil() * g.range_step_m;
    let max_depth = (sc.bathymetry().max_depth() / g.depth_step_m).ceil() * g.depth_step_m;
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
fn source_layers(g: &GridModel, sc: &Scenario, cna_depth: f64, (lo, hi): ((f64, f64), (f64, f64))) -> Vec<f64> {
    let mut depths: Vec<f64> = std::iter::once(cna_depth)
        .chain(sc.buoys.iter().map(|b| b.modem_depth_m))
        .chain(sc.ships.iter().map(|s| s.outriggers.depth))
        .collect();
    let water = || water_span(sc, (lo, hi));
    let span = |top: f64, bottom: f64| {
        let layers = ((bottom - top) / g.source_depth_step_m).ceil().max(0.0) as usize;
        (0..=layers).map(move |i| (top + i as f64 * g.source_depth_step_m).min(bottom))
    };
    if let CnaKind::Auv { min_depth, max_depth, .. } = sc.platform().cna {
        // Without these layers a depth change of more than the tolerance would leave every
        // later CNA packet without a transmission loss, i.e. lost. From the surface even below a
        // working `min_depth`: the CNA climbs there for its GPS fixes, and pings meanwhile.
        let top = if sc.cna.navigation.surfacing().is_some() { 0.0 } else { min_depth.max(0.0) };
        depths.extend(span(top, max_depth.min(water().1)));
    }
    match sc.fleet.depth {
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
fn water_span(sc: &Scenario, (lo, hi): ((f64, f64), (f64, f64))) -> (f64, f64) {
    let bathymetry = sc.bathymetry();
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
        let fields: Vec<String> = bad.problems("comms.tl.").into_iter().map(|p| p.0).collect();
        assert_eq!(fields, ["comms.tl.bearings", "comms.tl.anchor_spacing_m"]);
        let flat = TlModel::BellhopGrid(GridModel { source_depth_step_m: 0.1, ..GridModel::default() });
        assert_eq!(flat.problems("comms.tl.")[0].0, "comms.tl.source_depth_step_m");
        assert!(TlModel::Analytic(Thorp { k: -1.0, freq_hz: 25_000.0 }).problems("t.")[0].0 == "t.k");
    }

    #[test]
    fn the_lattice_covers_the_fleet_and_the_grid_the_schedules_range() {
        let sc = Scenario::example();
        let (lattice, spec) = layout(&GridModel::default(), &sc);
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
        let (lattice, _) = layout(&GridModel { source_depth_step_m: 10.0, ..GridModel::default() }, &sc);
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
        let (asc, _) = layout(&g, &Scenario::example());
        assert_eq!(asc.source_depths, [0.0, 20.0]);
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
    fn small_grid(sc: &Scenario, bearings: usize, range_m: f64, cache_dir: &std::path::Path) -> (GridModel, Scenario) {
        let g = GridModel {
            bearings,
            range_step_m: 20.0,
            anchor_spacing_m: 10_000.0,
            margin_m: 0.0,
            cache_dir: Some(cache_dir.to_path_buf()),
            ..GridModel::default()
        };
        let mut sc = sc.clone();
        sc.comms.max_range_m = range_m;
        (g, sc)
    }

    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn grids_asked_for_from_inside_a_pools_jobs_are_built_once_per_key_without_deadlock() {
        use rayon::prelude::*;
        let dir = tempfile::tempdir().unwrap();
        let example = Scenario::example();
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
                                let (g, sc) = &keys[job % 2];
                                grid(g, sc).map_err(|e| e.to_string())
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
        let mut sc = Scenario::example();
        sc.channel.sound_speed = SoundSpeed::Profile { points: vec![[5.0, 1500.0], [50.0, 1480.0]] };
        assert_eq!(environment(&sc).ssp, vec![(0.0, 1500.0), (5.0, 1500.0), (50.0, 1480.0)]);
    }
}
