//! Scenarios (thesis Table 6), behaviours (§5.4: three controls and the adaptive selector, each a
//! [`RatePolicySpec`]) and the experiment configuration, validated before anything runs.

pub use crate::models::peer::EstimatorMode;
use crate::scenario::file::{Problems, ScenarioError};
use coopnav_acomms::selector::RatePolicySpec;
use coopnav_acomms::{Receiver, SuccessModel, Tdma};
use coopnav_core::validation::CheckFields;
use coopnav_core::{Iver2Params, Shelf};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One mission environment. A field a file leaves out is Table 6 scenario 1's ([`TABLE_6`]'s
/// first entry, which gives every field).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    #[serde(default = "first::name")]
    pub name: String,
    /// Side of the square lawnmower, m (500 or 2000 in the thesis).
    #[serde(default = "first::square")]
    pub square: f64,
    /// Lane spacing, m. Invented: docs/models.md#nams-scenarios (50 m small, 200 m large).
    #[serde(default = "first::lane_spacing")]
    pub lane_spacing: f64,
    /// Extra ambient noise, dB (0 or 6).
    #[serde(default = "first::noise_db")]
    pub noise_db: f64,
    #[serde(default = "first::receiver")]
    pub receiver: Receiver,
    /// Altitude above the seafloor, m (5 m altitude keeping).
    #[serde(default = "first::altitude")]
    pub altitude: f64,
    /// Speed through water, m/s (3 kn).
    #[serde(default = "first::speed")]
    pub speed: f64,
}

/// Each field's default: Table 6 scenario 1's. Per field (serde calls one only when its field is
/// missing), so reading [`TABLE_6`], whose entries give every field, asks for none of them.
mod first {
    use super::{table_6, Receiver, Scenario};

    fn scenario() -> Scenario {
        table_6().swap_remove(0)
    }
    pub fn name() -> String {
        scenario().name
    }
    pub fn square() -> f64 {
        scenario().square
    }
    pub fn lane_spacing() -> f64 {
        scenario().lane_spacing
    }
    pub fn noise_db() -> f64 {
        scenario().noise_db
    }
    pub fn receiver() -> Receiver {
        scenario().receiver
    }
    pub fn altitude() -> f64 {
        scenario().altitude
    }
    pub fn speed() -> f64 {
        scenario().speed
    }
}

/// Thesis Table 6's four scenarios as an experiment file (`scenarios/experiments/nams-table-6.toml`).
pub const TABLE_6: &str = include_str!("../../../../scenarios/experiments/nams-table-6.toml");

/// Thesis Table 6's scenarios 1–4, read from [`TABLE_6`].
pub fn table_6() -> Vec<Scenario> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        experiment: Scenarios,
    }
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Scenarios {
        scenarios: Vec<Scenario>,
    }
    toml::from_str::<File>(TABLE_6).expect("the embedded Table 6 file parses").experiment.scenarios
}

impl Scenario {
    /// Adds every out-of-range field to `problems`; `at` is this scenario's path in the file.
    fn collect_problems(&self, at: &str, problems: &mut Problems) {
        let mut in_range = |name: &str, v: f64, lo: f64, hi: f64| {
            problems.check(
                &format!("{at}.{name}"),
                v,
                |v| (lo..=hi).contains(&v),
                &format!("a number in [{lo}, {hi}]"),
            );
        };
        in_range("square", self.square, 10.0, 20_000.0);
        in_range("lane_spacing", self.lane_spacing, 1.0, self.square);
        in_range("noise_db", self.noise_db, 0.0, 60.0);
        in_range("altitude", self.altitude, 0.5, 100.0);
        in_range("speed", self.speed, 0.1, 5.0);
    }
}

/// A rate-selection behaviour: the rate policy both vehicles run (`{ kind = "fixed", rate = 1 }`,
/// `{ kind = "alternating", rates = [0, 5] }`, `{ kind = "adaptive", … }`).
pub type Behaviour = RatePolicySpec;

/// Everything an experiment needs besides the TL provider.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentConfig {
    pub scenarios: Vec<Scenario>,
    pub behaviours: Vec<RatePolicySpec>,
    pub runs: usize,
    pub seed: u64,
    pub shelf: Shelf,
    pub success: SuccessModel,
    pub tdma: Tdma,
    pub ack: bool,
    pub estimator: EstimatorMode,
    pub vehicle: Iver2Params,
    /// Limit on mission length, s (None: until both vehicles finish).
    pub max_time: Option<f64>,
}

impl Default for ExperimentConfig {
    fn default() -> Self {
        ExperimentConfig {
            scenarios: table_6(),
            behaviours: RatePolicySpec::thesis(),
            runs: 40,
            seed: 1,
            shelf: Shelf::default(),
            success: SuccessModel::default(),
            tdma: Tdma::default(),
            ack: false,
            estimator: EstimatorMode::PrePlanned,
            vehicle: Iver2Params::default(),
            max_time: None,
        }
    }
}

impl ExperimentConfig {
    /// Checks every field before anything runs; the message names every bad field and its allowed range.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        self.validate_file(Path::new("experiment configuration"), "experiment")
    }

    /// As [`ExperimentConfig::validate`], for a file (`file`) holding this configuration in table `table`.
    pub fn validate_file(&self, file: &Path, table: &str) -> Result<(), ScenarioError> {
        let mut problems = Problems::new(file);
        self.collect_problems(table, &mut problems);
        problems.finish()
    }

    fn collect_problems(&self, t: &str, problems: &mut Problems) {
        if self.scenarios.is_empty() {
            problems.push(format!("{t}.scenarios"), "[]", "at least one scenario");
        }
        if self.behaviours.is_empty() {
            problems.push(format!("{t}.behaviours"), "[]", "at least one behaviour");
        }
        if !(1..=100_000).contains(&self.runs) {
            problems.push(format!("{t}.runs"), self.runs.to_string(), "an integer in [1, 100000]");
        }
        for (i, s) in self.scenarios.iter().enumerate() {
            s.collect_problems(&format!("{t}.scenarios[{i}]"), problems);
        }
        for (i, b) in self.behaviours.iter().enumerate() {
            if let Err(e) = b.build() {
                problems.push(format!("{t}.behaviours[{i}]"), "rejected", e.to_string());
            }
        }
        if let Some(max_time) = self.max_time {
            problems.positive(&format!("{t}.max_time"), max_time);
        }
        self.success.check_fields(&format!("{t}.success."), problems);
        self.vehicle.check_fields(&format!("{t}.vehicle."), problems);
        problems.positive(&format!("{t}.tdma.base_slot"), self.tdma.base_slot);
        problems.positive(&format!("{t}.tdma.rate5_slot"), self.tdma.rate5_slot);
        problems.non_negative(&format!("{t}.tdma.ack_extra"), self.tdma.ack_extra);
        self.collect_shelf_problems(&format!("{t}.shelf"), problems);
    }

    /// Depths and extents must be finite, the grid spacing positive (the extent's order is the
    /// bathymetry's own check).
    fn collect_shelf_problems(&self, at: &str, problems: &mut Problems) {
        let s = &self.shelf;
        let finite = [
            ("shallow", s.shallow),
            ("deep", s.deep),
            ("x_shallow", s.x_shallow),
            ("x_deep", s.x_deep),
            ("x_min", s.x_min),
            ("x_max", s.x_max),
            ("y_min", s.y_min),
            ("y_max", s.y_max),
        ];
        for (name, v) in finite {
            problems.check(&format!("{at}.{name}"), v, |_| true, "a finite number");
        }
        problems.positive(&format!("{at}.spacing"), s.spacing);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thesis_experiment_is_valid() {
        ExperimentConfig::default().validate().unwrap();
    }

    #[test]
    fn table_6_is_the_thesis_four_and_gives_a_partial_scenario_its_missing_fields() {
        let t = table_6();
        let squares_noise: Vec<(f64, f64)> = t.iter().map(|s| (s.square, s.noise_db)).collect();
        assert_eq!(squares_noise, [(500.0, 0.0), (500.0, 6.0), (2000.0, 0.0), (2000.0, 6.0)]);
        // 3 kn at 5 m altitude, the lanes a tenth of the square.
        assert!(t.iter().all(|s| s.speed == 3.0 * 1852.0 / 3600.0 && s.altitude == 5.0));
        assert!(t.iter().all(|s| s.lane_spacing == s.square / 10.0 && s.receiver == Receiver::Iver2));
        assert_eq!(ExperimentConfig::default().scenarios, t);
        // A field left out is scenario 1's.
        let partial = "[[scenarios]]\nname = \"a\"\nsquare = 800.0\nnoise_db = 3.0\n";
        let read = toml::from_str::<ExperimentConfig>(partial).unwrap().scenarios;
        let want = Scenario { name: "a".into(), square: 800.0, noise_db: 3.0, ..t[0].clone() };
        assert_eq!(read, [want]);
    }

    #[test]
    fn every_bad_field_is_named_at_once() {
        let text = "runs = 0\nmax_time = -5.0\n[tdma]\nbase_slot = nan\n[shelf]\nspacing = -1.0\n\
                    [[scenarios]]\nname = \"a\"\nsquare = 500.0\nlane_spacing = 50.0\nnoise_db = nan\n\
                    altitude = -2.0\nspeed = 99.0\n";
        let cfg: ExperimentConfig = toml::from_str(text).unwrap();
        let e = cfg.validate_file(Path::new("exp.toml"), "experiment").unwrap_err().to_string();
        for field in [
            "exp.toml",
            "experiment.runs = 0",
            "experiment.max_time = -5",
            "experiment.tdma.base_slot = NaN",
            "experiment.shelf.spacing = -1",
            "experiment.scenarios[0].noise_db = NaN: allowed a number in [0, 60]",
            "experiment.scenarios[0].altitude = -2",
            "experiment.scenarios[0].speed = 99: allowed a number in [0.1, 5]",
        ] {
            assert!(e.contains(field), "{field} missing from: {e}");
        }
        assert!(e.contains("7 bad fields"), "{e}");
    }
}
