//! The `[comms] tl` table: which transmission-loss model a scenario names, with its parameters
//! and their validation (the provider a run builds from it, over the scenario's sea, is in
//! [`super::tl`]).

use coopnav_acomms::tl::analytic::Thorp;
use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TlModel {
    /// k·10·log10(d) + Thorp absorption (`k`, `freq_hz`).
    Analytic(Thorp),
    /// A BELLHOP run for every arrival, at the true geometry.
    Bellhop,
    /// Cached BELLHOP fields on a lattice of source positions.
    BellhopGrid(GridModel),
}

impl Default for TlModel {
    fn default() -> Self {
        TlModel::Analytic(Thorp::default())
    }
}

/// The `bellhop_grid` layout. Invented defaults, measured against direct runs (acomms
/// `tl::cached` tests): they keep the grid within 1 dB of a direct run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridModel {
    /// Bearings per anchor, evenly spaced.
    pub bearings: usize,
    pub range_step_m: f64,
    pub depth_step_m: f64,
    /// Distance between neighbouring source anchors.
    pub anchor_spacing_m: f64,
    /// The lattice covers the survey blocks and the CNA's start, widened by this much.
    pub margin_m: f64,
    /// Spacing of the source layers over a depth span a transmitter moves through (an
    /// altitude-keeping survey AUV, an AUV CNA). Invented; measured (acomms `tl::cached` tests):
    /// a source 4 m from the layers either side of it, 8 m apart, read 0.6–2.0 dB off a direct
    /// run.
    pub source_depth_step_m: f64,
    /// Directory of the disk cache (default: `coopnav-tl` in the system temporary directory).
    pub cache_dir: Option<PathBuf>,
}

impl Default for GridModel {
    fn default() -> Self {
        GridModel {
            bearings: 16,
            range_step_m: 10.0,
            depth_step_m: 2.0,
            anchor_spacing_m: 500.0,
            margin_m: 500.0,
            source_depth_step_m: 10.0,
            cache_dir: None,
        }
    }
}

/// Largest number of BELLHOP fields a grid may ask for (anchors × bearings): about an hour of
/// one core at a kilometre's range.
pub const MAX_GRID_FIELDS: usize = 20_000;

impl TlModel {
    /// What the CNA's planner assumes: the analytic model itself, or the default analytic model
    /// for the BELLHOP kinds.
    pub fn assumed(&self) -> Thorp {
        match self {
            TlModel::Analytic(t) => *t,
            TlModel::Bellhop | TlModel::BellhopGrid(_) => Thorp::default(),
        }
    }
}

impl CheckFields for TlModel {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let mut need =
            |field: &str, v: f64, ok: bool, allowed: &str| p.require(&format!("{prefix}{field}"), v, ok, allowed);
        match self {
            TlModel::Analytic(t) => {
                need("k", t.k, t.k > 0.0, "a finite number > 0");
                need("freq_hz", t.freq_hz, t.freq_hz > 0.0, "a finite number > 0");
            }
            TlModel::Bellhop => {}
            TlModel::BellhopGrid(g) => {
                need("bearings", g.bearings as f64, (1..=360).contains(&g.bearings), "1..=360");
                need("range_step_m", g.range_step_m, g.range_step_m >= 1.0, ">= 1 m");
                need("depth_step_m", g.depth_step_m, g.depth_step_m >= 0.5, ">= 0.5 m");
                need("anchor_spacing_m", g.anchor_spacing_m, g.anchor_spacing_m >= 50.0, ">= 50 m");
                need("margin_m", g.margin_m, g.margin_m >= 0.0, ">= 0 m");
                need("source_depth_step_m", g.source_depth_step_m, g.source_depth_step_m >= 0.5, ">= 0.5 m");
            }
        }
    }
}

/// A `tl` table without `kind` is the analytic model.
pub fn kind_defaults_to_analytic<'de, D: serde::Deserializer<'de>>(d: D) -> Result<TlModel, D::Error> {
    use serde::de::Error;
    let mut value = toml::Value::deserialize(d)?;
    if let Some(t) = value.as_table_mut().filter(|t| !t.contains_key("kind")) {
        t.insert("kind".into(), toml::Value::String("analytic".into()));
    }
    value.try_into().map_err(D::Error::custom)
}
