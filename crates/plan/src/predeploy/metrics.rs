//! Mission metrics (docs/models.md#hudson-metrics): per-step cost (unpenalised) and the penalised cost beside
//! it, average and total cost, max and RMS error (the worst AUV), CNA–AUV distances at decision
//! times, distance-limit violations, and how often the search was cut short.

use crate::{AuvError, CnaPose, Decision, DistanceLimits};
use coopnav_core::Vec3;
use serde::Serialize;

/// The state after one executed step (step 0 = the start).
#[derive(Debug, Clone)]
pub struct StepRecord {
    pub step: usize,
    pub t: f64,
    pub cna: CnaPose,
    pub auv: Vec<Vec3>,
    pub errors: Vec<AuvError>,
    /// 3-D CNA–AUV distances, m.
    pub distance: Vec<f64>,
    /// Σ_k cost term (eq. 3), m².
    pub cost: f64,
    /// The same with the primary distance penalty applied.
    pub penalised_cost: f64,
}

/// Whole-mission figures (summary.json).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Summary {
    pub steps: usize,
    pub n_auvs: usize,
    /// Mean of the per-step cost over executed steps, m².
    pub average_cost: f64,
    pub total_cost: f64,
    pub average_penalised_cost: f64,
    /// Max over t (including t = 0) and AUVs of √(σ²+ε²), m.
    pub max_error: f64,
    /// Max over AUVs of the RMS over t (including t = 0) of √(σ²+ε²), m.
    pub rms_error: f64,
    pub rms_error_per_auv: Vec<f64>,
    /// Distances over executed steps and AUVs, m.
    pub min_distance: f64,
    pub mean_distance: f64,
    pub max_distance: f64,
    /// Executed steps with some AUV closer than the minimum or farther than the maximum distance.
    pub too_close_steps: usize,
    pub too_far_steps: usize,
    /// Decisions whose search stopped short of the requested depth (deadline or end of data).
    pub truncated_decisions: usize,
}

impl Summary {
    pub fn from_steps(steps: &[StepRecord], decisions: &[Decision], limits: &DistanceLimits) -> Summary {
        let n = steps[0].errors.len();
        let executed = &steps[1..];
        let count = executed.len().max(1) as f64;
        let total_cost: f64 = executed.iter().map(|s| s.cost).sum();
        let rms: Vec<f64> = (0..n)
            .map(|k| {
                (steps.iter().map(|s| s.errors[k].sigma2 + s.errors[k].eps2).sum::<f64>() / steps.len() as f64).sqrt()
            })
            .collect();
        let all_d = || executed.iter().flat_map(|s| s.distance.iter().cloned());
        Summary {
            steps: executed.len(),
            n_auvs: n,
            average_cost: total_cost / count,
            total_cost,
            average_penalised_cost: executed.iter().map(|s| s.penalised_cost).sum::<f64>() / count,
            max_error: steps.iter().flat_map(|s| s.errors.iter().map(AuvError::total)).fold(0.0, f64::max),
            rms_error: rms.iter().cloned().fold(0.0, f64::max),
            rms_error_per_auv: rms,
            min_distance: all_d().fold(f64::INFINITY, f64::min),
            mean_distance: all_d().sum::<f64>() / (count * n as f64),
            max_distance: all_d().fold(0.0, f64::max),
            too_close_steps: executed.iter().filter(|s| s.distance.iter().any(|&d| d < limits.min)).count(),
            too_far_steps: executed.iter().filter(|s| s.distance.iter().any(|&d| d > limits.max)).count(),
            truncated_decisions: decisions.iter().filter(|d| d.levels_searched < d.levels_requested).count(),
        }
    }
}
