//! The real BELLHOP program (Acoustic Toolbox) as a transmission-loss provider: writes the
//! `.env`, `.bty` and `.sbp` files for the 2-D slice between source and receiver (October SSP,
//! mud half-space 1490 m/s, 1.6 g/cm³, 1.0 dB/λ, 25 kHz, BT-1 source pattern; Nams 2014, §4.2
//! and App. A), runs the binary in a fresh temporary directory, and reads the incoherent TL from the
//! binary `.shd` file: TL = −20·log10|p| at the receiver node.
//!
//! The binary is found through `$COOPNAV_BELLHOP`, else `tools/bellhop/bellhop.exe` at the
//! repository root (installed by `scripts/install-bellhop.sh`); its Fortran libraries are looked
//! up in the `lib/` directory beside it.

use super::{TlError, TransmissionLoss, TL_CEILING};
use coopnav_core::{Bathymetry, Vec3};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use thiserror::Error;

const INSTALL_HINT: &str =
    "run `bash scripts/install-bellhop.sh` at the repository root, or set COOPNAV_BELLHOP to a bellhop.exe";

#[derive(Debug, Error)]
pub enum BellhopError {
    #[error("BELLHOP not found (looked for {tried}): {INSTALL_HINT}")]
    NotFound { tried: String },
    #[error(
        "COOPNAV_BELLHOP={path} is not an executable file: point it at bellhop.exe or unset it and {INSTALL_HINT}"
    )]
    BadEnvVar { path: String },
    #[error("BELLHOP input invalid: {0}")]
    BadEnvironment(String),
    #[error("BELLHOP I/O ({what}): {source}")]
    Io { what: String, source: std::io::Error },
    #[error("BELLHOP ({exe}) failed with {status}; last lines of its print file:\n{prt}\ncheck the environment values, or reinstall: {INSTALL_HINT}")]
    Exit { exe: String, status: String, prt: String },
    #[error("BELLHOP output {file} unreadable: {message} (incompatible BELLHOP version? {INSTALL_HINT})")]
    BadOutput { file: String, message: String },
}

/// The seabed half-space below the water column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Halfspace {
    pub cp: f64,
    pub cs: f64,
    /// Density, g/cm³.
    pub rho: f64,
    /// Attenuation, dB per wavelength.
    pub alpha: f64,
}

/// Everything BELLHOP needs besides the geometry.
#[derive(Debug, Clone)]
pub struct AcousticEnv {
    pub bathymetry: Arc<Bathymetry>,
    /// Sound-speed profile (depth m, speed m/s), depths increasing from 0.
    pub ssp: Vec<(f64, f64)>,
    pub bottom: Halfspace,
    pub freq_hz: f64,
    /// Source beam pattern (angle deg, positive down; relative level dB).
    pub beam: Vec<(f64, f64)>,
    /// Bathymetry samples along the slice (the thesis uses 10).
    pub slice_points: usize,
    /// Source pitch, deg nose-up: rotates the beam pattern by −pitch (Nams 2014, §4.2.2).
    pub source_pitch_deg: f64,
    /// Rays in the fan, the same for every run. Invented: BELLHOP's automatic count scales with
    /// the run's range box, so a one-receiver run and a whole field would read a shallow receiver
    /// differently; with a fixed fan both read the same value, and the default is large enough
    /// that more rays no longer change it.
    pub beams: usize,
}

/// The 17 Oct 2013 Bedford Basin cast (Nams 2014, §4.2 and App. A).
pub const OCTOBER_SSP: [(f64, f64); 44] = [
    (0.0, 1496.8),
    (1.0, 1495.9),
    (2.0, 1495.9),
    (3.0, 1495.8),
    (4.0, 1495.8),
    (5.0, 1495.8),
    (6.0, 1495.8),
    (7.0, 1495.8),
    (8.0, 1495.8),
    (9.0, 1495.9),
    (10.0, 1495.9),
    (11.0, 1495.9),
    (12.0, 1495.9),
    (13.0, 1495.9),
    (14.0, 1495.9),
    (15.0, 1495.9),
    (16.0, 1496.0),
    (16.9, 1496.0),
    (17.9, 1496.0),
    (19.0, 1495.9),
    (20.0, 1488.1),
    (21.0, 1480.8),
    (21.9, 1474.1),
    (22.9, 1470.2),
    (23.9, 1469.5),
    (24.9, 1468.8),
    (25.9, 1467.8),
    (26.9, 1467.3),
    (27.9, 1466.9),
    (28.9, 1466.9),
    (29.9, 1466.9),
    (30.9, 1466.9),
    (31.9, 1466.9),
    (32.9, 1467.0),
    (33.9, 1467.0),
    (34.9, 1467.1),
    (35.9, 1467.2),
    (36.9, 1467.2),
    (37.9, 1467.2),
    (38.9, 1467.2),
    (39.9, 1467.3),
    (40.9, 1467.3),
    (50.0, 1467.3),
    (60.0, 1467.3),
];

/// BT-1 transducer pattern at 25 kHz (Nams 2014, App. A `.sbp`), kept as the thesis's data.
pub const BT1_BEAM: [(f64, f64); 19] = [
    (-135.0, -6.90),
    (-120.0, -9.70),
    (-105.0, -5.50),
    (-90.0, -3.70),
    (-75.0, -5.50),
    (-60.0, -9.70),
    (-45.0, -6.90),
    (-30.0, -3.80),
    (-15.0, -2.80),
    (0.0, -2.90),
    (15.0, -3.70),
    (30.0, -5.30),
    (45.0, -6.80),
    (60.0, -4.50),
    (75.0, -1.20),
    (90.0, 0.00),
    (105.0, -1.20),
    (120.0, -4.50),
    (135.0, -6.80),
];

impl AcousticEnv {
    /// The thesis's environment over `bathymetry`.
    pub fn nams(bathymetry: Arc<Bathymetry>) -> Self {
        AcousticEnv {
            bathymetry,
            ssp: OCTOBER_SSP.to_vec(),
            bottom: Halfspace { cp: 1490.0, cs: 0.0, rho: 1.6, alpha: 1.0 },
            freq_hz: 25_000.0,
            beam: BT1_BEAM.to_vec(),
            slice_points: 10,
            source_pitch_deg: 0.0,
            beams: 3000,
        }
    }

    fn validate(&self) -> Result<(), BellhopError> {
        let bad = |m: String| Err(BellhopError::BadEnvironment(m));
        if self.ssp.first().map(|p| p.0) != Some(0.0) {
            return bad("ssp: the first point must be at depth 0 m".into());
        }
        if self.ssp.windows(2).any(|w| w[1].0 <= w[0].0) || self.ssp.iter().any(|p| !(p.1 > 0.0 && p.1.is_finite())) {
            return bad("ssp: depths must increase strictly and speeds be finite and > 0 m/s".into());
        }
        if !(self.freq_hz > 0.0 && self.freq_hz.is_finite()) {
            return bad(format!("freq_hz {} must be > 0", self.freq_hz));
        }
        if self.beam.len() < 2 || self.beam.windows(2).any(|w| w[1].0 <= w[0].0) {
            return bad("beam: need ≥ 2 points with increasing angles".into());
        }
        if !(100..=100_000).contains(&self.beams) {
            return bad(format!("beams {} must be within 100..=100000", self.beams));
        }
        if self.slice_points < 2 {
            return bad(format!("slice_points {} must be ≥ 2", self.slice_points));
        }
        Ok(())
    }

    /// SSP cut at `max_depth`, ending exactly there (extended with the last speed below it).
    fn ssp_to(&self, max_depth: f64) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = self.ssp.iter().copied().filter(|p| p.0 < max_depth).collect();
        let c = match self.ssp.iter().position(|p| p.0 >= max_depth) {
            Some(0) | None => self.ssp.last().map_or(1500.0, |p| p.1),
            Some(i) => {
                let (a, b) = (self.ssp[i - 1], self.ssp[i]);
                a.1 + (b.1 - a.1) * (max_depth - a.0) / (b.0 - a.0)
            }
        };
        out.push((max_depth, c));
        out
    }
}

/// One BELLHOP geometry: a 2-D slice, a source depth, receiver ranges (m) and depths (m).
struct Geometry<'a> {
    bottom: Vec<(f64, f64)>,
    source_depth: f64,
    ranges: &'a [f64],
    depths: Vec<f64>,
}

fn list(values: impl Iterator<Item = f64>) -> String {
    let mut s = String::new();
    for (i, v) in values.enumerate() {
        let _ = write!(
            s,
            "{}{v:.4}",
            if i > 0 && i % 8 == 0 {
                "\n"
            } else if i > 0 {
                " "
            } else {
                ""
            }
        );
    }
    s.push_str(" /");
    s
}

/// The `.env` text.
fn env_text(env: &AcousticEnv, g: &Geometry<'_>) -> String {
    // Rounded up so that no printed bathymetry point lies below the SSP's last depth.
    let max_depth = (g.bottom.iter().map(|p| p.1).fold(0.0, f64::max) * 100.0).ceil() / 100.0;
    let max_range_km = g.ranges.iter().copied().fold(0.0, f64::max) / 1000.0;
    let mut s = String::new();
    let _ = writeln!(s, "'coopnav auto-generated ENV file for BELLHOP'");
    let _ = writeln!(s, "{:.1}", env.freq_hz);
    let _ = writeln!(s, "1");
    let _ = writeln!(s, "'CVWT'");
    let _ = writeln!(s, "0 0.0 {max_depth:.2}");
    for (z, c) in env.ssp_to(max_depth) {
        let _ = writeln!(s, "{z:.2} {c:.2} /");
    }
    let b = env.bottom;
    let _ = writeln!(s, "'A*' 0.0");
    let _ = writeln!(s, "{max_depth:.2} {:.2} {:.2} {:.3} {:.3} /", b.cp, b.cs, b.rho, b.alpha);
    let _ = writeln!(s, "1\n{:.3} /", g.source_depth);
    let _ = writeln!(s, "{}\n{}", g.depths.len(), list(g.depths.iter().copied()));
    let _ = writeln!(s, "{}\n{}", g.ranges.len(), list(g.ranges.iter().map(|r| r / 1000.0)));
    let _ = writeln!(s, "'IB*'");
    let _ = writeln!(s, "{}", env.beams);
    let _ = writeln!(s, "-89.0 89.0 /");
    let _ = writeln!(s, "0.0 {:.3} {:.5}", 1.01 * max_depth, 1.01 * max_range_km);
    s
}

fn bty_text(bottom: &[(f64, f64)]) -> String {
    let mut s = format!("'L'\n{}\n", bottom.len());
    for (r, z) in bottom {
        let _ = writeln!(s, "{:.5} {z:.3}", r / 1000.0);
    }
    s
}

fn sbp_text(env: &AcousticEnv) -> String {
    let mut s = format!("{}\n", env.beam.len());
    for (a, db) in &env.beam {
        let _ = writeln!(s, "{:.2} {db:.2}", a - env.source_pitch_deg);
    }
    s
}

/// Reads the pressure field of a single-frequency, single-source `.shd` file: `nrz × nrr`
/// complex values, row-major by receiver depth.
pub fn parse_shd(bytes: &[u8], nrz: usize, nrr: usize, file: &str) -> Result<Vec<(f32, f32)>, BellhopError> {
    let bad = |message: String| BellhopError::BadOutput { file: file.to_string(), message };
    let word = |off: usize| -> Result<i32, BellhopError> {
        bytes
            .get(off..off + 4)
            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad(format!("truncated at byte {off}")))
    };
    let lrecl = word(0)?;
    if lrecl < 10 {
        return Err(bad(format!("record length {lrecl} words is too small")));
    }
    let rec = lrecl as usize * 4;
    let counts: Vec<i32> = (0..7).map(|i| word(2 * rec + 4 * i)).collect::<Result<_, _>>()?;
    let (nfreq, ntheta, nsz, f_nrz, f_nrr) = (counts[0], counts[1], counts[4], counts[5], counts[6]);
    if nfreq != 1 || ntheta != 1 || nsz != 1 {
        return Err(bad(format!("expected 1 frequency, 1 bearing, 1 source depth; got {nfreq}, {ntheta}, {nsz}")));
    }
    if f_nrz as usize != nrz || f_nrr as usize != nrr {
        return Err(bad(format!("expected {nrz} depths × {nrr} ranges, file has {f_nrz} × {f_nrr}")));
    }
    if rec < 8 * nrr {
        return Err(bad(format!("record of {rec} bytes cannot hold {nrr} complex values")));
    }
    let need = (10 + nrz) * rec;
    if bytes.len() < need {
        return Err(bad(format!("{} bytes, expected at least {need}", bytes.len())));
    }
    let mut out = Vec::with_capacity(nrz * nrr);
    for iz in 0..nrz {
        let base = (10 + iz) * rec;
        for ir in 0..nrr {
            let o = base + 8 * ir;
            let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
            out.push((f(o), f(o + 4)));
        }
    }
    Ok(out)
}

/// TL (dB) of a complex pressure, capped at [`TL_CEILING`].
pub fn tl_of(p: (f32, f32)) -> f64 {
    let mag = (p.0 as f64).hypot(p.1 as f64);
    if mag > 0.0 && mag.is_finite() {
        (-20.0 * mag.log10()).min(TL_CEILING)
    } else {
        TL_CEILING
    }
}

/// BELLHOP as a [`TransmissionLoss`] provider.
#[derive(Debug, Clone)]
pub struct Bellhop {
    exe: PathBuf,
    pub env: AcousticEnv,
}

impl Bellhop {
    /// Finds the binary: `$COOPNAV_BELLHOP`, else `tools/bellhop/bellhop.exe` at the repository
    /// root or under the current directory.
    pub fn locate() -> Result<PathBuf, BellhopError> {
        if let Ok(p) = std::env::var("COOPNAV_BELLHOP") {
            let path = PathBuf::from(&p);
            return if path.is_file() { Ok(path) } else { Err(BellhopError::BadEnvVar { path: p }) };
        }
        let candidates = [
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/bellhop/bellhop.exe"),
            PathBuf::from("tools/bellhop/bellhop.exe"),
        ];
        candidates.iter().find(|p| p.is_file()).cloned().ok_or_else(|| BellhopError::NotFound {
            tried: candidates.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
        })
    }

    /// Uses the located binary.
    pub fn new(env: AcousticEnv) -> Result<Self, BellhopError> {
        Self::with_exe(Self::locate()?, env)
    }

    pub fn with_exe(exe: PathBuf, env: AcousticEnv) -> Result<Self, BellhopError> {
        env.validate()?;
        if !exe.is_file() {
            return Err(BellhopError::NotFound { tried: exe.display().to_string() });
        }
        Ok(Bellhop { exe, env })
    }

    /// One BELLHOP run on the slice from `src` along `bearing`; returns TL row-major by depth.
    fn run(&self, src: &Vec3, bearing: f64, ranges: &[f64], rx_depths: &[f64]) -> Result<Vec<f64>, BellhopError> {
        if ranges.is_empty() || rx_depths.is_empty() {
            return Err(BellhopError::BadEnvironment("need at least one receiver range and depth".into()));
        }
        if ranges.windows(2).any(|w| w[1] <= w[0]) || ranges[0] <= 0.0 || ranges.iter().any(|r| !r.is_finite()) {
            return Err(BellhopError::BadEnvironment("receiver ranges must be finite, > 0 m and increasing".into()));
        }
        let max_range = ranges[ranges.len() - 1];
        // The slice runs 2 % past the last receiver so BELLHOP's range box stays inside it.
        let end = 1.02 * max_range;
        let (c, s) = (bearing.cos(), bearing.sin());
        let bottom =
            self.env.bathymetry.slice((src.x, src.y), (src.x + end * c, src.y + end * s), self.env.slice_points);
        let src_bottom = bottom[0].1;
        let max_depth = bottom.iter().map(|p| p.1).fold(0.0, f64::max);
        let geometry = Geometry {
            source_depth: src.z.clamp(0.5, (src_bottom - 0.5).max(0.5)),
            depths: rx_depths.iter().map(|z| z.clamp(0.5, (max_depth - 0.5).max(0.5))).collect(),
            ranges,
            bottom,
        };
        let dir = tempfile::Builder::new()
            .prefix("coopnav-bellhop-")
            .tempdir()
            .map_err(|e| BellhopError::Io { what: "temporary directory".into(), source: e })?;
        let io = |what: &str| {
            let what = format!("{what} in {}", dir.path().display());
            move |e| BellhopError::Io { what, source: e }
        };
        std::fs::write(dir.path().join("run.env"), env_text(&self.env, &geometry)).map_err(io("writing run.env"))?;
        std::fs::write(dir.path().join("run.bty"), bty_text(&geometry.bottom)).map_err(io("writing run.bty"))?;
        std::fs::write(dir.path().join("run.sbp"), sbp_text(&self.env)).map_err(io("writing run.sbp"))?;
        let exe = std::fs::canonicalize(&self.exe).map_err(io("resolving the BELLHOP path"))?;
        let libdir = exe.parent().map(|p| p.join("lib")).unwrap_or_default();
        let ld = match std::env::var("LD_LIBRARY_PATH") {
            Ok(old) if !old.is_empty() => format!("{}:{old}", libdir.display()),
            _ => libdir.display().to_string(),
        };
        let out = Command::new(&exe)
            .arg("run")
            .current_dir(dir.path())
            .env("LD_LIBRARY_PATH", ld)
            .output()
            .map_err(io("starting bellhop"))?;
        let shd = dir.path().join("run.shd");
        if !out.status.success() || !shd.is_file() {
            let prt = std::fs::read_to_string(dir.path().join("run.prt"))
                .unwrap_or_else(|_| String::from_utf8_lossy(&out.stderr).into_owned());
            let tail: Vec<&str> = prt.lines().rev().take(8).collect();
            return Err(BellhopError::Exit {
                exe: exe.display().to_string(),
                status: out.status.to_string(),
                prt: tail.into_iter().rev().collect::<Vec<_>>().join("\n"),
            });
        }
        let bytes = std::fs::read(&shd).map_err(io("reading run.shd"))?;
        let p = parse_shd(&bytes, rx_depths.len(), ranges.len(), "run.shd")?;
        Ok(p.into_iter().map(tl_of).collect())
    }
}

impl TransmissionLoss for Bellhop {
    fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError> {
        let r = (rx.x - src.x).hypot(rx.y - src.y).max(1.0);
        let bearing = (rx.y - src.y).atan2(rx.x - src.x);
        Ok(self.run(src, bearing, &[r], &[rx.z])?[0])
    }

    fn field(&self, src: &Vec3, bearing: f64, ranges: &[f64], depths: &[f64]) -> Result<Vec<f64>, TlError> {
        Ok(self.run(src, bearing, ranges, depths)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::Shelf;

    fn env() -> AcousticEnv {
        AcousticEnv::nams(Arc::new(Bathymetry::shelf(&Shelf::default()).unwrap()))
    }

    #[test]
    fn env_file_has_the_thesis_environment() {
        let g = Geometry {
            bottom: vec![(0.0, 22.2), (500.0, 40.7999)],
            source_depth: 0.5,
            ranges: &[100.0, 200.0],
            depths: vec![10.0],
        };
        let t = env_text(&env(), &g);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[1], "25000.0");
        assert_eq!(lines[3], "'CVWT'");
        assert_eq!(lines[4], "0 0.0 40.80");
        assert!(t.contains("'A*' 0.0\n40.80 1490.00 0.00 1.600 1.000 /"));
        assert!(t.contains("40.80 1467.30 /"), "SSP ends exactly at the deepest slice point");
        assert!(t.contains("2\n0.1000 0.2000 /"));
        assert!(t.contains("'IB*'\n3000\n"), "a fixed fan, whatever the run's range box");
        assert!(t.ends_with("0.0 41.208 0.20200\n"));
        assert_eq!(bty_text(&g.bottom), "'L'\n2\n0.00000 22.200\n0.50000 40.800\n");
        let deep = Geometry { bottom: vec![(0.0, 53.3333)], ..g };
        assert!(env_text(&env(), &deep).contains("0 0.0 53.34\n"), "max depth rounds up");
        let s = sbp_text(&AcousticEnv { source_pitch_deg: 10.0, ..env() });
        assert!(s.starts_with("19\n-145.00 -6.90\n"));
    }

    #[test]
    fn ssp_interpolates_at_the_cut() {
        let e = env();
        let s = e.ssp_to(20.5);
        assert_eq!(s.last().unwrap().0, 20.5);
        assert!((s.last().unwrap().1 - (1488.1 + 1480.8) / 2.0).abs() < 1e-9);
        assert_eq!(e.ssp_to(80.0).last().unwrap(), &(80.0, 1467.3));
    }

    fn fake_shd(nrz: usize, nrr: usize, p: f32) -> Vec<u8> {
        let lrecl = (2 * nrr).max(41);
        let rec = lrecl * 4;
        let mut b = vec![0u8; (10 + nrz) * rec];
        b[..4].copy_from_slice(&(lrecl as i32).to_le_bytes());
        for (i, v) in [1, 1, 1, 1, 1, nrz as i32, nrr as i32].iter().enumerate() {
            b[2 * rec + 4 * i..2 * rec + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
        }
        for iz in 0..nrz {
            for ir in 0..nrr {
                let o = (10 + iz) * rec + 8 * ir;
                b[o..o + 4].copy_from_slice(&(p * (1 + ir) as f32).to_le_bytes());
            }
        }
        b
    }

    #[test]
    fn shd_parser_reads_and_rejects() {
        let b = fake_shd(2, 3, 0.01);
        let p = parse_shd(&b, 2, 3, "x.shd").unwrap();
        assert_eq!(p.len(), 6);
        assert!((tl_of(p[0]) - 40.0).abs() < 1e-4);
        assert_eq!(tl_of((0.0, 0.0)), TL_CEILING);
        assert!(matches!(parse_shd(&b[..b.len() - 1], 2, 3, "x.shd"), Err(BellhopError::BadOutput { .. })));
        assert!(matches!(parse_shd(&b, 3, 3, "x.shd"), Err(BellhopError::BadOutput { .. })));
        assert!(matches!(parse_shd(&[1, 2], 1, 1, "x.shd"), Err(BellhopError::BadOutput { .. })));
        assert!(matches!(parse_shd(&[], 1, 1, "x.shd"), Err(BellhopError::BadOutput { .. })));
    }

    #[test]
    fn failures_are_typed_errors_that_say_what_to_run() {
        let e = Bellhop::with_exe(PathBuf::from("/nonexistent/bellhop.exe"), env()).unwrap_err();
        assert!(matches!(e, BellhopError::NotFound { .. }) && e.to_string().contains("install-bellhop.sh"));
        let bad = AcousticEnv { ssp: vec![(5.0, 1500.0)], ..env() };
        assert!(matches!(Bellhop::with_exe(PathBuf::from("/bin/false"), bad), Err(BellhopError::BadEnvironment(_))));
        for beams in [0, 99, 100_001] {
            let e = Bellhop::with_exe(PathBuf::from("/bin/false"), AcousticEnv { beams, ..env() }).unwrap_err();
            assert!(e.to_string().contains(&format!("beams {beams} must be within 100..=100000")), "{e}");
        }
        // A program that exits non-zero without output.
        let b = Bellhop::with_exe(PathBuf::from("/bin/false"), env()).unwrap();
        let e = b.tl(&Vec3::new(0.0, 0.0, 10.0), &Vec3::new(100.0, 0.0, 10.0)).unwrap_err();
        assert!(matches!(e, TlError::Bellhop(BellhopError::Exit { .. })), "{e}");
        assert!(e.to_string().contains("install-bellhop.sh"));
        // A program that "succeeds" but writes no .shd.
        let e = Bellhop::with_exe(PathBuf::from("/bin/true"), env())
            .unwrap()
            .tl(&Vec3::zeros(), &Vec3::new(50.0, 0.0, 5.0))
            .unwrap_err();
        assert!(matches!(e, TlError::Bellhop(BellhopError::Exit { .. })));
    }

    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn real_bellhop_gives_plausible_tl() {
        let b = Bellhop::new(env()).expect("build.rs found BELLHOP installed");
        let src = Vec3::new(0.0, 0.0, 10.0);
        let near = b.tl(&src, &Vec3::new(100.0, 0.0, 15.0)).unwrap();
        let far = b.tl(&src, &Vec3::new(2000.0, 0.0, 30.0)).unwrap();
        assert!((25.0..70.0).contains(&near), "TL at 100 m = {near} dB");
        assert!(far > near + 10.0, "TL grows with range: {near} → {far}");
        // The field mode agrees with the single-point mode at a shared node.
        let f = b.field(&src, 0.0, &[100.0, 500.0, 2000.0], &[15.0, 30.0]).unwrap();
        assert_eq!(f.len(), 6);
        assert!((f[0] - near).abs() < 3.0, "field {} vs point {near}", f[0]);
    }
}
