//! The arguments every scenario-driven command shares (`coopnav plan`, `coopnav simulate`): the
//! scenario file, `-o/--output`, `--force`, `--allow-large` and `--example`, and what they mean —
//! print the embedded scenario, read the file (its size checked first) or else the embedded
//! scenario, and open the run directory
//! (the one given, or a fresh `runs/<prefix>-<name>`). Each command says what differs in a
//! [`ScenarioCommand`].

use crate::input::{self, Format};
use anyhow::Result;
use coopnav_core::limits::{self, Estimate};
use coopnav_sim::output::RunDir;
use coopnav_sim::scenario::file::{ScenarioError, Validate};
use serde::de::DeserializeOwned;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

/// What one scenario-driven command reads and how its shared arguments are described.
pub trait ScenarioCommand {
    type Scenario: DeserializeOwned;
    /// Help of the scenario argument, of `-o` and of `--example`.
    const SCENARIO_HELP: &'static str;
    const OUTPUT_HELP: &'static str;
    const EXAMPLE_HELP: &'static str;
    /// The embedded scenario (TOML), run when no file is given.
    const EXAMPLE: &'static str;
    /// Its name: messages call it `<embedded NAME>`, and its fresh run directories end in NAME.
    const EMBEDDED: &'static str;
    /// Fresh run directories are `runs/<RUN_PREFIX>-<scenario name>`.
    const RUN_PREFIX: &'static str;
    /// The format the scenario file is in (a file in another is named as such).
    const FORMAT: Format;
    /// Reads the scenario type from text without validating it (`file` names it in messages).
    const READ: fn(&str, &Path) -> Result<Self::Scenario, ScenarioError>;
    /// The scenario type's validation (`file` names it in messages).
    const VALIDATE: Validate<Self::Scenario>;
    /// The sizes the scenario asks for, checked before validation (which may build tables).
    const WORK: fn(&Self::Scenario) -> Vec<Estimate>;
}

#[derive(clap::Args)]
pub struct ScenarioArgs<C: ScenarioCommand> {
    #[arg(help = C::SCENARIO_HELP)]
    scenario: Option<PathBuf>,
    #[arg(short, long, help = C::OUTPUT_HELP)]
    output: Option<PathBuf>,
    #[arg(long, help = "Replace the output directory if it exists")]
    force: bool,
    #[arg(long, help = "Run even when the estimated work or memory is above coopnav's limits (coopnav_core::limits)")]
    allow_large: bool,
    #[arg(long, help = C::EXAMPLE_HELP)]
    example: bool,
    #[arg(skip)]
    command: PhantomData<fn() -> C>,
}

/// A scenario read and validated, with where it came from.
pub struct Loaded<S> {
    pub scenario: S,
    /// The file, or `<embedded NAME>`.
    pub file: PathBuf,
    /// The directory relative paths inside the scenario start from.
    pub base: PathBuf,
    /// The name fresh run directories are named after: the file's stem, or the embedded NAME.
    pub stem: String,
}

impl<C: ScenarioCommand> ScenarioArgs<C> {
    /// With `--example`, prints the embedded scenario and says so (the command then stops).
    pub fn print_example(&self) -> bool {
        if self.example {
            print!("{}", C::EXAMPLE);
        }
        self.example
    }

    /// `-o/--output`, when given.
    pub fn output(&self) -> Option<&Path> {
        self.output.as_deref()
    }

    /// `--allow-large`: the work limits are lifted.
    pub fn allow_large(&self) -> bool {
        self.allow_large
    }

    /// Reads and validates the scenario file, or the embedded scenario when none is given.
    pub fn load(&self) -> Result<Loaded<C::Scenario>> {
        Ok(match &self.scenario {
            Some(path) => Loaded {
                scenario: self.parse(&input::read(path, self.allow_large)?, path)?,
                file: path.clone(),
                base: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                stem: path.file_stem().map_or("scenario".into(), |s| s.to_string_lossy().into_owned()),
            },
            None => {
                let file = PathBuf::from(format!("<embedded {}>", C::EMBEDDED));
                Loaded {
                    scenario: self.parse(C::EXAMPLE, &file)?,
                    file,
                    base: PathBuf::from("."),
                    stem: C::EMBEDDED.to_string(),
                }
            }
        })
    }

    /// Parses `text` (read from `file`), checks its sizes against the work limits, validates it.
    fn parse(&self, text: &str, file: &Path) -> Result<C::Scenario> {
        let scenario = input::parsed_as((C::READ)(text, file), text, file, C::FORMAT)?;
        limits::check((C::WORK)(&scenario), self.allow_large)?;
        (C::VALIDATE)(&scenario, file)?;
        Ok(scenario)
    }

    /// Opens the run directory: `-o` (replaced only with `--force`), or a fresh
    /// `runs/<RUN_PREFIX>-<stem>`.
    /// `inputs` are the files the command reads: a directory holding one is never replaced.
    pub fn run_dir(&self, stem: &str, inputs: &[&Path]) -> Result<RunDir> {
        crate::run_dir::given_or_fresh(self.output.as_deref(), self.force, inputs, &format!("{}-{stem}", C::RUN_PREFIX))
    }
}
