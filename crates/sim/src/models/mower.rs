//! A survey AUV's own lawnmower (`[[fleet.lawnmowers]]`, one per AUV when given): where its
//! block starts, which way its lanes run and to which side they step. Lane length, spacing and
//! count stay the fleet's. Without it, blocks sit side by side (`fleet.block_offset`); Nams's
//! two vehicles start at opposite corners of one square and fly it in opposite directions
//! (invented: docs/models.md#nams-scenarios).

use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// Which side of the lane heading the next lane lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    Left,
    Right,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MowerSpec {
    /// Start of the first lane, m.
    pub origin: (f64, f64),
    pub lane_heading_compass_deg: f64,
    pub turn: Turn,
}

impl MowerSpec {
    /// The signed lane spacing the core lawnmower takes (positive steps left of the heading).
    pub fn spacing(&self, lane_spacing: f64) -> f64 {
        match self.turn {
            Turn::Left => lane_spacing,
            Turn::Right => -lane_spacing,
        }
    }
}

impl CheckFields for MowerSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let fields = [
            ("origin[0]", self.origin.0),
            ("origin[1]", self.origin.1),
            ("lane_heading_compass_deg", self.lane_heading_compass_deg),
        ];
        for (field, v) in fields {
            p.finite(&format!("{prefix}{field}"), v);
        }
    }
}
