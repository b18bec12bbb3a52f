//! Scenarios (thesis Table 6), behaviours (§5.4: three controls and the adaptive selector) and the
//! experiment configuration, validated before anything runs.

use coopnav_acomms::selector::{AdaptiveBins, AdaptiveConfig, Alternating, FixedRate, RatePolicy};
use coopnav_acomms::{Rate, Receiver, SuccessModel, Tdma};
use coopnav_core::{Iver2Params, Shelf};
use serde::{Deserialize, Serialize};

/// One mission environment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scenario {
    pub name: String,
    /// Side of the square lawnmower, m (500 or 2000 in the thesis).
    pub square: f64,
    /// Lane spacing, m. Reconstructed: nams digest §8 item 21 (50 m small, 200 m large).
    pub lane_spacing: f64,
    /// Extra ambient noise, dB (0 or 6).
    pub noise_db: f64,
    pub receiver: Receiver,
    /// Altitude above the seafloor, m (5 m altitude keeping).
    pub altitude: f64,
    /// Speed through water, m/s (3 kn).
    pub speed: f64,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario::thesis(1)
    }
}

impl Scenario {
    /// Thesis Table 6 scenarios 1–4.
    pub fn thesis(n: usize) -> Scenario {
        let (square, noise_db) = match n {
            1 => (500.0, 0.0),
            2 => (500.0, 6.0),
            3 => (2000.0, 0.0),
            _ => (2000.0, 6.0),
        };
        Scenario {
            name: format!("scenario {n}"),
            square,
            lane_spacing: square / 10.0,
            noise_db,
            receiver: Receiver::Iver2,
            altitude: 5.0,
            speed: 3.0 * 1852.0 / 3600.0,
        }
    }

    fn validate(&self) -> Result<(), String> {
        let f = |name: &str, v: f64, lo: f64, hi: f64| {
            if (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(format!("{}: {name} = {v} must be in [{lo}, {hi}]", self.name))
            }
        };
        f("square", self.square, 10.0, 20_000.0)?;
        f("lane_spacing", self.lane_spacing, 1.0, self.square)?;
        f("noise_db", self.noise_db, 0.0, 60.0)?;
        f("altitude", self.altitude, 0.5, 100.0)?;
        f("speed", self.speed, 0.1, 5.0)
    }
}

/// A rate-selection behaviour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Behaviour {
    FixedRate0,
    FixedRate1,
    Alternating05,
    Adaptive(AdaptiveConfig),
}

impl Behaviour {
    /// The thesis's four: controls 1–3 and the adaptive selector without rate 5 (Table 8 values).
    pub fn thesis() -> Vec<Behaviour> {
        vec![
            Behaviour::FixedRate0,
            Behaviour::FixedRate1,
            Behaviour::Alternating05,
            Behaviour::Adaptive(AdaptiveConfig::default()),
        ]
    }
    pub fn policy(&self) -> Result<Box<dyn RatePolicy>, String> {
        Ok(match self {
            Behaviour::FixedRate0 => Box::new(FixedRate { rate: Rate::R0 }),
            Behaviour::FixedRate1 => Box::new(FixedRate { rate: Rate::R1 }),
            Behaviour::Alternating05 => Box::new(Alternating::new(vec![Rate::R0, Rate::R5])),
            Behaviour::Adaptive(c) => Box::new(AdaptiveBins::new(c.clone())?),
        })
    }
    pub fn label(&self) -> String {
        match self.policy() {
            Ok(p) => p.name(),
            Err(_) => "invalid".into(),
        }
    }
    pub fn is_control(&self) -> bool {
        !matches!(self, Behaviour::Adaptive(_))
    }
}

/// How the collaborator's position is estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorMode {
    /// Mission plans known to both (status carries a 1-byte waypoint id).
    PrePlanned,
    /// Plans unknown (status carries the next waypoint's lat/lon; stop there).
    Dynamic,
}

/// Everything an experiment needs besides the TL provider.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentConfig {
    pub scenarios: Vec<Scenario>,
    pub behaviours: Vec<Behaviour>,
    pub repetitions: usize,
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
            scenarios: (1..=4).map(Scenario::thesis).collect(),
            behaviours: Behaviour::thesis(),
            repetitions: 40,
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
    /// Checks every field before anything runs; the message names the field and allowed range.
    pub fn validate(&self) -> Result<(), String> {
        if self.scenarios.is_empty() || self.behaviours.is_empty() {
            return Err("scenarios and behaviours must each list at least one entry".into());
        }
        if !(1..=100_000).contains(&self.repetitions) {
            return Err(format!("repetitions = {} must be in [1, 100000]", self.repetitions));
        }
        for s in &self.scenarios {
            s.validate()?;
        }
        for b in &self.behaviours {
            b.policy()?;
        }
        if let Some(t) = self.max_time {
            if t.is_nan() || t <= 0.0 {
                return Err(format!("max_time = {t} must be > 0 s"));
            }
        }
        self.success.validate()?;
        self.vehicle.validate()?;
        if !(self.tdma.base_slot > 0.0 && self.tdma.rate5_slot > 0.0 && self.tdma.ack_extra >= 0.0) {
            return Err("tdma slot lengths must be > 0 s and ack_extra ≥ 0 s".into());
        }
        Ok(())
    }
}
