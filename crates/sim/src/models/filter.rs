//! What the survey AUVs' filters assume (`[filter]`), apart from the truth (`[channel]`,
//! `[sensors]`): the state vector (`model`: the thesis's 5 states, or 7 with a water current) and
//! the coefficients of the nav crate's [`AuvParams`], in one table:
//! `[filter] model = { kind = "current" }`, `sigma_speed = 0.05`, … Absent keys keep the defaults.
//! `rate` says how often the filters run ([`FilterRate`]), `sound_speed` how they turn a travel
//! time into a range ([`FilterSoundSpeed`]).

use crate::models::channel::SoundSpeed;
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_nav::{AuvModel, AuvParams};
use serde::{Deserialize, Serialize};

/// The `[filter]` table: [`AuvParams`]'s keys plus `model`, `rate` and `sound_speed`.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSpec {
    pub model: AuvModel,
    pub params: AuvParams,
    pub rate: FilterRate,
    pub sound_speed: FilterSoundSpeed,
    /// Where the filters' stated current comes from ([`Adcp`]); absent (the default): the file's
    /// own `stated_current` or `model.mean`.
    pub adcp: Option<Adcp>,
}

/// The team states the water current to the survey AUVs' filters from an ADCP: the scenario's
/// true current (`fleet.current`) plus an error drawn N(0, `sd_m_s`²) on each axis, per run and
/// AUV. It becomes the 5-state filter's `stated_current` and the 7-state filter's `model.mean`
/// (whose `p0` should then be `sd_m_s`², the statement's variance). Invented
/// (docs/models.md#stated-current): the simulator stands for the ADCP, so that a filter's prior is
/// as wrong as it says, run by run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Adcp {
    /// SD of the statement's error on each axis (m/s, ≥ 0).
    pub sd_m_s: f64,
}

impl CheckFields for FilterSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        self.model.check_fields(&format!("{prefix}model."), p);
        self.params.check_fields(prefix, p);
        if let Some(a) = &self.adcp {
            p.non_negative(&format!("{prefix}{ADCP_KEY}.sd_m_s"), a.sd_m_s);
        }
        if matches!(self.model, AuvModel::Current(_)) && self.params.stated_current != [0.0, 0.0] {
            p.push(
                format!("{prefix}stated_current"),
                format!("{:?}", self.params.stated_current),
                "[0, 0] with model = { kind = \"current\" } (state its current as model.mean)",
            );
        }
        if let FilterSoundSpeed::Cast { points: Some(points) } = &self.sound_speed {
            SoundSpeed::Profile { points: points.clone() }.check_fields(&format!("{prefix}{SOUND_SPEED_KEY}."), p);
        }
    }
}

impl FilterSpec {
    /// How these filters convert travel times in water whose true sound speed is `channel` (a
    /// cast without points of its own is a cast of that water).
    pub fn range_speed(&self, channel: &SoundSpeed) -> RangeSpeed {
        let cast = match &self.sound_speed {
            FilterSoundSpeed::Constant {} => None,
            FilterSoundSpeed::Cast { points: None } => Some(channel.clone()),
            FilterSoundSpeed::Cast { points: Some(points) } => Some(SoundSpeed::Profile { points: points.clone() }),
        };
        RangeSpeed { nominal: self.params.range_noise.sound_speed, cast }
    }
}

/// The speed at which a survey AUV's filter converts a one-way travel time to a range:
/// `{ kind = "constant" }` (the default, the thesis's: every travel time at
/// `range_noise.sound_speed`) or `{ kind = "cast" }`, the harmonic-mean speed of a CTD cast between
/// the transponder's depth (as its packet reports it) and the AUV's own (its depth sensor), as a
/// field team converts with its cast. The cast is `channel.sound_speed`
/// unless `points = [[depth m, speed m/s], ...]` give one of its own (a real cast is not the
/// water: an older cast, another station). Either way the range's variance stays the travel
/// time's (`range_noise`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum FilterSoundSpeed {
    /// A struct variant, so that `{ kind = "constant", c = … }` is refused rather than ignored
    /// (the speed is `range_noise.sound_speed`).
    Constant {},
    Cast {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        points: Option<Vec<[f64; 2]>>,
    },
}

impl Default for FilterSoundSpeed {
    fn default() -> Self {
        FilterSoundSpeed::Constant {}
    }
}

/// [`FilterSoundSpeed`] resolved against the scenario's channel, built once per run.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeSpeed {
    nominal: f64,
    cast: Option<SoundSpeed>,
}

impl RangeSpeed {
    /// The speeds these filters convert at, as a profile (a constant one without a cast).
    pub fn conversion(&self) -> SoundSpeed {
        self.cast.clone().unwrap_or(SoundSpeed::Constant { c: self.nominal })
    }

    /// Speed (m/s) at which a travel time between a transponder at depth `z_transponder` and an
    /// AUV at depth `z_auv` becomes a range.
    pub fn between(&self, z_transponder: f64, z_auv: f64) -> f64 {
        self.cast.as_ref().map_or(self.nominal, |cast| cast.mean_between(z_transponder, z_auv))
    }
}

/// How often a survey AUV's filter predicts and takes its speed and compass readings:
/// `{ kind = "every_step" }` (the default: every truth step, the thesis's 10 Hz at dt = 0.1 s) or
/// `{ kind = "decimated", period_s = 0.5 }`, every `period_s` (a whole number of truth steps that
/// divides one second), predicting with the mean of the heading-rate readings since its last step
/// and taking one speed and one compass reading. Between its steps the controller steers on the
/// last estimate; range updates still predict to their own time. A speed option (the filters
/// are most of a run's time), not a thesis model: its accuracy against every step is in
/// docs/evaluation.md.
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

    /// Checks this rate at truth step `dt` under `prefix`: [`CheckFields`]'s shape with the step
    /// as one more argument.
    pub fn check_fields(&self, prefix: &str, dt: f64, p: &mut Problems) {
        let FilterRate::Decimated { period_s } = self else { return };
        let per_second = (1.0 / dt).round() as u64;
        if !whole_steps(*period_s, dt).is_some_and(|k| per_second % k == 0) {
            let allowed = format!("a whole number of truth steps (dt = {dt} s) that divides one second");
            p.push(format!("{prefix}rate.period_s"), period_s.to_string(), allowed);
        }
    }
}

/// `period_s` as a whole number (≥ 1) of steps of `dt`.
fn whole_steps(period_s: f64, dt: f64) -> Option<u64> {
    let k = (period_s / dt).round();
    (period_s.is_finite() && k >= 1.0 && (period_s / dt - k).abs() < 1e-6).then_some(k as u64)
}

const MODEL_KEY: &str = "model";
const RATE_KEY: &str = "rate";
const SOUND_SPEED_KEY: &str = "sound_speed";
const ADCP_KEY: &str = "adcp";

impl Serialize for FilterSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::Error;
        let mut table = toml::Value::try_from(&self.params).map_err(S::Error::custom)?;
        let model = toml::Value::try_from(self.model).map_err(S::Error::custom)?;
        if let toml::Value::Table(t) = &mut table {
            t.insert(MODEL_KEY.into(), model);
            // Written only when set, so the files and manifests of earlier runs stay as they were.
            if self.rate != FilterRate::EveryStep {
                t.insert(RATE_KEY.into(), toml::Value::try_from(self.rate).map_err(S::Error::custom)?);
            }
            if self.sound_speed != (FilterSoundSpeed::Constant {}) {
                let speed = toml::Value::try_from(&self.sound_speed).map_err(S::Error::custom)?;
                t.insert(SOUND_SPEED_KEY.into(), speed);
            }
            if let Some(adcp) = &self.adcp {
                t.insert(ADCP_KEY.into(), toml::Value::try_from(adcp).map_err(S::Error::custom)?);
            }
        }
        table.serialize(s)
    }
}

impl<'de> Deserialize<'de> for FilterSpec {
    /// `model`, `rate` and `sound_speed` are taken out of the table; the rest must be
    /// [`AuvParams`]'s keys (unknown keys are refused there, by name).
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
        let sound_speed = match take(SOUND_SPEED_KEY) {
            Some(s) => s.try_into().map_err(|e| D::Error::custom(format!("{SOUND_SPEED_KEY}: {e}")))?,
            None => FilterSoundSpeed::default(),
        };
        let adcp = match take(ADCP_KEY) {
            Some(a) => Some(a.try_into().map_err(|e| D::Error::custom(format!("{ADCP_KEY}: {e}")))?),
            None => None,
        };
        Ok(FilterSpec { model, params: value.try_into().map_err(D::Error::custom)?, rate, sound_speed, adcp })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::Vec3;
    use coopnav_nav::CurrentParams;

    #[test]
    fn a_cast_of_the_water_turns_a_travel_time_into_the_true_range_and_the_constant_speed_does_not() {
        let water = SoundSpeed::summer();
        let (transponder, auv) = (Vec3::new(0.0, 0.0, 2.0), Vec3::new(600.0, 300.0, 80.0));
        let truth = (auv - transponder).norm();
        let travel_time = water.travel_time(transponder, |_| auv);
        let error = |toml_text: &str| {
            let spec: FilterSpec = toml::from_str(toml_text).unwrap();
            spec.range_speed(&water).between(transponder.z, auv.z) * travel_time / truth - 1.0
        };
        assert!(error("sound_speed = { kind = \"cast\" }\n").abs() < 1e-9);
        // At 1500 m/s the range carries the scale error f = 1500 / c̄ − 1 (+0.3 % here).
        let f = 1500.0 / water.mean_between(2.0, 80.0) - 1.0;
        assert!(f > 2e-3, "{f}");
        assert!((error("") - f).abs() < 1e-9);
        assert!((error("sound_speed = { kind = \"constant\" }\n") - f).abs() < 1e-9);
        // A cast of its own, 2 m/s slower than the water everywhere: ranges about 0.13 % short.
        let slow = "sound_speed = { kind = \"cast\", points = [[0.0, 1508.0], [10.0, 1507.0], [30.0, 1490.0], [100.0, 1486.0]] }\n";
        assert!((-1.5e-3..-1.2e-3).contains(&error(slow)), "{}", error(slow));
    }

    #[test]
    fn the_sound_speed_key_is_read_written_only_when_set_and_its_mistakes_named() {
        let constant: FilterSpec = toml::from_str("sigma_speed = 0.2\n").unwrap();
        assert_eq!(constant.sound_speed, FilterSoundSpeed::Constant {});
        let written: toml::Table = toml::from_str(&toml::to_string(&constant).unwrap()).unwrap();
        assert!(!written.contains_key("sound_speed"), "written as before: {written}");
        for text in
            ["sound_speed = { kind = \"cast\" }\n", "sound_speed = { kind = \"cast\", points = [[0.0, 1500.0]] }\n"]
        {
            let spec: FilterSpec = toml::from_str(text).unwrap();
            let back: FilterSpec = toml::from_str(&toml::to_string(&spec).unwrap()).unwrap();
            assert_eq!(back, spec, "round trip of {text}");
        }
        for (text, named) in [
            ("sound_speed = { kind = \"cats\" }\n", "cats"),
            ("sound_speed = { kind = \"cast\", pionts = [[0.0, 1500.0]] }\n", "pionts"),
            ("sound_speed = { kind = \"constant\", c = 1490.0 }\n", "`c`"),
        ] {
            let e = toml::from_str::<FilterSpec>(text).unwrap_err().to_string();
            assert!(e.contains("sound_speed") && e.contains(named), "{text}: {e}");
        }
    }

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
        let fields = |rate: &FilterRate| {
            let mut p = Problems::new();
            rate.check_fields("filter.", 0.1, &mut p);
            p.finish().err().map(|e| e.fields()).unwrap_or_default()
        };
        assert!(fields(&spec.rate).is_empty());
        for bad in [0.25, 0.3, 0.05, 0.0, f64::NAN] {
            assert_eq!(fields(&FilterRate::Decimated { period_s: bad }), ["filter.rate.period_s"], "{bad}");
        }
    }

    #[test]
    fn the_adcp_key_reads_back_and_a_stated_current_beside_the_current_states_is_refused() {
        let plain: FilterSpec = toml::from_str("sigma_speed = 0.2\n").unwrap();
        assert!(plain.adcp.is_none() && !toml::to_string(&plain).unwrap().contains("adcp"));
        let spec: FilterSpec = toml::from_str("adcp = { sd_m_s = 0.005 }\n").unwrap();
        assert_eq!(spec.adcp, Some(Adcp { sd_m_s: 0.005 }));
        let back: FilterSpec = toml::from_str(&toml::to_string(&spec).unwrap()).unwrap();
        assert_eq!(back, spec, "round trip");
        let typo = toml::from_str::<FilterSpec>("adcp = { sd = 0.005 }\n").unwrap_err().to_string();
        assert!(typo.contains("adcp") && typo.contains("sd"), "{typo}");
        let both: FilterSpec =
            toml::from_str("model = { kind = \"current\" }\nstated_current = [0.1, 0.0]\nadcp = { sd_m_s = -1.0 }\n")
                .unwrap();
        let e = both.validate("filter.").unwrap_err().to_string();
        assert!(e.contains("filter.stated_current") && e.contains("filter.adcp.sd_m_s"), "{e}");
        let thesis: FilterSpec = toml::from_str("stated_current = [0.1, 0.0]\n").unwrap();
        assert!(thesis.validate("filter.").is_ok());
    }
}
