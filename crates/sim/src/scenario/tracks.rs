//! Survey-track CSV files: a header `t,x,y,z` then one row per sample (seconds, metres, z = depth
//! positive down), strictly increasing in time. Errors give the file and line.

use coopnav_core::{Track, TrackError, TrackSample, Vec3};
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum TrackLoadError {
    #[error("track file: {source}")]
    Read { path: PathBuf, source: coopnav_core::limits::InputError },
    #[error("track file {path}, line {line}: {message}")]
    Line { path: PathBuf, line: usize, message: String },
    #[error("track file {path}: {source}")]
    Track { path: PathBuf, source: TrackError },
}

/// Reads a `t,x,y,z` track CSV.
pub fn load_track_csv(path: &Path) -> Result<Track, TrackLoadError> {
    let limit = coopnav_core::limits::MAX_TABLE_FILE_BYTES;
    let text = coopnav_core::limits::read_text(path, "track file (bytes)", limit, false)
        .map_err(|source| TrackLoadError::Read { path: path.to_path_buf(), source })?;
    parse_track_csv(&text, path)
}

/// Parses `t,x,y,z` CSV text (`path` names it in messages).
pub fn parse_track_csv(text: &str, path: &Path) -> Result<Track, TrackLoadError> {
    let line_err = |line: usize, message: String| TrackLoadError::Line { path: path.to_path_buf(), line, message };
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| line_err(1, "file is empty: expected a header t,x,y,z and at least one row".into()))?;
    let cols: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
    if cols != ["t", "x", "y", "z"] {
        return Err(line_err(1, format!("header must be t,x,y,z, got '{}'", header.trim())));
    }
    let mut samples = Vec::new();
    for (i, l) in lines {
        let line = i + 1;
        let vals: Vec<&str> = l.split(',').map(str::trim).collect();
        if vals.len() != 4 {
            return Err(line_err(line, format!("expected 4 values t,x,y,z, got {}", vals.len())));
        }
        let mut v = [0.0; 4];
        for (j, s) in vals.iter().enumerate() {
            v[j] = s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                line_err(line, format!("column {} is not a finite number: '{s}'", ["t", "x", "y", "z"][j]))
            })?;
        }
        if let Some(prev) = samples.last().map(|s: &TrackSample| s.t) {
            if v[0] <= prev {
                return Err(line_err(
                    line,
                    format!("time {} is not after the previous row's {prev} (times must increase strictly)", v[0]),
                ));
            }
        }
        samples.push(TrackSample { t: v[0], pos: Vec3::new(v[1], v[2], v[3]) });
    }
    if samples.is_empty() {
        return Err(line_err(2, "no data rows after the header".into()));
    }
    Track::new(samples).map_err(|source| TrackLoadError::Track { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_track() {
        let t = parse_track_csv("t,x,y,z\n0,0,0,90\n10,15,0,90\n", Path::new("a.csv")).unwrap();
        assert_eq!(t.at(5.0), Vec3::new(7.5, 0.0, 90.0));
    }

    #[test]
    fn bad_tracks_name_the_line() {
        let p = Path::new("a.csv");
        let e = parse_track_csv("", p).unwrap_err().to_string();
        assert!(e.contains("empty"), "{e}");
        let e = parse_track_csv("t,x,y,z\n", p).unwrap_err().to_string();
        assert!(e.contains("no data rows"), "{e}");
        let e = parse_track_csv("t,x,y,z\n0,0,0,0\n10,1,1,1\n5,2,2,2\n", p).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("increase"), "{e}");
        let e = parse_track_csv("t,x,y,z\n0,0,zero,0\n", p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("column y"), "{e}");
        let e = parse_track_csv("time,x,y\n", p).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("header"), "{e}");
        let e = load_track_csv(Path::new("/nonexistent/track.csv")).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/track.csv"), "{e}");
    }
}
