//! Bathymetry: water depth over the local (x east, y north) plane, on a regular grid with
//! bilinear interpolation (held at the edge value outside the grid).
//!
//! Sources: a synthetic shelf (the default, since the Nams thesis's Bedford Basin survey is not
//! available; docs/models.md#nams-environment), an ESRI ASCII raster (`.asc`), or a CSV of
//! `x,y,depth` rows covering a complete regular grid. Parse errors carry the line number.

use serde::{Deserialize, Serialize};
use std::path::Path;
use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
pub enum BathymetryError {
    #[error("{file}: line {line}: {message}")]
    Parse { file: String, line: usize, message: String },
    #[error("{file}: {message}")]
    Shape { file: String, message: String },
    #[error("{file}: cannot read: {message}")]
    Io { file: String, message: String },
    #[error("bathymetry grid: {0}")]
    Invalid(String),
}

/// Water depth (m, positive down) on a regular grid: node (i, j) sits at
/// (x0 + i·dx, y0 + j·dy), i < nx, j < ny; depths stored row by row (j major).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bathymetry {
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    nx: usize,
    ny: usize,
    depth: Vec<f64>,
}

/// Parameters of the synthetic shelf: depth grows linearly from `shallow` at x = `x_shallow` to
/// `deep` at x = `x_deep` (held beyond), uniform in y. Invented in place of the Bedford Basin
/// survey (Nams 2014, §4.2; 30–40 m deep, 80 m at most): a shelf from 20 m to 60 m
/// (docs/models.md#nams-environment).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Shelf {
    pub shallow: f64,
    pub deep: f64,
    pub x_shallow: f64,
    pub x_deep: f64,
    /// Grid extent: [x_min, x_max] × [y_min, y_max], node spacing `spacing` m.
    pub x_min: f64,
    pub x_max: f64,
    pub y_min: f64,
    pub y_max: f64,
    pub spacing: f64,
}

impl Default for Shelf {
    fn default() -> Self {
        Shelf {
            shallow: 20.0,
            deep: 60.0,
            x_shallow: -500.0,
            x_deep: 2500.0,
            x_min: -1000.0,
            x_max: 3000.0,
            y_min: -1000.0,
            y_max: 3000.0,
            spacing: 50.0,
        }
    }
}

impl Shelf {
    /// Its grid's nodes, computed in floating point before anything is allocated (an absurd
    /// spacing gives an absurd count, not an overflow).
    pub fn nodes(&self) -> f64 {
        let axis = |lo: f64, hi: f64| ((hi - lo) / self.spacing).ceil() + 1.0;
        axis(self.x_min, self.x_max) * axis(self.y_min, self.y_max)
    }
}

/// The most nodes a grid built from input may have whatever the work limits allow (800 MB of
/// depths): above it the input is refused, so a typo is an error message, never an abort.
pub const MAX_GRID_NODES: f64 = 1e8;

impl Bathymetry {
    /// Builds a grid, checking the shape and that every depth is finite and positive.
    pub fn new(
        x0: f64,
        y0: f64,
        dx: f64,
        dy: f64,
        nx: usize,
        ny: usize,
        depth: Vec<f64>,
    ) -> Result<Self, BathymetryError> {
        if nx < 2 || ny < 2 {
            return Err(BathymetryError::Invalid(format!("need at least 2 × 2 nodes, got {nx} × {ny}")));
        }
        if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite() && x0.is_finite() && y0.is_finite()) {
            return Err(BathymetryError::Invalid(format!("spacing must be finite and > 0 (dx = {dx}, dy = {dy})")));
        }
        if depth.len() != nx * ny {
            return Err(BathymetryError::Invalid(format!("{} depths for {nx} × {ny} nodes", depth.len())));
        }
        if let Some(i) = depth.iter().position(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(BathymetryError::Invalid(format!(
                "node {i}: depth {} (must be a finite number > 0 m)",
                depth[i]
            )));
        }
        Ok(Bathymetry { x0, y0, dx, dy, nx, ny, depth })
    }

    /// Re-checks a grid read by serde (as [`Bathymetry::new`] checks a built one).
    pub fn check(&self) -> Result<(), BathymetryError> {
        Bathymetry::new(self.x0, self.y0, self.dx, self.dy, self.nx, self.ny, self.depth.clone()).map(|_| ())
    }

    /// The synthetic shelf.
    pub fn shelf(s: &Shelf) -> Result<Self, BathymetryError> {
        if !(s.spacing > 0.0 && s.x_max > s.x_min && s.y_max > s.y_min && s.x_deep != s.x_shallow) {
            return Err(BathymetryError::Invalid(format!("shelf: bad extent or spacing {s:?}")));
        }
        if !(s.nodes() <= MAX_GRID_NODES) {
            return Err(BathymetryError::Invalid(format!(
                "shelf: spacing {} m over the extent gives {:.3e} nodes (at most {MAX_GRID_NODES:e})",
                s.spacing,
                s.nodes()
            )));
        }
        let nx = ((s.x_max - s.x_min) / s.spacing).ceil() as usize + 1;
        let ny = ((s.y_max - s.y_min) / s.spacing).ceil() as usize + 1;
        let mut depth = Vec::new();
        depth
            .try_reserve_exact(nx * ny)
            .map_err(|e| BathymetryError::Invalid(format!("shelf: {nx} × {ny} nodes: {e}")))?;
        for _ in 0..ny {
            for i in 0..nx {
                let x = s.x_min + i as f64 * s.spacing;
                let f = ((x - s.x_shallow) / (s.x_deep - s.x_shallow)).clamp(0.0, 1.0);
                depth.push(s.shallow + (s.deep - s.shallow) * f);
            }
        }
        Bathymetry::new(s.x_min, s.y_min, s.spacing, s.spacing, nx, ny, depth)
    }

    /// Loads `.asc` (ESRI ASCII raster) or anything else as CSV `x,y,depth`.
    pub fn load(path: &Path) -> Result<Self, BathymetryError> {
        let file = path.display().to_string();
        let text =
            crate::limits::read_text(path, "bathymetry file (bytes)", crate::limits::MAX_TABLE_FILE_BYTES, false)
                .map_err(|e| BathymetryError::Io { file: file.clone(), message: e.to_string() })?;
        if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("asc")) {
            Self::parse_ascii_grid(&text, &file)
        } else {
            Self::parse_csv(&text, &file)
        }
    }

    /// ESRI ASCII raster: header `ncols nrows xllcorner|xllcenter yllcorner|yllcenter cellsize
    /// [NODATA_value]`, then `nrows` rows of `ncols` depths, northernmost row first.
    pub fn parse_ascii_grid(text: &str, file: &str) -> Result<Self, BathymetryError> {
        let perr = |line: usize, message: String| BathymetryError::Parse { file: file.to_string(), line, message };
        let mut header = std::collections::HashMap::new();
        let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()).peekable();
        while let Some((n, l)) = lines.peek() {
            let mut it = l.split_whitespace();
            let key = it.next().unwrap_or("").to_ascii_lowercase();
            if key.starts_with(|c: char| c.is_ascii_alphabetic()) {
                let v: f64 = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or_else(|| perr(n + 1, format!("header '{key}' needs one number")))?;
                header.insert(key, (v, n + 1));
                lines.next();
            } else {
                break;
            }
        }
        let get = |k: &str| header.get(k).map(|(v, _)| *v);
        let need = |k: &str| {
            get(k).ok_or_else(|| BathymetryError::Shape {
                file: file.to_string(),
                message: format!("missing header '{k}'"),
            })
        };
        let count = |k: &str| -> Result<usize, BathymetryError> {
            let v = need(k)?;
            if v >= 2.0 && v.fract() == 0.0 {
                Ok(v as usize)
            } else {
                Err(perr(header[k].1, format!("'{k}' must be an integer ≥ 2, got {v}")))
            }
        };
        let (nx, ny, cell) = (count("ncols")?, count("nrows")?, need("cellsize")?);
        let half = |corner: &str, center: &str| -> Result<f64, BathymetryError> {
            match (get(corner), get(center)) {
                (Some(c), _) => Ok(c + cell / 2.0),
                (None, Some(c)) => Ok(c),
                _ => Err(BathymetryError::Shape {
                    file: file.to_string(),
                    message: format!("missing header '{corner}' or '{center}'"),
                }),
            }
        };
        let (x0, y0) = (half("xllcorner", "xllcenter")?, half("yllcorner", "yllcenter")?);
        let nodata = get("nodata_value");
        // Grown by the rows read, not reserved from the header: `nrows` may be absurd (1e308).
        let mut rows: Vec<Vec<f64>> = Vec::new();
        for (n, l) in lines {
            let row = l
                .split_whitespace()
                .map(|t| {
                    let v: f64 = t.parse().map_err(|_| perr(n + 1, format!("'{t}' is not a number")))?;
                    if Some(v) == nodata || !(v.is_finite() && v > 0.0) {
                        return Err(perr(
                            n + 1,
                            format!("depth {t} is missing or not > 0 m (every cell needs a depth)"),
                        ));
                    }
                    Ok(v)
                })
                .collect::<Result<Vec<_>, _>>()?;
            if row.len() != nx {
                return Err(perr(n + 1, format!("{} values, expected ncols = {nx}", row.len())));
            }
            rows.push(row);
        }
        if rows.len() != ny {
            return Err(BathymetryError::Shape {
                file: file.to_string(),
                message: format!("{} data rows, expected nrows = {ny}", rows.len()),
            });
        }
        let depth = rows.into_iter().rev().flatten().collect();
        Bathymetry::new(x0, y0, cell, cell, nx, ny, depth)
    }

    /// CSV `x,y,depth` (optional header line) covering every node of a regular grid once.
    pub fn parse_csv(text: &str, file: &str) -> Result<Self, BathymetryError> {
        let perr = |line: usize, message: String| BathymetryError::Parse { file: file.to_string(), line, message };
        let mut pts = Vec::new();
        for (n, l) in text.lines().enumerate() {
            let l = l.trim();
            if l.is_empty() || l.starts_with('#') || (n == 0 && l.starts_with(|c: char| c.is_ascii_alphabetic())) {
                continue;
            }
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            if f.len() != 3 {
                return Err(perr(n + 1, format!("expected 3 fields x,y,depth, got {}", f.len())));
            }
            let mut v = [0.0f64; 3];
            for (k, t) in f.iter().enumerate() {
                v[k] = t.parse().map_err(|_| perr(n + 1, format!("field {} '{t}' is not a number", k + 1)))?;
                if !v[k].is_finite() {
                    return Err(perr(n + 1, format!("field {} is not finite", k + 1)));
                }
            }
            if v[2] <= 0.0 {
                return Err(perr(n + 1, format!("depth {} must be > 0 m", v[2])));
            }
            pts.push((v, n + 1));
        }
        let axis = |k: usize| {
            let mut a: Vec<f64> = pts.iter().map(|(p, _)| p[k]).collect();
            a.sort_by(f64::total_cmp);
            a.dedup();
            a
        };
        let (xs, ys) = (axis(0), axis(1));
        let shape = |message: String| BathymetryError::Shape { file: file.to_string(), message };
        if xs.len() < 2 || ys.len() < 2 {
            return Err(shape(format!("need at least 2 distinct x and y values, got {} × {}", xs.len(), ys.len())));
        }
        let (dx, dy) = (xs[1] - xs[0], ys[1] - ys[0]);
        let regular = |a: &[f64], d: f64| {
            a.iter().enumerate().all(|(i, v)| (v - (a[0] + i as f64 * d)).abs() <= 1e-6 * d.max(1.0))
        };
        if !regular(&xs, dx) || !regular(&ys, dy) {
            return Err(shape("x and y values must be evenly spaced (a regular grid)".into()));
        }
        let (nx, ny) = (xs.len(), ys.len());
        // Each point is one node and duplicates are refused, so a grid with more nodes than
        // points misses some: refused before the nodes are allocated (a diagonal of n points
        // would ask for n² of them).
        if nx.checked_mul(ny).is_none_or(|nodes| nodes > pts.len()) {
            return Err(shape(format!(
                "{} points cannot fill the {nx} × {ny} grid their x and y values span (every grid node needs a depth)",
                pts.len()
            )));
        }
        let mut depth = vec![f64::NAN; nx * ny];
        for (p, line) in &pts {
            let i = ((p[0] - xs[0]) / dx).round() as usize;
            let j = ((p[1] - ys[0]) / dy).round() as usize;
            if !depth[j * nx + i].is_nan() {
                return Err(perr(*line, format!("duplicate node x = {}, y = {}", p[0], p[1])));
            }
            depth[j * nx + i] = p[2];
        }
        if let Some(k) = depth.iter().position(|d| d.is_nan()) {
            return Err(shape(format!(
                "missing node x = {}, y = {} (every grid node needs a depth)",
                xs[k % nx],
                ys[k / nx]
            )));
        }
        Bathymetry::new(xs[0], ys[0], dx, dy, nx, ny, depth)
    }

    /// Water depth at (x, y), bilinear, clamped to the grid edge outside it.
    pub fn depth_at(&self, x: f64, y: f64) -> f64 {
        let fx = ((x - self.x0) / self.dx).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((y - self.y0) / self.dy).clamp(0.0, (self.ny - 1) as f64);
        let (i, j) = ((fx as usize).min(self.nx - 2), (fy as usize).min(self.ny - 2));
        let (tx, ty) = (fx - i as f64, fy - j as f64);
        let d = |i: usize, j: usize| self.depth[j * self.nx + i];
        let lo = d(i, j) * (1.0 - tx) + d(i + 1, j) * tx;
        let hi = d(i, j + 1) * (1.0 - tx) + d(i + 1, j + 1) * tx;
        lo * (1.0 - ty) + hi * ty
    }

    /// The grid's nodes span [x_min, x_max] × [y_min, y_max]: `((x_min, y_min), (x_max, y_max))`.
    pub fn bounds(&self) -> ((f64, f64), (f64, f64)) {
        let far = |o: f64, d: f64, n: usize| o + d * (n - 1) as f64;
        ((self.x0, self.y0), (far(self.x0, self.dx, self.nx), far(self.y0, self.dy, self.ny)))
    }

    /// Nodes along x and along y.
    pub fn shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// Shallowest node of the grid.
    pub fn min_depth(&self) -> f64 {
        self.depth.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Deepest node of the grid.
    pub fn max_depth(&self) -> f64 {
        self.depth.iter().copied().fold(0.0, f64::max)
    }

    /// `n ≥ 2` equally spaced (range m, depth m) samples of the bottom from `a` to `b`.
    pub fn slice(&self, a: (f64, f64), b: (f64, f64), n: usize) -> Vec<(f64, f64)> {
        let n = n.max(2);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        (0..n)
            .map(|k| {
                let f = k as f64 / (n - 1) as f64;
                (f * len, self.depth_at(a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shelf_slopes_from_shallow_to_deep() {
        let b = Bathymetry::shelf(&Shelf::default()).unwrap();
        assert!((b.depth_at(-800.0, 0.0) - 20.0).abs() < 1e-9);
        assert!((b.depth_at(1000.0, 500.0) - 40.0).abs() < 1e-9);
        assert!((b.depth_at(9000.0, 9000.0) - 60.0).abs() < 1e-9);
        assert_eq!(b.max_depth(), 60.0);
    }

    #[test]
    fn bilinear_interpolation_is_exact_for_planes() {
        let depth: Vec<f64> =
            (0..3).flat_map(|j| (0..4).map(move |i| 10.0 + 2.0 * i as f64 + 3.0 * j as f64)).collect();
        let b = Bathymetry::new(0.0, 0.0, 10.0, 10.0, 4, 3, depth).unwrap();
        assert!((b.depth_at(15.0, 5.0) - (10.0 + 3.0 + 1.5)).abs() < 1e-12);
        let s = b.slice((0.0, 0.0), (30.0, 0.0), 4);
        assert_eq!(s.len(), 4);
        assert!((s[3].0 - 30.0).abs() < 1e-12 && (s[3].1 - 16.0).abs() < 1e-12);
    }

    #[test]
    fn ascii_grid_loads_north_row_first() {
        let txt = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n30 31 32\n20 21 22\n";
        let b = Bathymetry::parse_ascii_grid(txt, "t.asc").unwrap();
        assert!((b.depth_at(5.0, 5.0) - 20.0).abs() < 1e-12);
        assert!((b.depth_at(25.0, 15.0) - 32.0).abs() < 1e-12);
    }

    #[test]
    fn ascii_grid_errors_name_the_line() {
        let bad = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n30 31\n20 21 22\n";
        match Bathymetry::parse_ascii_grid(bad, "t.asc") {
            Err(BathymetryError::Parse { line: 6, message, .. }) => assert!(message.contains("expected ncols = 3")),
            other => panic!("{other:?}"),
        }
        let nodata = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n30 -9999\n20 21\n";
        assert!(matches!(Bathymetry::parse_ascii_grid(nodata, "t.asc"), Err(BathymetryError::Parse { line: 7, .. })));
        let missing = "ncols 2\nnrows 2\nxllcorner 0\ncellsize 10\n1 2\n3 4\n";
        assert!(matches!(Bathymetry::parse_ascii_grid(missing, "t.asc"), Err(BathymetryError::Shape { .. })));
    }

    /// Inputs that would ask for absurd grids are refused before anything is allocated: a
    /// diagonal of points (n² nodes for n points) and a shelf spacing of a millimetre.
    #[test]
    fn absurd_grids_are_refused_before_allocation() {
        let diagonal: String = (0..20_000).map(|i| format!("{i},{i},30\n")).collect();
        let e = Bathymetry::parse_csv(&diagonal, "diag.csv").unwrap_err().to_string();
        assert!(e.contains("20000 points cannot fill the 20000 × 20000 grid"), "{e}");
        for spacing in [1e-3, 1e-9] {
            let e = Bathymetry::shelf(&Shelf { spacing, ..Shelf::default() }).unwrap_err().to_string();
            assert!(e.contains("nodes (at most 1e8)"), "{spacing}: {e}");
        }
        assert!((Shelf::default().nodes() - 81.0 * 81.0).abs() < 1e-9);
        assert!(Bathymetry::shelf(&Shelf::default()).is_ok());
    }

    #[test]
    fn csv_grid_loads_and_rejects_bad_input() {
        let ok = "x,y,depth\n0,0,10\n10,0,12\n0,10,14\n10,10,16\n";
        let b = Bathymetry::parse_csv(ok, "g.csv").unwrap();
        assert!((b.depth_at(5.0, 5.0) - 13.0).abs() < 1e-12);
        assert!(matches!(
            Bathymetry::parse_csv("x,y,depth\n0,0,10\n10,0,abc\n", "g.csv"),
            Err(BathymetryError::Parse { line: 3, .. })
        ));
        assert!(matches!(
            Bathymetry::parse_csv("0,0,10\n10,0,-1\n", "g.csv"),
            Err(BathymetryError::Parse { line: 2, .. })
        ));
        assert!(matches!(
            Bathymetry::parse_csv("0,0,10\n10,0,12\n0,10,14\n", "g.csv"),
            Err(BathymetryError::Shape { .. })
        ));
        assert!(matches!(
            Bathymetry::parse_csv("0,0,10\n10,0,12\n0,10,14\n10,10,1\n10,10,2\n", "g.csv"),
            Err(BathymetryError::Parse { line: 5, .. })
        ));
        assert!(matches!(Bathymetry::load(Path::new("/nonexistent/grid.csv")), Err(BathymetryError::Io { .. })));
    }
}
