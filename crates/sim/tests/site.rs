//! Geographic missions: the library's `geographic-survey.toml` (a `.bhv` lawnmower pair about a
//! MOOS origin, a CNA start in latitude/longitude, an ESRI grid of elevations in degrees) loads to
//! the local metres computed here by hand, and bad site files are refused by name.
//!
//! The expected numbers come from the ellipsoidal flat-earth formulas, not from the code under
//! test: north = Δφ·M(φ₀), east = Δλ·N(φ₀)·cos φ₀ (M, N the WGS-84 meridian and prime-vertical
//! radii at the origin), MOOS local → lat/lon about (43.655, −70.21), then lat/lon → metres about
//! the site origin (43.65, −70.20). They differ from the tangent plane's exact projection by
//! second-order terms, d²·tan φ / 2R ≈ 0.04 m at 0.7 km, hence the 0.25 m tolerance (a swapped,
//! mis-signed or mis-scaled axis is off by hundreds of metres).

use coopnav_sim::scenario::Scenario;
use std::path::{Path, PathBuf};

fn library(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(name)
}

/// Survey AUV 0's lawnmower: `x=300, y=200, width=400, height=200, lane_width=100, rows=ns` gives
/// 5 north-south lanes at MOOS x = 100 … 500, y 100 … 300, entered at (100, 100), nearest (0, 0).
const AUV0: [(f64, f64); 10] = [
    (-706.75, 655.53),
    (-706.75, 855.53),
    (-606.75, 855.53),
    (-606.75, 655.53),
    (-506.74, 655.53),
    (-506.74, 855.53),
    (-406.73, 855.53),
    (-406.73, 655.53),
    (-306.72, 655.53),
    (-306.72, 855.53),
];

/// Survey AUV 1's: `x=750, width=300`: 4 lanes at MOOS x = 600 … 900.
const AUV1: [(f64, f64); 8] = [
    (-206.71, 655.53),
    (-206.71, 855.53),
    (-106.70, 855.53),
    (-106.70, 655.53),
    (-6.70, 655.53),
    (-6.70, 855.53),
    (93.31, 855.53),
    (93.31, 655.53),
];

#[test]
fn a_bhv_lawnmower_over_a_lat_lon_grid_loads_in_local_metres() {
    let sc = Scenario::load(&library("geographic-survey.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((sc.fleet.n_auvs, sc.fleet.speed), (2, 1.5), "from the two BHV_Waypoint blocks and their speed");
    for (k, want) in [AUV0.as_slice(), AUV1.as_slice()].into_iter().enumerate() {
        let got = sc.lawnmower(k).waypoints();
        assert_eq!(got.len(), want.len(), "auv{k}: {got:?}");
        for (g, w) in got.iter().zip(want) {
            assert!((g.0 - w.0).abs() < 0.25 && (g.1 - w.1).abs() < 0.25, "auv{k}: {g:?} vs {w:?}");
        }
    }
    // The CNA at (43.6555, −70.2045).
    assert!((sc.cna.x + 363.04).abs() < 0.25 && (sc.cna.y - 611.08).abs() < 0.25, "{:?}", (sc.cna.x, sc.cna.y));
    // The grid's elevations are −(40 + 500·(λ + 70.225) + 200·(φ − 43.64)) m: depths at survey
    // AUV 0's first waypoint and AUV 1's last, at the lat/lon the formulas above give them.
    let bathy = sc.bathymetry();
    for ((x, y), want) in [(AUV0[0], 51.300), (AUV1[7], 56.258)] {
        let d = bathy.depth_at(x, y);
        assert!((d - want).abs() < 0.05, "depth at ({x}, {y}): {d} m, expected {want} m");
    }
    // A resolved scenario written out (a run's manifest) reads back the same, without its files.
    let text = toml::to_string(&sc).unwrap();
    let again = Scenario::parse(&text, Path::new("/nonexistent/manifest.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, sc);
}

/// A scratch directory with the library's site files and `files` written into it.
fn scratch(tag: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coopnav-site-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("site")).unwrap();
    for f in ["survey.bhv", "casco-elevation.asc"] {
        std::fs::copy(library("site").join(f), dir.join("site").join(f)).unwrap();
    }
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

fn refused(tag: &str, edit: impl Fn(&str) -> String, extra: &[(&str, &str)]) -> String {
    let text = edit(&std::fs::read_to_string(library("geographic-survey.toml")).unwrap());
    let mut files = vec![("m.toml", text.as_str())];
    files.extend_from_slice(extra);
    let dir = scratch(tag, &files);
    let e = Scenario::load(&dir.join("m.toml")).map(|_| ()).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    e
}

#[test]
fn bad_site_files_are_refused_by_name() {
    let bad_bhv = "Behavior = BHV_Waypoint\n{\n  points = format=lawnmower, x=0, y=0, width=100, lane_width=10\n}\n";
    let e = refused("bhv", |t| t.replace("site/survey.bhv", "bad.bhv"), &[("bad.bhv", bad_bhv)]);
    assert!(
        e.contains("fleet.survey.files[0]") && e.contains("bad.bhv: line 3: points: lawnmower needs 'height'"),
        "{e}"
    );
    let e = refused("missing", |t| t.replace("site/survey.bhv", "absent.bhv"), &[]);
    assert!(e.contains("fleet.survey.files[0]") && e.contains("absent.bhv"), "{e}");
    let bad_asc = "ncols 3\nnrows 2\nxllcorner -70.2\ncellsize 0.001\n1 2 3\n4 5 6\n";
    let e = refused("asc", |t| t.replace("site/casco-elevation.asc", "bad.asc"), &[("bad.asc", bad_asc)]);
    assert!(e.contains("site.bathymetry.file") && e.contains("bad.asc: missing header 'yllcorner'"), "{e}");
    // Elevations read as depths are all negative: refused with the line.
    let e = refused("depth", |t| t.replace("values = \"elevation\"", "values = \"depth\""), &[]);
    assert!(e.contains("casco-elevation.asc: line 7") && e.contains("not > 0 m"), "{e}");
    let e = refused("origin", |t| t.replace("origin = { lat_deg = 43.65, lon_deg = -70.20 }", ""), &[]);
    assert!(e.contains("site.origin"), "{e}");
    let e = refused("count", |t| t.replace("[fleet]\n", "[fleet]\nn_auvs = 3\n"), &[]);
    assert!(e.contains("fleet.n_auvs = 3") && e.contains("one survey AUV per waypoint behaviour"), "{e}");
    let e = refused("speed", |t| t.replace("[fleet]\n", "[fleet]\nspeed = 2.0\n"), &[]);
    assert!(e.contains("fleet.speed = 2") && e.contains("1.5 m/s"), "{e}");
    let e =
        refused("cna", |t| t.replace("position = { lat_deg = 43.6555", "x = 1.0\nposition = { lat_deg = 43.6555"), &[]);
    assert!(e.contains("cna.position") && e.contains("not both"), "{e}");
    // The survey must lie on the grid: an AUV 10 km west of it is refused naming the grid.
    let e = refused("off-grid", |t| t.replace("lon_deg = -70.21 }", "lon_deg = -70.35 }"), &[]);
    assert!(e.contains("site.bathymetry (survey AUV 0)") && e.contains("site/casco-elevation.asc"), "{e}");
}

#[test]
fn a_waypoint_csv_in_lat_lon_and_a_depth_csv_grid_load() {
    // Depth CSV in lat/lon, 3 × 3 nodes 0.01° apart: depth 30 m + 1000·(φ − 43.64) m.
    let mut grid = String::from("lat,lon,depth\n");
    for j in 0..3 {
        for i in 0..3 {
            let (lat, lon) = (43.64 + 0.01 * j as f64, -70.21 + 0.01 * i as f64);
            grid.push_str(&format!("{lat},{lon},{}\n", 30.0 + 1000.0 * (lat - 43.64)));
        }
    }
    let wps = "name,lat,lon\nstart,43.652,-70.205\nend,43.657,-70.195\n";
    let text = std::fs::read_to_string(library("geographic-survey.toml"))
        .unwrap()
        .replace(
            "{ file = \"site/casco-elevation.asc\", coords = \"lat_lon\", values = \"elevation\" }",
            "{ file = \"grid.csv\" }",
        )
        .replace(
            "{ files = [\"site/survey.bhv\"], moos_origin = { lat_deg = 43.655, lon_deg = -70.21 } }",
            "{ files = [\"wps.csv\"] }\nspeed = 1.5",
        );
    let dir = scratch("csv", &[("m.toml", &text), ("grid.csv", &grid), ("wps.csv", wps)]);
    let sc = Scenario::load(&dir.join("m.toml")).unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(sc.fleet.n_auvs, 1);
    // By hand (module doc): (43.652, −70.205) → (−403.38, 222.21) m; (43.657, −70.195) → (403.38, 777.74) m.
    let got = sc.lawnmower(0).waypoints();
    for (g, w) in got.iter().zip([(-403.38, 222.21), (403.38, 777.74)]) {
        assert!((g.0 - w.0).abs() < 0.25 && (g.1 - w.1).abs() < 0.25, "{got:?}");
    }
    // Depth at the first waypoint: 30 + 1000 · 0.012 = 42 m.
    let d = sc.bathymetry().depth_at(got[0].0, got[0].1);
    assert!((d - 42.0).abs() < 0.05, "{d}");
}

#[test]
fn fleets_beyond_eight_load_where_the_schedule_fits() {
    let twelve = coopnav_sim::scenario::EXAMPLE.replace("n_auvs = 3", "n_auvs = 12");
    let e = Scenario::parse(&twelve, Path::new("s.toml")).unwrap_err().to_string();
    assert!(e.contains("comms.schedule"), "{e}");
    // τ = 64 s holds 13 slots of 4.9 s; the CNA's turn per τ must stay under 180°.
    let fits =
        twelve.replace("tau = 30.0", "tau = 64.0").replace("max_turn_rate_deg_s = 4.0", "max_turn_rate_deg_s = 2.0");
    let sc = Scenario::parse(&fits, Path::new("s.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.fleet.n_auvs, 12);
    let e = Scenario::parse(&fits.replace("n_auvs = 12", "n_auvs = 32"), Path::new("s.toml")).unwrap_err().to_string();
    assert!(e.contains("fleet.n_auvs = 32") && e.contains("1..=31"), "{e}");
}
