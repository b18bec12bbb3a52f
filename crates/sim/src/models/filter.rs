//! What the survey AUVs' filters assume (`[filter]`), apart from the truth (`[channel]`,
//! `[sensors]`): the state vector (`model`: the thesis's 5 states, or 7 with a water current) and
//! the coefficients of the nav crate's [`AuvParams`], in one table:
//! `[filter] model = { kind = "current" }`, `sigma_speed = 0.05`, … Absent keys keep the defaults.

use coopnav_core::validation::{CheckFields, Problems};
use coopnav_nav::{AuvModel, AuvParams};
use serde::{Deserialize, Serialize};

/// The `[filter]` table: [`AuvParams`]'s keys plus `model`.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSpec {
    pub model: AuvModel,
    pub params: AuvParams,
}

impl CheckFields for FilterSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        self.model.check_fields(&format!("{prefix}model."), p);
        self.params.check_fields(prefix, p);
    }
}

const MODEL_KEY: &str = "model";

impl Serialize for FilterSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::Error;
        let mut table = toml::Value::try_from(&self.params).map_err(S::Error::custom)?;
        let model = toml::Value::try_from(self.model).map_err(S::Error::custom)?;
        if let toml::Value::Table(t) = &mut table {
            t.insert(MODEL_KEY.into(), model);
        }
        table.serialize(s)
    }
}

impl<'de> Deserialize<'de> for FilterSpec {
    /// `model` is taken out of the table; the rest must be [`AuvParams`]'s keys (unknown keys are
    /// refused there, by name).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut value = toml::Value::deserialize(d)?;
        let model = match value.as_table_mut().and_then(|t| t.remove(MODEL_KEY)) {
            Some(m) => m.try_into().map_err(|e| D::Error::custom(format!("{MODEL_KEY}: {e}")))?,
            None => AuvModel::default(),
        };
        Ok(FilterSpec { model, params: value.try_into().map_err(D::Error::custom)? })
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
}
