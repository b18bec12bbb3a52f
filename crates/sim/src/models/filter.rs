//! What the survey AUVs' filters assume (`[filter]`), apart from the truth (`[channel]`,
//! `[sensors]`): the state vector (`model`: the thesis's 5 states, or 7 with a water current) and
//! the coefficients of the nav crate's [`AuvParams`], in one table:
//! `[filter] model = { kind = "current" }`, `sigma_speed = 0.05`, … Absent keys keep the defaults.
//! `rate` says how often the filters run ([`FilterRate`]).

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_nav::{AuvModel, AuvParams};
use serde::{Deserialize, Serialize};

/// The `[filter]` table: [`AuvParams`]'s keys plus `model` and `rate`.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSpec {
    pub model: AuvModel,
    pub params: AuvParams,
    pub rate: FilterRate,
}

impl CheckFields for FilterSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        self.model.check_fields(&format!("{prefix}model."), p);
        self.params.check_fields(prefix, p);
    }
}

/// How often a survey AUV's filter predicts and takes its speed and compass readings:
/// `{ kind = "every_step" }` (the default: every truth step, the thesis's 10 Hz at dt = 0.1 s) or
/// `{ kind = "decimated", period_s = 0.5 }`, every `period_s` (a whole number of truth steps that
/// divides one second), predicting with the mean of the heading-rate readings since its last step
/// and taking one speed and one compass reading. Between its steps the controller steers on the
/// last estimate; range updates still predict to their own time. A speed option (issue 9: the
/// filters are most of a run's time), not a thesis model: its accuracy against every step is
/// measured in the issue-9 note.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum FilterRate {
    #[default]
    EveryStep,
    Decimated {
        period_s: f64,
    },
}

impl FilterRate {
    /// Truth steps of length `dt` per filter step (1 for a period that is not a whole number of
    /// steps: validation refuses it).
    pub fn steps(&self, dt: f64) -> u64 {
        match self {
            FilterRate::EveryStep => 1,
            FilterRate::Decimated { period_s } => whole_steps(*period_s, dt).unwrap_or(1),
        }
    }

    /// The problem with this rate at truth step `dt`, if any: (field, value, allowed).
    pub fn problem(&self, prefix: &str, dt: f64) -> Option<(String, String, String)> {
        let FilterRate::Decimated { period_s } = self else { return None };
        let per_second = (1.0 / dt).round() as u64;
        let ok = whole_steps(*period_s, dt).is_some_and(|k| per_second % k == 0);
        (!ok).then(|| {
            let allowed = format!("a whole number of truth steps (dt = {dt} s) that divides one second");
            (format!("{prefix}rate.period_s"), period_s.to_string(), allowed)
        })
    }
}

/// `period_s` as a whole number (≥ 1) of steps of `dt`.
fn whole_steps(period_s: f64, dt: f64) -> Option<u64> {
    let k = (period_s / dt).round();
    (period_s.is_finite() && k >= 1.0 && (period_s / dt - k).abs() < 1e-6).then_some(k as u64)
}

const MODEL_KEY: &str = "model";
const RATE_KEY: &str = "rate";

impl Serialize for FilterSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::Error;
        let mut table = toml::Value::try_from(&self.params).map_err(S::Error::custom)?;
        let model = toml::Value::try_from(self.model).map_err(S::Error::custom)?;
        if let toml::Value::Table(t) = &mut table {
            t.insert(MODEL_KEY.into(), model);
            // Written only when set, so the files and manifests of every-step runs stay as they were.
            if self.rate != FilterRate::EveryStep {
                t.insert(RATE_KEY.into(), toml::Value::try_from(self.rate).map_err(S::Error::custom)?);
            }
        }
        table.serialize(s)
    }
}

impl<'de> Deserialize<'de> for FilterSpec {
    /// `model` and `rate` are taken out of the table; the rest must be [`AuvParams`]'s keys
    /// (unknown keys are refused there, by name).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut value = toml::Value::deserialize(d)?;
        let mut take = |key: &str| value.as_table_mut().and_then(|t| t.remove(key));
        let model = match take(MODEL_KEY) {
            Some(m) => m.try_into().map_err(|e| D::Error::custom(format!("{MODEL_KEY}: {e}")))?,
            None => AuvModel::default(),
        };
        let rate = match take(RATE_KEY) {
            Some(r) => r.try_into().map_err(|e| D::Error::custom(format!("{RATE_KEY}: {e}")))?,
            None => FilterRate::default(),
        };
        Ok(FilterSpec { model, params: value.try_into().map_err(D::Error::custom)?, rate })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_nav::CurrentParams;

    #[test]
    fn the_model_key_selects_the_state_vector_and_the_rest_are_coefficients() {
        let spec: FilterSpec =
            toml::from_str("model = { kind = \"current\", p0 = 0.04 }\nsigma_speed = 0.2\n").unwrap();
        assert_eq!(spec.model, AuvModel::Current(CurrentParams { p0: 0.04, ..CurrentParams::default() }));
        assert_eq!(spec.params.sigma_speed, 0.2);
        let plain: FilterSpec = toml::from_str("sigma_speed = 0.2\n").unwrap();
        assert_eq!(plain.model, AuvModel::Thesis);
        let back: FilterSpec = toml::from_str(&toml::to_string(&spec).unwrap()).unwrap();
        assert_eq!(back, spec, "round trip");
        let typo = toml::from_str::<FilterSpec>("sigma_sped = 0.2\n").unwrap_err().to_string();
        assert!(typo.contains("sigma_sped"), "{typo}");
        let kind = toml::from_str::<FilterSpec>("model = { kind = \"curent\" }\n").unwrap_err().to_string();
        assert!(kind.contains("model") && kind.contains("curent"), "{kind}");
    }

    #[test]
    fn the_rate_key_is_read_written_only_when_set_and_checked_against_the_step() {
        let every: FilterSpec = toml::from_str("sigma_speed = 0.2\n").unwrap();
        assert_eq!(every.rate, FilterRate::EveryStep);
        assert!(!toml::to_string(&every).unwrap().contains("rate"), "an every-step table is written as before");
        let spec: FilterSpec = toml::from_str("rate = { kind = \"decimated\", period_s = 0.5 }\n").unwrap();
        assert_eq!(spec.rate, FilterRate::Decimated { period_s: 0.5 });
        let back: FilterSpec = toml::from_str(&toml::to_string(&spec).unwrap()).unwrap();
        assert_eq!(back, spec, "round trip");
        let typo = toml::from_str::<FilterSpec>("rate = { kind = \"decimated\", period = 0.5 }\n").unwrap_err();
        assert!(typo.to_string().contains("rate") && typo.to_string().contains("period"), "{typo}");
        assert_eq!((spec.rate.steps(0.1), FilterRate::EveryStep.steps(0.1)), (5, 1));
        assert!(spec.rate.problem("filter.", 0.1).is_none());
        for bad in [0.25, 0.3, 0.05, 0.0, f64::NAN] {
            let (field, ..) = FilterRate::Decimated { period_s: bad }.problem("filter.", 0.1).expect("refused");
            assert_eq!(field, "filter.rate.period_s", "{bad}");
        }
    }
}
