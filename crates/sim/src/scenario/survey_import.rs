//! Survey missions as a field team has them: the waypoint behaviours of a MOOS-IvP `.bhv` file
//! (one survey AUV per `BHV_Waypoint` block) or a waypoint CSV (one survey AUV per file), read
//! into waypoint lists. A `.bhv` gives MOOS local metres (x east, y north of the `.moos` file's
//! `LatOrigin`/`LongOrigin`); a CSV gives `x,y` metres or `lat,lon` degrees. Turning them into the
//! scenario's own frame is the caller's ([`super::site`]).
//!
//! Of a `BHV_Waypoint` block this reads `points` or `polygon` (a vertex list `x,y:x,y:…`, the
//! same inside `pts={…}`, or `format=lawnmower, …`) and `speed`; every other key is the helm's
//! and is ignored. A lawnmower is expanded as pHelmIvP's pattern block does (MOOS-IvP
//! `XYFormatUtilsSegl.cpp`, `XYPatternBlock.cpp`; docs/models.md#survey-import): centre `x, y`,
//! `width` across and `height` along the lanes, `lane_width` (or `swath`) apart, `rows` `ew`
//! (the default: lanes run east-west) or `ns`, rotated by `degs` (compass, clockwise), entered at
//! the lane end nearest `startx, starty` (default 0, 0).

use std::path::Path;
use thiserror::Error;

/// A file that cannot be imported, with the line and key at fault.
#[derive(Debug, Error, PartialEq)]
pub enum ImportError {
    #[error("{file}: line {line}: {key}: {message}")]
    Key { file: String, line: usize, key: String, message: String },
    #[error("{file}: line {line}: {message}")]
    Line { file: String, line: usize, message: String },
    #[error("{file}: {message}")]
    File { file: String, message: String },
}

/// Which coordinates an imported path's points are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coords {
    /// Metres east and north of the file's own origin (MOOS local, or a CSV's `x,y`).
    Local,
    /// (latitude, longitude) degrees.
    LatLon,
}

/// One survey AUV's imported path.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedPath {
    /// In [`Coords`] order: (x, y) or (lat, lon).
    pub points: Vec<(f64, f64)>,
    pub coords: Coords,
    /// Speed the behaviour names, m/s.
    pub speed: Option<f64>,
    /// `file:line` where the path is defined.
    pub source: String,
}

/// Reads a `.bhv` (by extension) or a waypoint CSV from its text.
pub fn import(text: &str, path: &Path) -> Result<Vec<ImportedPath>, ImportError> {
    let file = path.display().to_string();
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("bhv")) {
        parse_bhv(text, &file)
    } else {
        parse_csv(text, &file).map(|p| vec![p])
    }
}

/// Every `BHV_Waypoint` block of a `.bhv` file, in order.
pub fn parse_bhv(text: &str, file: &str) -> Result<Vec<ImportedPath>, ImportError> {
    let line_err = |line: usize, message: String| ImportError::Line { file: file.into(), line, message };
    let mut out = Vec::new();
    // (behaviour kind, line it starts on, inside braces, its key = value lines)
    let mut kind: Option<(String, usize)> = None;
    let mut open = false;
    let mut keys: Vec<(usize, String, String)> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let l = raw.split("//").next().unwrap_or("").trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        if l.contains("$(") {
            return Err(line_err(line, format!("'{l}' holds an nsplug macro: expand the file with nsplug first")));
        }
        if !open {
            if l == "{" {
                if kind.is_none() {
                    return Err(line_err(line, "'{' without a 'Behavior = …' line before it".into()));
                }
                open = true;
                keys.clear();
            } else if let Some((k, v)) = l.split_once('=') {
                if k.trim().eq_ignore_ascii_case("behavior") {
                    kind = Some((v.trim().to_string(), line));
                }
                // `initialize`, `set`, `modes`: the helm's, not the survey's.
            }
            continue;
        }
        if l == "}" {
            open = false;
            let (name, start) = kind.take().expect("a block opens after its Behavior line");
            if name.eq_ignore_ascii_case("BHV_Waypoint") {
                out.push(waypoint_block(&keys, file, start)?);
            }
            continue;
        }
        let Some((k, v)) = l.split_once('=') else {
            return Err(line_err(line, format!("'{l}' is not 'key = value' (or a closing '}}')")));
        };
        keys.push((line, k.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    if open {
        let start = kind.map_or(0, |(_, l)| l);
        return Err(line_err(start, "behaviour block opened here is never closed with '}'".into()));
    }
    if out.is_empty() {
        return Err(ImportError::File { file: file.into(), message: "no BHV_Waypoint behaviour".into() });
    }
    Ok(out)
}

fn waypoint_block(keys: &[(usize, String, String)], file: &str, start: usize) -> Result<ImportedPath, ImportError> {
    let key_err = |line: usize, key: &str, message: String| ImportError::Key {
        file: file.into(),
        line,
        key: key.into(),
        message,
    };
    let mut points = None;
    let mut speed = None;
    for (line, key, value) in keys {
        match key.as_str() {
            "points" | "polygon" => {
                if points.is_some() {
                    return Err(key_err(*line, key, "a second point list in one behaviour".into()));
                }
                points = Some(seglist(value).map_err(|m| key_err(*line, key, m))?);
            }
            "speed" => {
                let v: f64 = value.parse().map_err(|_| key_err(*line, key, format!("'{value}' is not a number")))?;
                if !(v.is_finite() && v > 0.0) {
                    return Err(key_err(*line, key, format!("{v} m/s: must be > 0")));
                }
                speed = Some(v);
            }
            _ => {}
        }
    }
    let Some(points) = points else {
        return Err(ImportError::Line {
            file: file.into(),
            line: start,
            message: "BHV_Waypoint without 'points' or 'polygon'".into(),
        });
    };
    Ok(ImportedPath { points, coords: Coords::Local, speed, source: format!("{file}:{start}") })
}

/// A MOOS-IvP point list: `format=lawnmower, …`, `pts={x,y:…}, label=…`, or `x,y:x,y:…`.
fn seglist(value: &str) -> Result<Vec<(f64, f64)>, String> {
    let squeezed: String = value.chars().filter(|c| !c.is_whitespace()).collect::<String>().to_ascii_lowercase();
    if squeezed.contains("format=lawnmower") || squeezed.starts_with("lawnmower:") {
        return lawnmower(value.trim().trim_start_matches("lawnmower:"));
    }
    if squeezed.contains("format=") {
        return Err("only the lawnmower format and vertex lists are read".into());
    }
    let list = match value.find("pts=") {
        Some(i) => {
            let rest = value[i + 4..].trim_start();
            let rest = rest.strip_prefix('{').ok_or("pts= must be followed by '{'")?;
            rest.split('}').next().unwrap_or("").to_string()
        }
        None => value.to_string(),
    };
    let mut pts = Vec::new();
    for vertex in list.split(':').map(str::trim).filter(|v| !v.is_empty()) {
        let f: Vec<&str> = vertex.split(',').map(str::trim).collect();
        // `label,name` and similar pairs inside an abbreviated list are the viewer's.
        if f.len() == 2 && f[0].starts_with(|c: char| c.is_ascii_alphabetic()) {
            continue;
        }
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
        match (f.first().and_then(|s| num(s)), f.get(1).and_then(|s| num(s))) {
            (Some(x), Some(y)) => pts.push((x, y)),
            _ => return Err(format!("vertex '{vertex}' is not x,y")),
        }
    }
    if pts.is_empty() {
        return Err("no vertices".into());
    }
    Ok(pts)
}

/// The largest lane count a lawnmower may ask for (width / lane_width), so that a typo is an error,
/// not a million-lane survey.
pub const MAX_LANES: f64 = 10_000.0;

/// `format=lawnmower` expanded as pHelmIvP does (module doc).
fn lawnmower(spec: &str) -> Result<Vec<(f64, f64)>, String> {
    let mut v = std::collections::HashMap::new();
    let mut rows = "ew".to_string();
    for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let Some((k, val)) = part.split_once('=') else { return Err(format!("'{part}' is not key=value")) };
        let (k, val) = (k.trim().to_ascii_lowercase(), val.trim());
        match k.as_str() {
            "x" | "y" | "width" | "height" | "lane_width" | "swath" | "degs" | "startx" | "starty" => {
                let num = val.parse::<f64>().ok().filter(|n| n.is_finite());
                v.insert(
                    if k == "swath" { "lane_width".to_string() } else { k.clone() },
                    num.ok_or(format!("{k}: '{val}' is not a number"))?,
                );
            }
            "rows" => rows = val.to_ascii_lowercase(),
            _ => {}
        }
    }
    let need = |k: &str| v.get(k).copied().ok_or(format!("lawnmower needs '{k}'"));
    let (x, y, mut width, mut height, lane) =
        (need("x")?, need("y")?, need("width")?, need("height")?, need("lane_width")?);
    for (k, val) in [("width", width), ("height", height), ("lane_width", lane)] {
        if val <= 0.0 {
            return Err(format!("lawnmower {k} = {val}: must be > 0"));
        }
    }
    let mut degs = v.get("degs").copied().unwrap_or(0.0);
    let start = (v.get("startx").copied().unwrap_or(0.0), v.get("starty").copied().unwrap_or(0.0));
    let rows = match rows.as_str() {
        "ns" | "north-south" => "ns",
        // pHelmIvP reads anything else as east-west.
        _ => "ew",
    };
    if rows == "ew" {
        std::mem::swap(&mut width, &mut height);
        degs += 90.0;
    }
    // The pattern block keeps its angle at 0 unless given one of at least 1 degree.
    let angle = if degs >= 1.0 { degs } else { 0.0 };
    if !(width / lane <= MAX_LANES) {
        return Err(format!("lawnmower width / lane_width = {:.0} lanes (at most {MAX_LANES})", width / lane));
    }
    let lanes = (width / lane + 1.0 + 0.99999).trunc() as usize;
    // Compass projection: `dist` m towards compass bearing `deg` from `p`.
    let project = |deg: f64, dist: f64, p: (f64, f64)| {
        let (s, c) = deg.to_radians().sin_cos();
        (p.0 + s * dist, p.1 + c * dist)
    };
    let segments: Vec<[(f64, f64); 2]> = (0..lanes)
        .map(|i| {
            let off = width / 2.0 - i as f64 * lane;
            let mid = if off < 0.0 { project(angle + 90.0, -off, (x, y)) } else { project(angle - 90.0, off, (x, y)) };
            [project(angle, height / 2.0, mid), project(angle - 180.0, height / 2.0, mid)]
        })
        .collect();
    let d = |p: (f64, f64)| (p.0 - start.0).hypot(p.1 - start.1);
    let ends = [segments[0][0], segments[0][1], segments[lanes - 1][0], segments[lanes - 1][1]];
    let mut best = 0;
    for (i, e) in ends.iter().enumerate().skip(1) {
        if d(*e) < d(ends[best]) {
            best = i;
        }
    }
    let mut segments = segments;
    if best >= 2 {
        segments.reverse();
    }
    let mut first_end_zero = best % 2 == 0;
    let snap = |v: f64| (v / 1e-5).round() * 1e-5;
    let mut pts = Vec::with_capacity(2 * lanes);
    for s in &segments {
        let (a, b) = if first_end_zero { (s[0], s[1]) } else { (s[1], s[0]) };
        pts.extend([(snap(a.0), snap(a.1)), (snap(b.0), snap(b.1))]);
        first_end_zero = !first_end_zero;
    }
    Ok(pts)
}

/// A waypoint CSV: a header naming `x,y` or `lat,lon` (also `latitude`, `longitude`, `lon` or
/// `long`) columns, in any order among others, then one waypoint per row.
pub fn parse_csv(text: &str, file: &str) -> Result<ImportedPath, ImportError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim().starts_with('#'));
    let Some((hn, header)) = lines.next() else {
        return Err(ImportError::File { file: file.into(), message: "empty: expected a header x,y or lat,lon".into() });
    };
    let names: Vec<String> = header.split(',').map(|h| h.trim().to_ascii_lowercase()).collect();
    let col = |wanted: &[&str]| names.iter().position(|n| wanted.contains(&n.as_str()));
    let (coords, a, b) = match (col(&["x"]), col(&["y"]), col(&["lat", "latitude"]), col(&["lon", "long", "longitude"]))
    {
        (Some(x), Some(y), None, None) => (Coords::Local, x, y),
        (None, None, Some(lat), Some(lon)) => (Coords::LatLon, lat, lon),
        _ => {
            return Err(ImportError::Line {
                file: file.into(),
                line: hn + 1,
                message: format!("header '{}' must name the columns x,y or lat,lon (one pair)", header.trim()),
            })
        }
    };
    let mut points = Vec::new();
    for (n, l) in lines {
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        let get = |i: usize| -> Result<f64, ImportError> {
            let s = f.get(i).copied().unwrap_or("");
            s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| ImportError::Key {
                file: file.into(),
                line: n + 1,
                key: names[i].clone(),
                message: format!("'{s}' is not a number"),
            })
        };
        points.push((get(a)?, get(b)?));
    }
    if points.is_empty() {
        return Err(ImportError::File { file: file.into(), message: "no waypoints after the header".into() });
    }
    Ok(ImportedPath { points, coords, speed: None, source: file.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6
    }

    #[test]
    fn an_east_west_lawnmower_is_entered_at_the_corner_nearest_its_start() {
        // rows = ew: lanes run east-west, 200 m long (width), stepping 50 m across the 100 m
        // height: 100 / 50 + 1 = 3 lanes at y = 50, 0, -50 about the centre (0, 0). Nearest
        // lane end to (-100, 60) is (-100, 50): the northernmost lane, flown west to east.
        let pts = lawnmower("x=0, y=0, width=200, height=100, lane_width=50, rows=ew, startx=-100, starty=60").unwrap();
        let want = [(-100.0, 50.0), (100.0, 50.0), (100.0, 0.0), (-100.0, 0.0), (-100.0, -50.0), (100.0, -50.0)];
        assert_eq!(pts.len(), want.len(), "{pts:?}");
        for (p, w) in pts.iter().zip(want) {
            assert!(close(*p, w), "{pts:?}");
        }
    }

    #[test]
    fn a_north_south_lawnmower_and_a_rotation() {
        // rows = ns, degs = 0: lanes run north-south, 80 m (height) long, across 40 m of width at
        // 20 m: x = -20, 0, 20 about (10, 100); start defaults to (0, 0), nearest the south end
        // of the western lane (-10, 60).
        let pts = lawnmower("format=lawnmower, x=10, y=100, width=40, height=80, lane_width=20, rows=ns").unwrap();
        let want = [(-10.0, 60.0), (-10.0, 140.0), (10.0, 140.0), (10.0, 60.0), (30.0, 60.0), (30.0, 140.0)];
        for (p, w) in pts.iter().zip(want) {
            assert!(close(*p, w), "{pts:?}");
        }
        // degs = 90 turns the ns lanes east-west: same as rows = ew with width and height swapped.
        let turned = lawnmower("x=0, y=0, width=40, height=80, lane_width=20, rows=ns, degs=90").unwrap();
        let ew = lawnmower("x=0, y=0, width=80, height=40, lane_width=20, rows=ew").unwrap();
        assert_eq!(turned.len(), ew.len());
        for (a, b) in turned.iter().zip(&ew) {
            assert!(close(*a, *b), "{turned:?} vs {ew:?}");
        }
    }

    #[test]
    fn a_bhv_gives_one_path_per_waypoint_behaviour() {
        let bhv = "initialize DEPLOY = true\n\
                   Behavior = BHV_ConstantDepth\n{\n  depth = 20\n}\n\
                   Behavior = BHV_Waypoint\n{\n  name = a // comment\n  speed = 1.5\n  points = 0,0:100,0:100,50\n}\n\
                   Behavior = BHV_Waypoint\n{\n  polygon = pts={5,5:6,6}, label=b\n}\n";
        let p = parse_bhv(bhv, "m.bhv").unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].points, vec![(0.0, 0.0), (100.0, 0.0), (100.0, 50.0)]);
        assert_eq!((p[0].speed, p[0].source.as_str()), (Some(1.5), "m.bhv:6"));
        assert_eq!(p[1].points, vec![(5.0, 5.0), (6.0, 6.0)]);
    }

    #[test]
    fn bad_bhv_files_are_refused_naming_file_line_and_key() {
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  points = 0,0:abc\n}\n", "s.bhv").unwrap_err();
        assert_eq!(e.to_string(), "s.bhv: line 3: points: vertex 'abc' is not x,y");
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  points = format=lawnmower, x=0, y=0, width=10\n}\n", "s.bhv")
            .unwrap_err();
        assert!(e.to_string().starts_with("s.bhv: line 3: points: lawnmower needs 'height'"), "{e}");
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  speed = -1\n  points = 0,0\n}\n", "s.bhv").unwrap_err();
        assert!(e.to_string().contains("line 3: speed"), "{e}");
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  name = x\n}\n", "s.bhv").unwrap_err();
        assert_eq!(e.to_string(), "s.bhv: line 1: BHV_Waypoint without 'points' or 'polygon'");
        let e = parse_bhv("Behavior = BHV_Loiter\n{\n  name = x\n}\n", "s.bhv").unwrap_err();
        assert_eq!(e.to_string(), "s.bhv: no BHV_Waypoint behaviour");
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  points = $(PTS)\n}\n", "s.bhv").unwrap_err();
        assert!(e.to_string().contains("line 3") && e.to_string().contains("nsplug"), "{e}");
        let e = parse_bhv("Behavior = BHV_Waypoint\n{\n  points = 0,0\n", "s.bhv").unwrap_err();
        assert!(e.to_string().contains("line 1") && e.to_string().contains("never closed"), "{e}");
    }

    #[test]
    fn a_csv_names_its_columns() {
        let p = parse_csv("name,lat,lon\na,43.5,-70.25\nb,43.51,-70.2\n", "w.csv").unwrap();
        assert_eq!((p.coords, p.points.clone()), (Coords::LatLon, vec![(43.5, -70.25), (43.51, -70.2)]));
        let p = parse_csv("y,x\n1,2\n", "w.csv").unwrap();
        assert_eq!((p.coords, p.points), (Coords::Local, vec![(2.0, 1.0)]));
        let e = parse_csv("a,b\n1,2\n", "w.csv").unwrap_err();
        assert!(e.to_string().starts_with("w.csv: line 1: header 'a,b'"), "{e}");
        let e = parse_csv("x,y\n1,2\n3,north\n", "w.csv").unwrap_err();
        assert_eq!(e.to_string(), "w.csv: line 3: y: 'north' is not a number");
    }
}
