//! Reading an input file (scenario, config, spec, mapping) through the libraries' one bounded
//! reader ([`coopnav_core::limits::read_text`]): at most [`MAX_INPUT_FILE_BYTES`] are read
//! without `--allow-large`, whatever the input is (a file, a pipe, a device), so a mistaken
//! multi-gigabyte input is refused before it fills memory.
//!
//! A file that does not read as what a command expects is tried against coopnav's other TOML
//! formats ([`Format`]); when exactly one of them reads it, the error says which it is and which
//! command reads it, instead of only naming the first field the expected format does not know.

use anyhow::Result;
use coopnav_core::limits::{self, MAX_INPUT_FILE_BYTES};
use std::path::Path;

/// The text of `path`, read at most to the input limit.
pub fn read(path: &Path, allow_large: bool) -> Result<String> {
    Ok(limits::read_text(path, "input file (bytes)", MAX_INPUT_FILE_BYTES, allow_large)?)
}

/// coopnav's TOML input formats, by the command that reads each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A closed-loop mission (`simulate`, `advise`, `sitl`, `hbl simulate|montecarlo|grid|tune`).
    Mission,
    /// A pre-deployment planning scenario.
    Plan,
    /// A sweep file.
    Sweep,
    /// A Nams rate-selection experiment.
    Nams,
    /// A mission generator's ranges.
    Generator,
    /// An `hbl tune` spec.
    HblTune,
    /// An `hbl grid` spec.
    HblGrid,
    /// An `hbl postprocess` config.
    HblPost,
    /// An `hbl postprocess` log-format description.
    HblLogFormat,
}

impl Format {
    const ALL: [Format; 9] = [
        Format::Mission,
        Format::Plan,
        Format::Sweep,
        Format::Nams,
        Format::Generator,
        Format::HblTune,
        Format::HblGrid,
        Format::HblPost,
        Format::HblLogFormat,
    ];

    /// What the format is called.
    pub fn name(self) -> &'static str {
        match self {
            Format::Mission => "a closed-loop mission",
            Format::Plan => "a planning scenario",
            Format::Sweep => "a sweep file",
            Format::Nams => "a rate-selection experiment",
            Format::Generator => "a mission generator's ranges",
            Format::HblTune => "a tuning spec",
            Format::HblGrid => "a buoy-grid spec",
            Format::HblPost => "a post-processing config",
            Format::HblLogFormat => "a log-format description",
        }
    }

    /// The command that reads the format, and the one that prints an example of it.
    pub fn read_by(self) -> &'static str {
        match self {
            Format::Mission => "read by `coopnav simulate FILE`; example: `coopnav simulate --example`",
            Format::Plan => "read by `coopnav plan FILE`; example: `coopnav plan --example`",
            Format::Sweep => "read by `coopnav sweep plan FILE`; example: `coopnav sweep --example`",
            Format::Nams => "read by `coopnav nams FILE`; example: `coopnav nams --example`",
            Format::Generator => "read by `coopnav generate FILE`; example: scenarios/generators/",
            Format::HblTune => "read by `coopnav hbl tune --spec FILE`; example: `coopnav hbl example tune`",
            Format::HblGrid => "read by `coopnav hbl grid --grid FILE`; example: `coopnav hbl example grid`",
            Format::HblPost => "read by `coopnav hbl postprocess --config FILE`; example: `coopnav hbl example post`",
            Format::HblLogFormat => {
                "read by `coopnav hbl simulate --log-format FILE`; example: `coopnav hbl example log-format`"
            }
        }
    }

    /// Whether `text` reads as this format (its fields and types, before validation).
    fn reads(self, text: &str) -> bool {
        let file = Path::new("");
        match self {
            Format::Mission => coopnav_sim::scenario::Scenario::read(text, file).is_ok(),
            Format::Plan => coopnav_sim::scenario::plan::Scenario::read(text, file).is_ok(),
            Format::Sweep => coopnav_sweep::file::SweepFile::parse(text, file).is_ok(),
            Format::Nams => crate::nams::parse_file(text, file).is_ok(),
            Format::Generator => coopnav_sim::scenario::generate::Ranges::parse(text, file).is_ok(),
            Format::HblTune => toml::from_str::<coopnav_sim::batch::tune::TuneSpec>(text).is_ok(),
            Format::HblGrid => toml::from_str::<coopnav_sim::batch::grid::GridSpec>(text).is_ok(),
            Format::HblPost => coopnav_nav::post::PostConfig::from_toml(text).is_ok(),
            Format::HblLogFormat => toml::from_str::<coopnav_sim::output::log_format::LogFormat>(text).is_ok(),
        }
    }

    /// The one other format `text` reads as, if exactly one does: an empty file or one of only
    /// shared keys reads as several, and then nothing is guessed.
    pub fn other_reading(self, text: &str) -> Option<Format> {
        let mut others = Format::ALL.into_iter().filter(|f| *f != self && f.reads(text));
        match (others.next(), others.next()) {
            (Some(f), None) => Some(f),
            _ => None,
        }
    }
}

/// `parsed` (the result of reading `text`, from `path`, as `expected`), with the error naming the
/// format the file is in when it is one of coopnav's others.
pub fn parsed_as<T, E: Into<anyhow::Error>>(
    parsed: std::result::Result<T, E>,
    text: &str,
    path: &Path,
    expected: Format,
) -> Result<T> {
    parsed.map_err(|e| {
        let e = e.into();
        match expected.other_reading(text) {
            Some(found) => e.context(format!(
                "{} is {} ({}), not {}",
                path.display(),
                found.name(),
                found.read_by(),
                expected.name()
            )),
            None => e,
        }
    })
}

/// Reads `path` and parses it with `parse` as `format`: a parse error says `in PATH`, and names
/// the format the file is in when it is one of coopnav's others ([`parsed_as`]).
pub fn read_as<T, E>(
    path: &Path,
    allow_large: bool,
    format: Format,
    parse: impl FnOnce(&str) -> std::result::Result<T, E>,
) -> Result<T>
where
    std::result::Result<T, E>: anyhow::Context<T, E>,
{
    use anyhow::Context as _;
    let text = read(path, allow_large)?;
    let parsed = parse(&text).with_context(|| format!("in {}", path.display()));
    parsed_as(parsed, &text, path, format)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hbl::{self, ExampleKind};

    /// Every format's own example reads as that format and as no other, so the guess is never
    /// ambiguous for a file a command printed.
    #[test]
    fn each_example_reads_as_its_own_format_only() {
        let examples = [
            (Format::Mission, coopnav_sim::scenario::EXAMPLE.to_string()),
            (Format::Plan, coopnav_sim::scenario::plan::EXAMPLE.to_string()),
            (Format::Sweep, coopnav_sweep::file::EXAMPLE.to_string()),
            (Format::Nams, crate::nams::example().unwrap()),
            (Format::Mission, hbl::example_text(ExampleKind::Scenario).unwrap()),
            (Format::HblTune, hbl::example_text(ExampleKind::Tune).unwrap()),
            (Format::HblGrid, hbl::example_text(ExampleKind::Grid).unwrap()),
            (Format::HblPost, hbl::example_text(ExampleKind::Post).unwrap()),
            (Format::HblLogFormat, hbl::example_text(ExampleKind::LogFormat).unwrap()),
            (Format::Generator, include_str!("../../../scenarios/generators/generalization.toml").to_string()),
        ];
        for (format, text) in &examples {
            let reads: Vec<Format> = Format::ALL.into_iter().filter(|f| f.reads(text)).collect();
            assert_eq!(reads, [*format], "{format:?}'s example");
        }
    }

    #[test]
    fn a_planning_scenario_given_to_simulate_is_named_as_one() {
        let text = coopnav_sim::scenario::plan::EXAMPLE;
        let read = coopnav_sim::scenario::Scenario::read(text, Path::new("plan.toml"));
        let e = parsed_as(read, text, Path::new("plan.toml"), Format::Mission).unwrap_err();
        let shown = format!("{e:#}");
        assert!(shown.starts_with("plan.toml is a planning scenario (read by `coopnav plan FILE`"), "{shown}");
        // The parser's own message is kept after it.
        assert!(shown.contains("unknown field `depth`"), "{shown}");
    }

    #[test]
    fn an_empty_file_guesses_nothing() {
        assert_eq!(Format::Mission.other_reading(""), None);
        let read = coopnav_sim::scenario::Scenario::read("[nonsense]\n", Path::new("x.toml"));
        let e = parsed_as(read, "[nonsense]\n", Path::new("x.toml"), Format::Mission).unwrap_err();
        assert!(!format!("{e:#}").contains(" is a "), "{e:#}");
    }
}
