//! Coefficient tuning (Gill 2013, §2.3.3; docs/models.md#gill-tuning): a bounded Nelder–Mead
//! search (argmin) over a chosen
//! subset of the Table 2/3 coefficients of an engine scenario (survey AUV 0's filter, and its
//! filters of ship 0 and buoy 0), on the zone Monte Carlo's cost with fixed seeds (common random
//! numbers make the cost a deterministic function of the coefficients).

use crate::observe::zone::{zone_monte_carlo, ZoneError, ZoneSpec};
use crate::policy::PolicyError;
use crate::scenario::Scenario;
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use coopnav_core::validation::{InvalidFields, Problems};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A tunable coefficient (E and N share one value, as in Table 3). The first seven are the
/// thesis's tuned set (Tables 2–3); the rest are the coefficients it kept at unpublished MSBL
/// values (Gill 2013, §2.3.3; docs/models.md#gill-coefficients), so a user can re-derive them the same way.
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
    /// and for the range noise 10 m / 1500 m/s, the largest outlier (invented: docs/models.md#gill-tuning).
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
    /// Whose filter holds it: the survey AUV's own, or its filter of buoy 0 or ship 0.
    fn vehicle(self) -> &'static str {
        match self {
            Coefficient::BuoyPEn
            | Coefficient::BuoyPSpeed
            | Coefficient::BuoyPHeading
            | Coefficient::BuoyQEn
            | Coefficient::BuoyQSpeed
            | Coefficient::BuoyQHeading => "buoys[0]",
            Coefficient::ShipQEn | Coefficient::ShipQSpeed | Coefficient::ShipQHeading => "ships[0]",
            _ => "filter",
        }
    }
    /// The coefficient's slot in a scenario's filters, and its E/N partner that shares the value
    /// (Table 3 ties E and N); None when the scenario lacks the vehicle.
    fn slots(self, sc: &mut Scenario) -> Option<(&mut f64, Option<&mut f64>)> {
        let auv = &mut sc.filter.params;
        Some(match self {
            Coefficient::AuvQEn => east_north(&mut auv.q),
            Coefficient::AuvQSpeed => (&mut auv.q[2], None),
            Coefficient::AuvQHeading => (&mut auv.q[3], None),
            Coefficient::AuvQBias => (&mut auv.q[4], None),
            Coefficient::AuvRangeSigmaTime => (&mut auv.range_noise.sigma_time, None),
            Coefficient::AuvSigmaSpeed => (&mut auv.sigma_speed, None),
            Coefficient::AuvSigmaHeading => (&mut auv.sigma_heading, None),
            Coefficient::BuoyPEn => east_north(&mut sc.buoys.first_mut()?.filter.p0),
            Coefficient::BuoyPSpeed => (&mut sc.buoys.first_mut()?.filter.p0[2], None),
            Coefficient::BuoyPHeading => (&mut sc.buoys.first_mut()?.filter.p0[3], None),
            Coefficient::BuoyQEn => east_north(&mut sc.buoys.first_mut()?.filter.q),
            Coefficient::BuoyQSpeed => (&mut sc.buoys.first_mut()?.filter.q[2], None),
            Coefficient::BuoyQHeading => (&mut sc.buoys.first_mut()?.filter.q[3], None),
            Coefficient::ShipQEn => east_north(&mut sc.ships.first_mut()?.filter.q),
            Coefficient::ShipQSpeed => (&mut sc.ships.first_mut()?.filter.q[2], None),
            Coefficient::ShipQHeading => (&mut sc.ships.first_mut()?.filter.q[3], None),
        })
    }
    /// Reads through the same map as `set` (on a copy), so there is one map to keep right; None
    /// when the scenario lacks the vehicle.
    pub fn get(self, sc: &Scenario) -> Option<f64> {
        self.slots(&mut sc.clone()).map(|(v, _)| *v)
    }
    /// Sets it (and its north twin); false when the scenario lacks the vehicle.
    pub fn set(self, sc: &mut Scenario, v: f64) -> bool {
        let Some((slot, twin)) = self.slots(sc) else { return false };
        *slot = v;
        if let Some(n) = twin {
            *n = v;
        }
        true
    }
}

/// The east entry of a diagonal and its north partner after it.
fn east_north(v: &mut [f64]) -> (&mut f64, Option<&mut f64>) {
    let (east, rest) = v.split_at_mut(1);
    (&mut east[0], rest.first_mut())
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
    /// against the work limits by `coopnav_sim::batch::work`).
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
    #[error("tune: {name} is a coefficient of {vehicle}, which the scenario does not have")]
    NoVehicle { name: String, vehicle: &'static str },
    #[error(transparent)]
    Policy(#[from] PolicyError),
    #[error(transparent)]
    Zone(#[from] ZoneError),
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
    zone: ZoneSpec,
}

impl Problem<'_> {
    /// Unit-box coordinates → coefficient values, clamped to [tiny, upper]; the distance
    /// outside the box is returned for the penalty. Every coefficient's vehicle was checked.
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
    fn evaluate(&self, u: &[f64]) -> Result<f64, TuneError> {
        let (sc, outside) = self.scenario(u);
        let summary = zone_monte_carlo(&sc, self.zone, self.spec.runs, self.spec.seed)?.summary(self.spec.seed)?;
        let cost = match self.spec.objective {
            Objective::AuvZone => summary.zone_error.mean,
            Objective::BuoyMission => summary.buoy_error.map_or(f64::INFINITY, |s| s.mean),
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

/// Tunes the chosen coefficients of `base` (a validated scenario), starting from their current
/// values, each cost the zone Monte Carlo in `zone`.
pub fn tune(base: &Scenario, zone: ZoneSpec, spec: &TuneSpec) -> Result<TuneResult, TuneError> {
    spec.validate()?;
    let start: Vec<f64> = spec
        .coefficients
        .iter()
        .map(|c| {
            let v = c.get(base).ok_or(TuneError::NoVehicle { name: format!("{c:?}"), vehicle: c.vehicle() })?;
            if (0.0..=c.upper()).contains(&v) {
                Ok(v / c.upper())
            } else {
                Err(TuneError::StartOutOfBounds { name: format!("{c:?}"), value: v, upper: c.upper() })
            }
        })
        .collect::<Result<_, _>>()?;
    let problem = Problem { base, spec, zone };
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
    let problem = Problem { base, spec, zone };
    let (best_sc, _) = problem.scenario(&best);
    Ok(TuneResult {
        coefficients: spec.coefficients.iter().filter_map(|c| Some((*c, c.get(&best_sc)?))).collect(),
        start_cost,
        best_cost: state.get_best_cost(),
        iterations: state.get_iter(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::hbl::table5_scenario;
    use coopnav_nav::cycle::Configuration;
    use std::path::Path;

    fn table5() -> Scenario {
        table5_scenario(Configuration::HblTwo).unwrap()
    }

    #[test]
    fn tuning_never_worsens_the_fixed_seed_cost() {
        let mut base = table5();
        // Start from a deliberately poor Q^A so there is something to find.
        assert!(Coefficient::AuvQEn.set(&mut base, 2.5));
        let spec = TuneSpec {
            coefficients: vec![Coefficient::AuvQEn],
            objective: Objective::AuvZone,
            runs: 8,
            max_iters: 6,
            seed: 3,
        };
        let r = tune(&base, ZoneSpec::table5(), &spec).unwrap();
        assert!(r.best_cost <= r.start_cost + 1e-12, "{r:?}");
        let v = r.coefficients[0].1;
        assert!(v > 0.0 && v <= 3.0);
        // The poor start is left: the value moves and the cost falls.
        assert!(r.iterations > 0 && v != 2.5 && r.best_cost < r.start_cost, "{r:?}");
        // The cost reported is the cost of the value reported: the same Monte Carlo (same runs and
        // seed) at that value, and at the start.
        let mean_error = |q: f64| {
            let mut sc = base.clone();
            assert!(Coefficient::AuvQEn.set(&mut sc, q));
            zone_monte_carlo(&sc, ZoneSpec::table5(), spec.runs, spec.seed)
                .unwrap()
                .summary(spec.seed)
                .unwrap()
                .zone_error
                .mean
        };
        assert_eq!(mean_error(2.5), r.start_cost, "{r:?}");
        assert_eq!(mean_error(v), r.best_cost, "{r:?}");
    }

    #[test]
    fn every_coefficient_is_settable_and_starts_inside_its_bounds() {
        let base = table5();
        for c in Coefficient::ALL {
            let v = c.get(&base).unwrap();
            assert!((0.0..=c.upper()).contains(&v), "{c:?} default {v} outside [0, {}]", c.upper());
            let mut sc = base.clone();
            assert!(c.set(&mut sc, 0.5 * c.upper()));
            assert_eq!(c.get(&sc), Some(0.5 * c.upper()), "{c:?}");
            let changed = Coefficient::ALL.iter().filter(|o| o.get(&sc) != o.get(&base)).count();
            assert_eq!(changed, 1, "{c:?} moved another coefficient");
            sc.validate(Path::new("tuned.toml")).unwrap();
        }
        let mut sc = base.clone();
        Coefficient::ShipQEn.set(&mut sc, 2.0);
        assert_eq!((sc.ships[0].filter.q[0], sc.ships[0].filter.q[1]), (2.0, 2.0));
    }

    #[test]
    fn bad_specs_are_refused() {
        let base = table5();
        let spec = TuneSpec { coefficients: vec![], objective: Objective::AuvZone, runs: 1, max_iters: 0, seed: 1 };
        let e = tune(&base, ZoneSpec::table5(), &spec).unwrap_err().to_string();
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
        assert!(matches!(tune(&off, ZoneSpec::table5(), &spec), Err(TuneError::StartOutOfBounds { .. })));
        let mut no_buoy = base.clone();
        no_buoy.buoys.clear();
        let e = tune(&no_buoy, ZoneSpec::table5(), &spec).unwrap_err().to_string();
        assert!(e.contains("BuoyPEn") && e.contains("buoys[0]"), "{e}");
    }
}
