//! A study's output directory that fills as the study runs and that a rerun resumes: each
//! mission's runs are written to `missions/NNN.cbor` as soon as the mission finishes (staged and
//! renamed, [`write_file`]), and a rerun with the same directory reads the missions already
//! there instead of flying them again. The study's report is computed from these files whether
//! they were written by this process or an earlier one, so an interrupted-and-resumed study gives
//! the same bytes as one that ran straight through.
//!
//! The directory's `manifest.json` (written when the directory is opened, before any work)
//! stamps the study: experiment, generator file and a digest of its text, seed, missions, runs,
//! policies and the crate's version. A directory stamped otherwise is refused with every field
//! that differs. Each mission file holds its own header (the stamp, the mission's index, its
//! seed and a digest of its scenario) and is refused when that header is not the one expected.
//!
//! The files are CBOR, which keeps every f64 bit for bit (NaN and infinities included), as the
//! sweep shards are (`coopnav-sweep`).

use crate::observe::metrics::RunResult;
use crate::output::{write_file, Manifest, OutputError};
use serde::{Deserialize, Serialize};
use std::fs;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a study directory cannot be opened, read or written; each names the file and what to do.
#[derive(Debug, Error)]
pub enum StudyDirError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error(
        "{} is neither empty nor a study directory ({}: {source}); name a new directory, or pass --force to replace it",
        dir.display(),
        manifest.display()
    )]
    NotAStudy { dir: PathBuf, manifest: PathBuf, source: std::io::Error },
    #[error("{}: {source}", manifest.display())]
    Manifest { manifest: PathBuf, source: serde_json::Error },
    #[error(
        "{}: field inputs.study is not a study's stamp ({source}); {} holds another run: name a new directory, or pass --force to replace it",
        manifest.display(),
        dir.display()
    )]
    NotAStamp { dir: PathBuf, manifest: PathBuf, source: serde_json::Error },
    #[error(
        "{} holds another study's missions ({}: {}); resume it with the same generator file, seed, size and \
         coopnav version, name a new directory, or pass --force to replace it",
        dir.display(),
        manifest.display(),
        differs.join("; ")
    )]
    OtherStudy { dir: PathBuf, manifest: PathBuf, differs: Vec<String> },
    #[error("{}: not a coopnav mission results file", path.display())]
    NotMissionResults { path: PathBuf },
    #[error("{}: unreadable mission results ({message})", path.display())]
    Unreadable { path: PathBuf, message: String },
    #[error("{} is not mission {index} of this study ({}); remove it to fly the mission again", path.display(), differs.join("; "))]
    OtherMission { path: PathBuf, index: usize, differs: Vec<String> },
    #[error(
        "{}: {found} run results, where {} ({policies} policies x {runs} runs) are expected; remove it to fly the mission again",
        path.display(),
        policies * runs
    )]
    RunCount { path: PathBuf, found: usize, policies: usize, runs: usize },
    #[error("{0}")]
    Encode(String),
    #[error(transparent)]
    Write(#[from] OutputError),
}

/// The first line of every mission file.
pub const MAGIC: &[u8] = b"coopnav study mission results\n";

/// What a study is: the fields a resumed study must share with the one that wrote the directory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stamp {
    pub experiment: String,
    /// The generator file, as the repository names it.
    pub generator: String,
    /// FNV-1a 64 of the generator file's text (hex).
    pub generator_digest: String,
    /// The missions' base seed (mission i flies seed + i).
    pub seed: u64,
    pub missions: usize,
    pub runs: usize,
    pub policies: Vec<String>,
    /// The coopnav crate version that wrote the directory.
    pub version: String,
}

impl Stamp {
    /// Each field that differs, as `name: there X, here Y`.
    fn differences(&self, here: &Stamp) -> Vec<String> {
        let there = serde_json::to_value(self).unwrap_or_default();
        let ours = serde_json::to_value(here).unwrap_or_default();
        let (Some(there), Some(ours)) = (there.as_object(), ours.as_object()) else { return Vec::new() };
        ours.iter()
            .filter(|(k, v)| there.get(*k) != Some(*v))
            .map(|(k, v)| format!("{k}: {} there, {v} here", there.get(k).cloned().unwrap_or_default()))
            .collect()
    }
}

/// One mission file's header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionHeader {
    pub stamp: Stamp,
    pub index: usize,
    pub seed: u64,
    /// FNV-1a 64 of the mission's scenario as TOML (hex): the scenario flown, not only its seed.
    pub scenario_digest: String,
}

/// One mission file: its header and every run, policy by policy in the study's order, run by
/// run within each policy.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct MissionFile {
    header: MissionHeader,
    results: Vec<RunResult>,
}

/// FNV-1a 64 of `bytes`, hex (an identity, not a security digest).
pub fn digest(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// An open study directory.
#[derive(Debug)]
pub struct StudyDir {
    dir: PathBuf,
    stamp: Stamp,
}

const MANIFEST: &str = "manifest.json";
const MISSIONS: &str = "missions";

impl StudyDir {
    /// Opens `dir` for the study `stamp`: an absent or empty directory is made a new study (its
    /// manifest written at once); a directory whose manifest carries the same stamp is resumed;
    /// anything else is refused, naming the directory and what differs.
    pub fn open(dir: &Path, stamp: Stamp) -> Result<StudyDir, StudyDirError> {
        let manifest = dir.join(MANIFEST);
        let io = |source| StudyDirError::Io { path: dir.to_path_buf(), source };
        let empty = match fs::read_dir(dir) {
            Ok(mut entries) => entries.next().is_none(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
            Err(e) => return Err(io(e)),
        };
        if empty {
            fs::create_dir_all(dir.join(MISSIONS)).map_err(io)?;
            let inputs = serde_json::json!({ "id": stamp.experiment, "seed": stamp.seed, "study": stamp });
            let m = Manifest::new("reproduce", Some(stamp.seed), inputs);
            let text = serde_json::to_string_pretty(&m).map_err(|e| StudyDirError::Encode(e.to_string()))? + "\n";
            write_file(&manifest, text.as_bytes(), false, |_| false, &[])?;
            return Ok(StudyDir { dir: dir.to_path_buf(), stamp });
        }
        let text = fs::read_to_string(&manifest).map_err(|source| StudyDirError::NotAStudy {
            dir: dir.to_path_buf(),
            manifest: manifest.clone(),
            source,
        })?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|source| StudyDirError::Manifest { manifest: manifest.clone(), source })?;
        let there: Stamp = serde_json::from_value(value["inputs"]["study"].clone()).map_err(|source| {
            StudyDirError::NotAStamp { dir: dir.to_path_buf(), manifest: manifest.clone(), source }
        })?;
        let differs = there.differences(&stamp);
        if !differs.is_empty() {
            return Err(StudyDirError::OtherStudy { dir: dir.to_path_buf(), manifest, differs });
        }
        fs::create_dir_all(dir.join(MISSIONS)).map_err(io)?;
        Ok(StudyDir { dir: dir.to_path_buf(), stamp })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where mission `index`'s runs are written.
    pub fn mission_path(&self, index: usize) -> PathBuf {
        self.dir.join(MISSIONS).join(format!("{index:03}.cbor"))
    }

    fn header(&self, index: usize, seed: u64, scenario_digest: &str) -> MissionHeader {
        MissionHeader { stamp: self.stamp.clone(), index, seed, scenario_digest: scenario_digest.to_string() }
    }

    /// Mission `index`'s runs when an earlier run wrote them (None: not yet flown). A file whose
    /// header is not this mission's (another study, seed or scenario) or that does not hold
    /// policies × runs results is refused, naming it.
    pub fn load(
        &self,
        index: usize,
        seed: u64,
        scenario_digest: &str,
    ) -> Result<Option<Vec<RunResult>>, StudyDirError> {
        let path = self.mission_path(index);
        let bytes = match fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(StudyDirError::Io { path, source }),
        };
        let Some(body) = bytes.strip_prefix(MAGIC) else {
            return Err(StudyDirError::NotMissionResults { path });
        };
        let file: MissionFile = ciborium::from_reader(body)
            .map_err(|e| StudyDirError::Unreadable { path: path.clone(), message: e.to_string() })?;
        let expected = self.header(index, seed, scenario_digest);
        if file.header != expected {
            let mut what = file.header.stamp.differences(&expected.stamp);
            for (name, there, here) in [
                ("index", file.header.index.to_string(), expected.index.to_string()),
                ("seed", file.header.seed.to_string(), expected.seed.to_string()),
                ("scenario_digest", file.header.scenario_digest.clone(), expected.scenario_digest.clone()),
            ] {
                if there != here {
                    what.push(format!("{name}: {there} there, {here} here"));
                }
            }
            return Err(StudyDirError::OtherMission { path, index, differs: what });
        }
        if file.results.len() != self.stamp.policies.len() * self.stamp.runs {
            let (policies, runs) = (self.stamp.policies.len(), self.stamp.runs);
            return Err(StudyDirError::RunCount { path, found: file.results.len(), policies, runs });
        }
        Ok(Some(file.results))
    }

    /// Writes mission `index`'s runs (staged beside the file and renamed over it once whole).
    pub fn store(
        &self,
        index: usize,
        seed: u64,
        scenario_digest: &str,
        results: &[RunResult],
    ) -> Result<(), StudyDirError> {
        let file = MissionFile { header: self.header(index, seed, scenario_digest), results: results.to_vec() };
        let mut bytes = MAGIC.to_vec();
        ciborium::into_writer(&file, &mut bytes).map_err(|e| StudyDirError::Encode(e.to_string()))?;
        Ok(write_file(&self.mission_path(index), &bytes, false, |_| false, &[])?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamp() -> Stamp {
        Stamp {
            experiment: "x".into(),
            generator: "g.toml".into(),
            generator_digest: digest(b"seed = 1"),
            seed: 7,
            missions: 2,
            runs: 1,
            policies: vec!["a".into()],
            version: "0.1.0".into(),
        }
    }

    #[test]
    fn a_directory_of_another_study_is_refused_naming_what_differs() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("s");
        StudyDir::open(&dir, stamp()).unwrap();
        // The same study resumes.
        StudyDir::open(&dir, stamp()).unwrap();
        let other = Stamp { seed: 8, version: "0.2.0".into(), ..stamp() };
        let e = StudyDir::open(&dir, other).unwrap_err();
        assert!(matches!(&e, StudyDirError::OtherStudy { differs, .. } if differs.len() == 2), "{e}");
        let e = e.to_string();
        assert!(e.contains("seed: 7 there, 8 here"), "{e}");
        assert!(e.contains("version: \"0.1.0\" there, \"0.2.0\" here"), "{e}");
        assert!(!e.contains("runs:"), "{e}");
        // A directory holding something else is refused.
        let busy = tmp.path().join("busy");
        fs::create_dir(&busy).unwrap();
        fs::write(busy.join("notes.txt"), "mine").unwrap();
        let e = StudyDir::open(&busy, stamp()).unwrap_err().to_string();
        assert!(e.contains("neither empty nor a study directory"), "{e}");
    }

    #[test]
    fn a_mission_file_of_another_mission_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let d = StudyDir::open(&tmp.path().join("s"), stamp()).unwrap();
        assert!(d.load(0, 7, "d0").unwrap().is_none());
        d.store(0, 7, "d0", &[]).unwrap();
        // Zero results where one is expected.
        let e = d.load(0, 7, "d0").unwrap_err().to_string();
        assert!(e.contains(": 0 run results, where 1 (1 policies x 1 runs) are expected"), "{e}");
        let e = d.load(0, 7, "other").unwrap_err().to_string();
        assert!(e.contains("scenario_digest: d0 there, other here"), "{e}");
        fs::write(d.mission_path(1), b"junk").unwrap();
        assert!(d.load(1, 8, "d1").unwrap_err().to_string().contains("not a coopnav mission results file"));
    }
}
