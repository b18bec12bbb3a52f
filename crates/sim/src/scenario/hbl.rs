//! The scenario file of the `coopnav hbl` tools: an engine scenario, as `coopnav simulate` reads
//! it (by default Gill's Table 5 HBL Two set-up, `scenarios/gill-table5-hbl-two.toml`). A file in
//! the former HBL-world format is refused with a message naming the file and the new format.

use crate::scenario::world::{Scenario, ScenarioError};
use coopnav_nav::cycle::Configuration;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Top-level keys only the former HBL-world format had.
const FORMER_KEYS: [&str; 12] = [
    "max_duration_s",
    "configuration",
    "cycle",
    "custom_cycle",
    "geometry",
    "init",
    "control",
    "acoustic",
    "buoy",
    "quantisation",
    "filters",
    "log",
];

#[derive(Debug, Error)]
pub enum HblScenarioError {
    #[error(
        "scenario {file}: this is the former `coopnav hbl` scenario format (its top-level `{key}`), which is gone: \
         the HBL tools run Gill's pass on the mission engine. Write an engine scenario file instead: \
         `coopnav hbl example scenario` prints Gill's Table 5 set-up in it (scenarios/gill-table5-hbl-two.toml; \
         gill-table5-msbl.toml and gill-table5-hbl-one.toml are the other configurations); \
         the former geometry.zone_min / zone_max are the hbl commands' --zone-min-m / --zone-max-m"
    )]
    FormerFormat { file: PathBuf, key: String },
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
}

/// Parses `text` (from `file`) as an engine scenario.
pub fn parse(text: &str, file: &Path) -> Result<Scenario, HblScenarioError> {
    Scenario::parse(text, file).map_err(|e| match former_key(text) {
        Some(key) => HblScenarioError::FormerFormat { file: file.to_path_buf(), key },
        None => e.into(),
    })
}

/// The first top-level key of `text` that only the former format had.
fn former_key(text: &str) -> Option<String> {
    let table: toml::Table = text.parse().ok()?;
    FORMER_KEYS.iter().find(|k| table.contains_key(**k)).map(|k| k.to_string())
}

/// Gill's Table 5 set-up as scenario files of the one engine (ship, buoy and AUV vehicles, Gill's
/// cycles as `gill_cycle` schedules, mini-packets through the engine's channel): configuration
/// `c`'s file name under `scenarios/` and its text.
pub fn table5_file(c: Configuration) -> (&'static str, &'static str) {
    match c {
        Configuration::Msbl => ("gill-table5-msbl.toml", include_str!("../../../../scenarios/gill-table5-msbl.toml")),
        Configuration::HblOne => {
            ("gill-table5-hbl-one.toml", include_str!("../../../../scenarios/gill-table5-hbl-one.toml"))
        }
        Configuration::HblTwo => {
            ("gill-table5-hbl-two.toml", include_str!("../../../../scenarios/gill-table5-hbl-two.toml"))
        }
    }
}

/// Configuration `c`'s Table 5 file, parsed.
pub fn table5_scenario(c: Configuration) -> Result<Scenario, ScenarioError> {
    let (file, text) = table5_file(c);
    Scenario::parse(text, Path::new(file))
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_nav::cycle::Configuration;

    #[test]
    fn a_former_format_file_is_refused_naming_the_file_and_the_new_format() {
        let former = "dt = 0.1\nmax_duration_s = 400.0\nconfiguration = \"msbl\"\ncycle = \"msbl\"\n\n[geometry]\nauv_speed = 0.85\n";
        let e = parse(former, Path::new("old-hbl.toml")).unwrap_err().to_string();
        assert!(e.contains("old-hbl.toml") && e.contains("former") && e.contains("max_duration_s"), "{e}");
        assert!(e.contains("coopnav hbl example scenario") && e.contains("gill-table5-hbl-two.toml"), "{e}");
        // An engine file with a typo is reported as the engine's error, not as the former format.
        let (name, text) = table5_file(Configuration::HblTwo);
        let typo = text.replacen("duration_s = 130.0", "duration_s = -1.0", 1);
        let e = parse(&typo, Path::new(name)).unwrap_err().to_string();
        assert!(e.contains("duration_s") && !e.contains("former"), "{e}");
        assert_eq!(parse(text, Path::new(name)).unwrap().ships.len(), 1);
    }
}
