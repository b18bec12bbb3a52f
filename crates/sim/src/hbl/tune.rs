//! Coefficient tuning (digest §5.7 item 3): a bounded Nelder–Mead search (argmin) over a chosen
//! subset of the Table 2/3 coefficients, on the Monte Carlo cost with fixed seeds (common random
//! numbers make the cost a deterministic function of the coefficients).

use super::config::Scenario;
use super::mc::{monte_carlo, McError};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use coopnav_core::validation::{InvalidFields, Problems};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A tunable coefficient (E and N share one value, as in Table 3). The first seven are the
/// thesis's tuned set (Tables 2–3); the rest are the coefficients it kept at unpublished MSBL
/// values (digest §5.7 item 3, §10 A2), so a user can re-derive them the same way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coefficient {
    AuvQEn,
    BuoyPEn,
    BuoyPSpeed,
    BuoyPHeading,
    BuoyQEn,
    BuoyQSpeed,
    BuoyQHeading,
    AuvQSpeed,
    AuvQHeading,
    AuvQBias,
    /// Timing SD of the range noise (s): c·σ_τ is the range SD at zero range.
    AuvRangeSigmaTime,
    AuvSigmaSpeed,
    AuvSigmaHeading,
    ShipQEn,
    ShipQSpeed,
    ShipQHeading,
}

impl Coefficient {
    pub const ALL: [Coefficient; 16] = [
        Coefficient::AuvQEn,
        Coefficient::BuoyPEn,
        Coefficient::BuoyPSpeed,
        Coefficient::BuoyPHeading,
        Coefficient::BuoyQEn,
        Coefficient::BuoyQSpeed,
        Coefficient::BuoyQHeading,
        Coefficient::AuvQSpeed,
        Coefficient::AuvQHeading,
        Coefficient::AuvQBias,
        Coefficient::AuvRangeSigmaTime,
        Coefficient::AuvSigmaSpeed,
        Coefficient::AuvSigmaHeading,
        Coefficient::ShipQEn,
        Coefficient::ShipQSpeed,
        Coefficient::ShipQHeading,
    ];

    /// Upper bound (the lower bound is 0). Table 2 for the thesis's set; for the others the Table 2
    /// bound of the same kind of quantity (speed 5 (m/s)², heading 4π² rad², surface E/N 10 m²),
    /// and for the range noise 10 m / 1500 m/s, the largest outlier (invented: digest §10 A2).
    pub fn upper(self) -> f64 {
        let four_pi2 = 4.0 * std::f64::consts::PI.powi(2);
        match self {
            Coefficient::AuvQEn => 3.0,
            Coefficient::BuoyPEn => 30.0,
            Coefficient::BuoyPSpeed | Coefficient::BuoyQSpeed | Coefficient::AuvQSpeed | Coefficient::ShipQSpeed => 5.0,
            Coefficient::BuoyPHeading
            | Coefficient::BuoyQHeading
            | Coefficient::AuvQHeading
            | Coefficient::AuvQBias
            | Coefficient::ShipQHeading => four_pi2,
            Coefficient::BuoyQEn | Coefficient::ShipQEn => 10.0,
            Coefficient::AuvRangeSigmaTime => 10.0 / 1500.0,
            // SDs: the square roots of the speed and heading variance bounds.
            Coefficient::AuvSigmaSpeed => 5f64.sqrt(),
            Coefficient::AuvSigmaHeading => 2.0 * std::f64::consts::PI,
        }
    }
    /// The coefficient's slot in a scenario's filters.
    fn slot(self, sc: &mut Scenario) -> &mut f64 {
        let f = &mut sc.filters;
        match self {
            Coefficient::AuvQEn => &mut f.auv.q[0],
            Coefficient::BuoyPEn => &mut f.buoy.p0[0],
            Coefficient::BuoyPSpeed => &mut f.buoy.p0[2],
            Coefficient::BuoyPHeading => &mut f.buoy.p0[3],
            Coefficient::BuoyQEn => &mut f.buoy.q[0],
            Coefficient::BuoyQSpeed => &mut f.buoy.q[2],
            Coefficient::BuoyQHeading => &mut f.buoy.q[3],
            Coefficient::AuvQSpeed => &mut f.auv.q[2],
            Coefficient::AuvQHeading => &mut f.auv.q[3],
            Coefficient::AuvQBias => &mut f.auv.q[4],
            Coefficient::AuvRangeSigmaTime => &mut f.auv.range_noise.sigma_time,
            Coefficient::AuvSigmaSpeed => &mut f.auv.sigma_speed,
            Coefficient::AuvSigmaHeading => &mut f.auv.sigma_heading,
            Coefficient::ShipQEn => &mut f.ship.q[0],
            Coefficient::ShipQSpeed => &mut f.ship.q[2],
            Coefficient::ShipQHeading => &mut f.ship.q[3],
        }
    }
    /// The E/N partner that shares the value (Table 3 ties E and N).
    fn north_twin(self, sc: &mut Scenario) -> Option<&mut f64> {
        let f = &mut sc.filters;
        match self {
            Coefficient::AuvQEn => Some(&mut f.auv.q[1]),
            Coefficient::BuoyPEn => Some(&mut f.buoy.p0[1]),
            Coefficient::BuoyQEn => Some(&mut f.buoy.q[1]),
            Coefficient::ShipQEn => Some(&mut f.ship.q[1]),
            _ => None,
        }
    }
    /// Reads through the same map as `set` (on a copy), so there is one map to keep right.
    pub fn get(self, sc: &Scenario) -> f64 {
        *self.slot(&mut sc.clone())
    }
    pub fn set(self, sc: &mut Scenario, v: f64) {
        *self.slot(sc) = v;
        if let Some(n) = self.north_twin(sc) {
            *n = v;
        }
    }
}

/// What the Monte Carlo cost measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Mean AUV zone error (the cost for Q^A).
    AuvZone,
    /// Mean buoy-filter error over the mission (the cost for the buoy coefficients).
    BuoyMission,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TuneSpec {
    pub coefficients: Vec<Coefficient>,
    pub objective: Objective,
    #[serde(default = "default_runs")]
    pub runs: usize,
    #[serde(default = "default_iters")]
    pub max_iters: u64,
    #[serde(default = "default_seed")]
    pub seed: u64,
}

impl TuneSpec {
    /// Checks every field and reports every bad one at once (the Monte Carlo's size is checked
    /// against the work limits by `coopnav_sim::work`).
    pub fn validate(&self) -> Result<(), InvalidFields> {
        let mut p = Problems::new();
        if self.coefficients.is_empty() {
            p.push("coefficients", "[]", "at least one of auv_q_en, buoy_p_en, buoy_p_speed, buoy_p_heading, buoy_q_en, buoy_q_speed, buoy_q_heading, auv_q_speed, auv_q_heading, auv_q_bias, auv_range_sigma_time, auv_sigma_speed, auv_sigma_heading, ship_q_en, ship_q_speed, ship_q_heading");
        }
        if self.runs < 2 {
            p.push("runs", self.runs.to_string(), "≥ 2 (each cost is a Monte Carlo)");
        }
        if self.max_iters == 0 {
            p.push("max_iters", "0", "≥ 1");
        }
        p.finish()
    }
}

fn default_runs() -> usize {
    50
}
fn default_iters() -> u64 {
    40
}
fn default_seed() -> u64 {
    1
}

#[derive(Debug, Error)]
pub enum TuneError {
    #[error("tune spec: {0}")]
    Fields(#[from] InvalidFields),
    #[error("tune: {name} starts at {value}, outside its bounds [0, {upper}] (Table 2)")]
    StartOutOfBounds { name: String, value: f64, upper: f64 },
    #[error(transparent)]
    Mc(#[from] McError),
    #[error("tune: the optimiser failed: {0}")]
    Optimiser(String),
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TuneResult {
    pub coefficients: Vec<(Coefficient, f64)>,
    pub start_cost: f64,
    pub best_cost: f64,
    pub iterations: u64,
}

struct Problem<'a> {
    base: &'a Scenario,
    spec: &'a TuneSpec,
}

impl Problem<'_> {
    /// Unit-box coordinates → coefficient values, clamped to [tiny, upper]; the distance
    /// outside the box is returned for the penalty.
    fn scenario(&self, u: &[f64]) -> (Scenario, f64) {
        let mut sc = self.base.clone();
        let mut outside = 0.0;
        for (c, &ui) in self.spec.coefficients.iter().zip(u) {
            let clamped = ui.clamp(1e-9, 1.0);
            outside += (ui - clamped).abs();
            c.set(&mut sc, clamped * c.upper());
        }
        (sc, outside)
    }
    fn evaluate(&self, u: &[f64]) -> Result<f64, McError> {
        let (sc, outside) = self.scenario(u);
        let r = monte_carlo(&sc, self.spec.runs, self.spec.seed, &|_| {})?;
        let cost = match self.spec.objective {
            Objective::AuvZone => r.summary.zone_error.mean,
            Objective::BuoyMission => r.summary.buoy_error.map_or(f64::INFINITY, |s| s.mean),
        };
        Ok(cost + 10.0 * outside)
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.evaluate(u)?)
    }
}

/// Tunes the chosen coefficients of `base`, starting from their current values.
pub fn tune(base: &Scenario, spec: &TuneSpec) -> Result<TuneResult, TuneError> {
    spec.validate()?;
    base.validate().map_err(McError::from)?;
    let start: Vec<f64> = spec
        .coefficients
        .iter()
        .map(|c| {
            let v = c.get(base);
            if (0.0..=c.upper()).contains(&v) {
                Ok(v / c.upper())
            } else {
                Err(TuneError::StartOutOfBounds { name: format!("{c:?}"), value: v, upper: c.upper() })
            }
        })
        .collect::<Result<_, _>>()?;
    let problem = Problem { base, spec };
    let start_cost = problem.evaluate(&start)?;
    // Initial simplex: the start and one vertex per coordinate, moved 20 % of the box inwards.
    let mut simplex = vec![start.clone()];
    for i in 0..start.len() {
        let mut v = start.clone();
        v[i] = if v[i] > 0.5 { v[i] - 0.2 } else { v[i] + 0.2 };
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex).with_sd_tolerance(1e-4).map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(spec.max_iters))
        .run()
        .map_err(|e| TuneError::Optimiser(e.to_string()))?;
    let state = res.state();
    let best = state.get_best_param().cloned().unwrap_or(start);
    let problem = Problem { base, spec };
    let (best_sc, _) = problem.scenario(&best);
    Ok(TuneResult {
        coefficients: spec.coefficients.iter().map(|c| (*c, c.get(&best_sc))).collect(),
        start_cost,
        best_cost: state.get_best_cost(),
        iterations: state.get_iter(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_never_worsens_the_fixed_seed_cost() {
        let mut base = Scenario::default();
        // Start from a deliberately poor Q^A so there is something to find.
        Coefficient::AuvQEn.set(&mut base, 2.5);
        let spec = TuneSpec {
            coefficients: vec![Coefficient::AuvQEn],
            objective: Objective::AuvZone,
            runs: 8,
            max_iters: 6,
            seed: 3,
        };
        let r = tune(&base, &spec).unwrap();
        assert!(r.best_cost <= r.start_cost + 1e-12, "{r:?}");
        let v = r.coefficients[0].1;
        assert!(v > 0.0 && v <= 3.0);
    }

    #[test]
    fn every_coefficient_is_settable_and_starts_inside_its_bounds() {
        let base = Scenario::default();
        for c in Coefficient::ALL {
            let v = c.get(&base);
            assert!((0.0..=c.upper()).contains(&v), "{c:?} default {v} outside [0, {}]", c.upper());
            let mut sc = base.clone();
            c.set(&mut sc, 0.5 * c.upper());
            assert_eq!(c.get(&sc), 0.5 * c.upper(), "{c:?}");
            let changed = Coefficient::ALL.iter().filter(|o| o.get(&sc) != o.get(&base)).count();
            assert_eq!(changed, 1, "{c:?} moved another coefficient");
            sc.validate().unwrap();
        }
        let mut sc = base.clone();
        Coefficient::ShipQEn.set(&mut sc, 2.0);
        assert_eq!((sc.filters.ship.q[0], sc.filters.ship.q[1]), (2.0, 2.0));
    }

    #[test]
    fn bad_specs_are_refused() {
        let base = Scenario::default();
        let spec = TuneSpec { coefficients: vec![], objective: Objective::AuvZone, runs: 1, max_iters: 0, seed: 1 };
        let e = tune(&base, &spec).unwrap_err().to_string();
        for field in ["coefficients = []", "runs = 1", "max_iters = 0"] {
            assert!(e.contains(&format!("field {field}: allowed")), "{field} not named in: {e}");
        }
        let mut off = base.clone();
        Coefficient::BuoyPEn.set(&mut off, 85.0);
        let spec = TuneSpec {
            coefficients: vec![Coefficient::BuoyPEn],
            objective: Objective::BuoyMission,
            runs: 4,
            max_iters: 2,
            seed: 1,
        };
        assert!(matches!(tune(&off, &spec), Err(TuneError::StartOutOfBounds { .. })));
    }
}
