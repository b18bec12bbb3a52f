//! A scenario's place on Earth (`[site]`): a geodetic origin, positions in latitude/longitude,
//! site bathymetry from a file, and survey missions imported from MOOS-IvP `.bhv` files or
//! waypoint CSVs.
//!
//! All of it is resolved on reading, before the typed scenario is built: with `site.origin`
//! given, any position written `{ lat_deg = …, lon_deg = … }` (a pair such as `fleet.origin`, or
//! `position = { … }` in place of a table's `x`, `y`) becomes `[east, north]` metres on the local
//! tangent plane at the origin (`coopnav_core::geodesy::LocalFrame`; accuracy in
//! docs/models.md#site-frame); `site.bathymetry = { file = … }` is read and kept as the grid it
//! gives, in local metres; and `fleet.survey = { files = [ … ] }` becomes `fleet.paths`, one per
//! survey AUV. The engine then sees metres only, and a resolved scenario written out (a run's
//! manifest) reads back the same without its files.

use super::file::ScenarioError;
use super::survey_import::{self, Coords, ImportedPath};
use coopnav_core::geodesy::{Geodetic, LatLon, LocalFrame};
use coopnav_core::limits::{read_text, MAX_INPUT_FILE_BYTES, MAX_TABLE_FILE_BYTES};
use coopnav_core::Bathymetry;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use toml::Value;

/// `[site]`: where the scenario's local frame sits, and its seafloor.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Site {
    /// Geodetic origin of the local x east, y north plane (height above the ellipsoid optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<Geodetic>,
    /// Site bathymetry, read from `file` (module doc).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bathymetry: Option<SiteBathymetry>,
}

impl Site {
    pub fn is_empty(&self) -> bool {
        *self == Site::default()
    }

    /// The local tangent plane at the origin, if one is given.
    pub fn frame(&self) -> Option<LocalFrame> {
        self.origin.map(LocalFrame::new)
    }
}

/// A site grid as read: the file it came from, and its depths in local metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SiteBathymetry {
    pub source: String,
    pub grid: Bathymetry,
}

/// Survey AUV `k`'s own waypoints (`[[fleet.paths]]`), in local metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    pub waypoints: Vec<(f64, f64)>,
    /// Where they were imported from (`file:line`), if imported.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
}

/// `text` as a TOML tree with its site resolved, or None when it uses none of this module's
/// forms (or is not TOML: the caller's parser then reports it with its line).
pub fn resolved(text: &str, file: &Path, lawnmower_keys: &Value) -> Result<Option<Value>, ScenarioError> {
    let Ok(mut root) = text.parse::<toml::Table>().map(Value::Table) else { return Ok(None) };
    let changed = resolve(&mut root, file, lawnmower_keys)?;
    Ok(changed.then_some(root))
}

/// Resolves the tree in place (module doc); true if it used any of this module's forms.
/// `lawnmower_keys`: the fleet keys a file with `paths` may leave out, with the values they take.
pub fn resolve(root: &mut Value, file: &Path, lawnmower_keys: &Value) -> Result<bool, ScenarioError> {
    let Some(table) = root.as_table_mut() else { return Ok(false) };
    let mut changed = table.contains_key("site");
    let origin = match table.get("site").and_then(|s| s.get("origin")) {
        Some(v) => Some(v.clone().try_into::<Geodetic>().map_err(|e| {
            ScenarioError::invalid(file, "site.origin", e.to_string(), "{ lat_deg = …, lon_deg = …, height_m = … }")
        })?),
        None => None,
    };
    let frame = origin.map(LocalFrame::new);
    let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    if let Some(fleet) = table.get_mut("fleet").and_then(Value::as_table_mut) {
        if let Some(spec) = fleet.remove("survey") {
            import_survey(fleet, spec, &dir, frame.as_ref(), file)?;
        }
        if fleet.contains_key("paths") {
            changed = true;
            if let Some(keys) = lawnmower_keys.as_table() {
                for (k, v) in keys {
                    fleet.entry(k.clone()).or_insert_with(|| v.clone());
                }
            }
        }
    }
    for (key, v) in table.iter_mut().filter(|(k, _)| k.as_str() != "site") {
        changed |= to_metres(v, key, frame.as_ref(), file)?;
    }
    if let Some(b) = table.get_mut("site").and_then(|s| s.get_mut("bathymetry")) {
        if b.get("file").is_some() {
            let grid = load_bathymetry(b, &dir, frame.as_ref(), file)?;
            *b = Value::try_from(grid)
                .map_err(|e| ScenarioError::invalid(file, "site.bathymetry", e.to_string(), "a grid TOML can hold"))?;
        }
    }
    Ok(changed)
}

/// `{ lat_deg, lon_deg }` exactly.
fn as_latlon(v: &Value) -> Option<(f64, f64)> {
    let t = v.as_table()?;
    let num = |k: &str| t.get(k).and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)));
    (t.len() == 2).then_some(())?;
    Some((num("lat_deg")?, num("lon_deg")?))
}

fn plane(
    (lat, lon): (f64, f64),
    field: &str,
    frame: Option<&LocalFrame>,
    file: &Path,
) -> Result<(f64, f64), ScenarioError> {
    let found = || format!("{{ lat_deg = {lat}, lon_deg = {lon} }}");
    let Some(frame) = frame else {
        return Err(ScenarioError::invalid(
            file,
            field,
            found(),
            "metres, or a site.origin to place latitudes and longitudes",
        ));
    };
    let ll = LatLon::new(lat, lon).map_err(|e| ScenarioError::invalid(file, field, found(), e.to_string()))?;
    Ok(frame.to_plane(ll))
}

/// Rewrites every lat/lon position under `v` (named `path`) as metres; true if any was found.
fn to_metres(v: &mut Value, path: &str, frame: Option<&LocalFrame>, file: &Path) -> Result<bool, ScenarioError> {
    if let Some(ll) = as_latlon(v) {
        let (x, y) = plane(ll, path, frame, file)?;
        *v = Value::Array(vec![Value::Float(x), Value::Float(y)]);
        return Ok(true);
    }
    let mut changed = false;
    match v {
        Value::Table(t) => {
            if let Some(ll) = t.get("position").and_then(as_latlon) {
                let field = format!("{path}.position");
                if t.contains_key("x") || t.contains_key("y") {
                    return Err(ScenarioError::invalid(file, field, "given with x or y", "position or x, y, not both"));
                }
                let (x, y) = plane(ll, &field, frame, file)?;
                t.remove("position");
                t.insert("x".into(), Value::Float(x));
                t.insert("y".into(), Value::Float(y));
                changed = true;
            }
            for (k, child) in t.iter_mut() {
                changed |= to_metres(child, &format!("{path}.{k}"), frame, file)?;
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter_mut().enumerate() {
                changed |= to_metres(child, &format!("{path}[{i}]"), frame, file)?;
            }
        }
        _ => {}
    }
    Ok(changed)
}

fn string_key(
    t: &Value,
    key: &str,
    field: &str,
    allowed: &[&str],
    file: &Path,
) -> Result<Option<String>, ScenarioError> {
    let Some(v) = t.get(key) else { return Ok(None) };
    match v.as_str() {
        Some(s) if allowed.is_empty() || allowed.contains(&s) => Ok(Some(s.to_string())),
        _ => {
            let want = if allowed.is_empty() { "a string".to_string() } else { format!("one of {allowed:?}") };
            Err(ScenarioError::invalid(file, field, v.to_string(), want))
        }
    }
}

/// `fleet.survey = { files = [ … ], moos_origin = { lat_deg, lon_deg } }` → `fleet.paths`.
fn import_survey(
    fleet: &mut toml::Table,
    spec: Value,
    dir: &Path,
    frame: Option<&LocalFrame>,
    file: &Path,
) -> Result<(), ScenarioError> {
    let bad = |field: &str, value: String, allowed: &str| ScenarioError::invalid(file, field, value, allowed);
    let Some(t) = spec.as_table() else {
        return Err(bad("fleet.survey", spec.to_string(), "{ files = [\"survey.bhv\"], moos_origin = { … } }"));
    };
    if let Some(k) = t.keys().find(|k| !["files", "moos_origin"].contains(&k.as_str())) {
        return Err(bad(&format!("fleet.survey.{k}"), "an unknown key".into(), "files, moos_origin"));
    }
    let files: Vec<String> = match t.get("files").and_then(Value::as_array) {
        Some(a) if !a.is_empty() => a
            .iter()
            .map(|f| f.as_str().map(str::to_string))
            .collect::<Option<_>>()
            .ok_or_else(|| bad("fleet.survey.files", format!("{a:?}"), "file names"))?,
        _ => {
            return Err(bad("fleet.survey.files", "missing or empty".into(), "one or more .bhv or waypoint CSV files"))
        }
    };
    // The .bhv's MOOS local frame: LatOrigin/LongOrigin of its .moos file, if not the site's.
    let moos = match t.get("moos_origin") {
        Some(v) => {
            let g: Geodetic = v.clone().try_into().map_err(|e: toml::de::Error| {
                bad(
                    "fleet.survey.moos_origin",
                    e.to_string(),
                    "{ lat_deg = …, lon_deg = … } (the .moos LatOrigin, LongOrigin)",
                )
            })?;
            if frame.is_none() {
                return Err(bad(
                    "fleet.survey.moos_origin",
                    "given without site.origin".into(),
                    "a site.origin to place it",
                ));
            }
            Some(LocalFrame::new(g))
        }
        None => None,
    };
    let mut paths: Vec<ImportedPath> = Vec::new();
    for (i, name) in files.iter().enumerate() {
        let field = format!("fleet.survey.files[{i}]");
        let path = resolve_path(dir, name);
        let text = read_text(&path, "survey file (bytes)", MAX_INPUT_FILE_BYTES, false)
            .map_err(|e| bad(&field, e.to_string(), "a readable .bhv or waypoint CSV"))?;
        let found = survey_import::import(&text, &path).map_err(|e| {
            bad(&field, e.to_string(), "a MOOS-IvP .bhv with BHV_Waypoint behaviours, or a waypoint CSV")
        })?;
        paths.extend(found);
    }
    let mut out = Vec::new();
    for p in &paths {
        let mut wps = Vec::with_capacity(p.points.len());
        for &(a, b) in &p.points {
            let field = format!("fleet.survey ({})", p.source);
            let xy = match (p.coords, &moos) {
                (Coords::LatLon, _) => plane((a, b), &field, frame, file)?,
                (Coords::Local, None) => (a, b),
                (Coords::Local, Some(m)) => {
                    let ll =
                        m.from_plane(a, b).map_err(|e| bad(&field, e.to_string(), "points near the MOOS origin"))?;
                    plane((ll.lat_deg(), ll.lon_deg()), &field, frame, file)?
                }
            };
            wps.push(Value::Array(vec![Value::Float(xy.0), Value::Float(xy.1)]));
        }
        let mut entry = toml::Table::new();
        entry.insert("waypoints".into(), Value::Array(wps));
        entry.insert("source".into(), Value::String(p.source.clone()));
        out.push(Value::Table(entry));
    }
    match fleet.get("n_auvs").and_then(Value::as_integer) {
        None => {
            fleet.insert("n_auvs".into(), Value::Integer(out.len() as i64));
        }
        Some(n) if n as usize != out.len() => {
            return Err(bad(
                "fleet.n_auvs",
                n.to_string(),
                &format!(
                    "{} (one survey AUV per waypoint behaviour or CSV in fleet.survey), or leave it out",
                    out.len()
                ),
            ))
        }
        Some(_) => {}
    }
    let speeds: Vec<(f64, &str)> = paths.iter().filter_map(|p| p.speed.map(|s| (s, p.source.as_str()))).collect();
    if let Some(&(s, _)) = speeds.first() {
        if let Some((other, src)) = speeds.iter().find(|(v, _)| *v != s) {
            return Err(bad(
                &format!("fleet.survey ({src})"),
                format!("speed {other} m/s"),
                &format!("{s} m/s: the fleet flies one speed"),
            ));
        }
        match fleet.get("speed").and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))) {
            None => {
                fleet.insert("speed".into(), Value::Float(s));
            }
            Some(f) if f != s => {
                return Err(bad(
                    "fleet.speed",
                    f.to_string(),
                    &format!("{s} m/s, the speed the survey's behaviours give (or leave it out)"),
                ))
            }
            Some(_) => {}
        }
    }
    if fleet.contains_key("paths") {
        return Err(bad("fleet.paths", "given with fleet.survey".into(), "one of fleet.paths, fleet.survey"));
    }
    fleet.insert("paths".into(), Value::Array(out));
    Ok(())
}

fn resolve_path(dir: &Path, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    }
}

/// `site.bathymetry = { file, coords = "local" | "lat_lon", values = "depth" | "elevation" }`.
fn load_bathymetry(
    spec: &Value,
    dir: &Path,
    frame: Option<&LocalFrame>,
    file: &Path,
) -> Result<SiteBathymetry, ScenarioError> {
    let bad = |field: &str, value: String, allowed: &str| ScenarioError::invalid(file, field, value, allowed);
    let t = spec.as_table().expect("a table holds `file`");
    if let Some(k) = t.keys().find(|k| !["file", "coords", "values"].contains(&k.as_str())) {
        return Err(bad(&format!("site.bathymetry.{k}"), "an unknown key".into(), "file, coords, values"));
    }
    let name = string_key(spec, "file", "site.bathymetry.file", &[], file)?.expect("checked by the caller");
    let coords = string_key(spec, "coords", "site.bathymetry.coords", &["local", "lat_lon"], file)?;
    let elevation = string_key(spec, "values", "site.bathymetry.values", &["depth", "elevation"], file)?.as_deref()
        == Some("elevation");
    let path = resolve_path(dir, &name);
    let field = "site.bathymetry.file";
    let text = read_text(&path, "bathymetry file (bytes)", MAX_TABLE_FILE_BYTES, false)
        .map_err(|e| bad(field, e.to_string(), "a readable ESRI ASCII grid (.asc) or x,y,depth / lat,lon,depth CSV"))?;
    let shown = path.display().to_string();
    let asc = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("asc"));
    let (grid, lat_lon) = if asc {
        let text = if elevation { negate_asc(&text) } else { text };
        (Bathymetry::parse_ascii_grid(&text, &shown), coords.as_deref() == Some("lat_lon"))
    } else {
        let (text, header_lat_lon) = csv_as_xy_depth(&text, elevation);
        if coords.as_deref() == Some("local") && header_lat_lon {
            return Err(bad(
                "site.bathymetry.coords",
                "local".into(),
                "lat_lon: the CSV's header names lat,lon columns",
            ));
        }
        (Bathymetry::parse_csv(&text, &shown), header_lat_lon || coords.as_deref() == Some("lat_lon"))
    };
    let grid = grid.map_err(|e| bad(field, e.to_string(), "a complete grid of depths > 0 m"))?;
    let grid = if lat_lon {
        let Some(frame) = frame else {
            return Err(bad("site.bathymetry.coords", "lat_lon".into(), "local, or a site.origin to place the grid"));
        };
        to_local_grid(&grid, frame).map_err(|m| bad(field, m, "a grid in degrees around site.origin"))?
    } else {
        grid
    };
    Ok(SiteBathymetry { source: name, grid })
}

/// An ESRI grid of elevations (negative below the sea) as depths: every data value negated,
/// except the NODATA value, which the grid reader then refuses by line.
fn negate_asc(text: &str) -> String {
    let mut nodata: Option<String> = None;
    let mut out = String::with_capacity(text.len() + text.len() / 8);
    for l in text.lines() {
        let first = l.split_whitespace().next().unwrap_or("");
        if first.starts_with(|c: char| c.is_ascii_alphabetic()) {
            if first.eq_ignore_ascii_case("nodata_value") {
                nodata = l.split_whitespace().nth(1).map(str::to_string);
            }
            out.push_str(l);
        } else {
            let row: Vec<String> = l
                .split_whitespace()
                .map(|t| match t.parse::<f64>() {
                    Ok(_) if Some(t) == nodata.as_deref() => t.to_string(),
                    Ok(v) => (-v).to_string(),
                    Err(_) => t.to_string(),
                })
                .collect();
            out.push_str(&row.join(" "));
        }
        out.push('\n');
    }
    out
}

/// A bathymetry CSV rewritten as `x,y,depth` (line for line, so errors keep their line numbers):
/// a header naming `lat,lon,depth` (any order; `elevation` for a negated depth) becomes
/// (lon, lat, depth); true if it named lat/lon.
fn csv_as_xy_depth(text: &str, elevation: bool) -> (String, bool) {
    let mut cols = [0usize, 1, 2];
    let mut lat_lon = false;
    let mut negate = elevation;
    let mut out = String::with_capacity(text.len());
    for (n, l) in text.lines().enumerate() {
        let trimmed = l.trim();
        if n == 0 && trimmed.starts_with(|c: char| c.is_ascii_alphabetic()) {
            let names: Vec<String> = trimmed.split(',').map(|h| h.trim().to_ascii_lowercase()).collect();
            let at = |w: &[&str]| names.iter().position(|h| w.contains(&h.as_str()));
            if let (Some(lat), Some(lon)) = (at(&["lat", "latitude"]), at(&["lon", "long", "longitude"])) {
                lat_lon = true;
                cols[0] = lon;
                cols[1] = lat;
            } else if let (Some(x), Some(y)) = (at(&["x"]), at(&["y"])) {
                cols[0] = x;
                cols[1] = y;
            }
            if let Some(d) = at(&["depth"]) {
                cols[2] = d;
            } else if let Some(d) = at(&["elevation", "z"]) {
                cols[2] = d;
                negate = names[d] == "elevation" || elevation;
            }
            out.push_str("x,y,depth\n");
            continue;
        }
        let f: Vec<&str> = trimmed.split(',').map(str::trim).collect();
        if trimmed.is_empty() || trimmed.starts_with('#') || f.len() != 3 {
            out.push_str(l);
        } else {
            let d = match f[cols[2]].parse::<f64>() {
                Ok(v) if negate => (-v).to_string(),
                _ => f[cols[2]].to_string(),
            };
            out.push_str(&format!("{},{},{}", f[cols[0]], f[cols[1]], d));
        }
        out.push('\n');
    }
    (out, lat_lon)
}

/// A grid in degrees (x = longitude, y = latitude) resampled onto the local plane: as many nodes
/// as it has, evenly over the largest east/north rectangle inside its corners, each node's depth
/// interpolated at that node's latitude and longitude.
fn to_local_grid(deg: &Bathymetry, frame: &LocalFrame) -> Result<Bathymetry, String> {
    let ((lon0, lat0), (lon1, lat1)) = deg.bounds();
    let corner = |lat: f64, lon: f64| {
        LatLon::new(lat, lon).map(|ll| frame.to_plane(ll)).map_err(|e| format!("grid corner: {e}"))
    };
    let (sw, nw, se, ne) = (corner(lat0, lon0)?, corner(lat1, lon0)?, corner(lat0, lon1)?, corner(lat1, lon1)?);
    let (x0, x1) = (sw.0.max(nw.0), se.0.min(ne.0));
    let (y0, y1) = (sw.1.max(se.1), nw.1.min(ne.1));
    if !(x1 > x0 && y1 > y0) {
        return Err(format!("its corners ({lat0}, {lon0}) to ({lat1}, {lon1}) span no area"));
    }
    let (nx, ny) = deg.shape();
    let (dx, dy) = ((x1 - x0) / (nx - 1) as f64, (y1 - y0) / (ny - 1) as f64);
    let mut depth = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (x0 + i as f64 * dx, y0 + j as f64 * dy);
            let ll = frame.from_plane(x, y).map_err(|e| e.to_string())?;
            depth.push(deg.depth_at(ll.lon_deg(), ll.lat_deg()));
        }
    }
    Bathymetry::new(x0, y0, dx, dy, nx, ny, depth).map_err(|e| e.to_string())
}
