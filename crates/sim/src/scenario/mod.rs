//! Scenarios: the types, validation and loading of every input file. The engine's scenario
//! ([`world`]) with its file loader ([`file`]), the pre-deployment planner's ([`plan`]) and its
//! survey-track CSVs ([`tracks`]), the seeded mission generator ([`generate`]), the `coopnav hbl` tools' file ([`hbl`]) and Nams's experiment
//! configuration ([`nams`]).

pub mod file;
pub mod generate;
pub mod hbl;
pub mod moved;
pub mod nams;
pub mod plan;
pub mod policies;
pub mod site;
pub mod start;
pub mod survey_import;
pub mod tl_site;
pub mod tracks;
pub mod world;

pub use file::ScenarioError;
pub use world::{BeforeFirstReport, Scenario, EXAMPLE};
