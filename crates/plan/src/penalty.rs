//! Distance penalties (Hudson 2012, Sec. 3.2, eqs. 4–12; formulas lost, reconstructed:
//! docs/models.md#hudson-penalties).
//!
//! A violation is measured on the worst AUV: too close v_TC = d_min − min_k d_k, too far
//! v_TF = max_k d_k − d_max (3-D distances). "Too close" wins when both apply. Each penalty is one
//! named type behind [`Penalty`]; the generic family is [`ScaledViolation`], per side
//! `C' = a·C + m·C·v^p + b·v^p`, which holds every Table 5.2 variant as a preset.
//! Every penalty keeps C' ≥ C (checked by `check_fields`), which the branch-and-bound bound relies on.

use coopnav_core::validation::{CheckFields, Problems};
use serde::{Deserialize, Serialize};

/// How far the worst AUVs are outside the distance limits (metres, ≥ 0).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Violation {
    pub too_close: f64,
    pub too_far: f64,
}

impl Violation {
    pub fn any(&self) -> bool {
        self.too_close > 0.0 || self.too_far > 0.0
    }
}

/// A distance penalty: turns a raw cost and a violation into a penalised cost ≥ the raw cost.
pub trait Penalty {
    fn apply(&self, cost: f64, v: &Violation) -> f64;
}

/// No penalty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoPenalty {}

impl Penalty for NoPenalty {
    fn apply(&self, cost: f64, _: &Violation) -> f64 {
        cost
    }
}

/// Eq. (11): the look-ahead penalty that doubles the cost of any option too close to or too far
/// from any AUV.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Doubling {}

impl Penalty for Doubling {
    fn apply(&self, cost: f64, v: &Violation) -> f64 {
        if v.any() {
            2.0 * cost
        } else {
            cost
        }
    }
}

/// One side of the family: C' = a·C + m·C·v^p + b·v^p.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideTerm {
    /// a (≥ 1).
    pub cost_scale: f64,
    /// m (≥ 0): cost-proportional violation weight.
    pub cost_violation: f64,
    /// b (≥ 0): absolute violation weight, m² per m^p.
    pub violation: f64,
    /// p (≥ 1).
    pub power: f64,
}

impl SideTerm {
    fn apply(&self, cost: f64, v: f64) -> f64 {
        let vp = if self.power == 1.0 { v } else { v.powf(self.power) };
        self.cost_scale * cost + (self.cost_violation * cost + self.violation) * vp
    }
}

/// A penalty may never lower a cost, hence the lower limits.
impl CheckFields for SideTerm {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.check(&format!("{prefix}cost_scale"), self.cost_scale, |v| v >= 1.0, "a finite number >= 1");
        p.non_negative(&format!("{prefix}cost_violation"), self.cost_violation);
        p.non_negative(&format!("{prefix}violation"), self.violation);
        p.check(&format!("{prefix}power"), self.power, |v| v >= 1.0, "a finite number >= 1");
    }
}

/// The generic family, one [`SideTerm`] per side; "too close" wins when both apply.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScaledViolation {
    pub too_close: SideTerm,
    pub too_far: SideTerm,
}

impl Penalty for ScaledViolation {
    fn apply(&self, cost: f64, v: &Violation) -> f64 {
        if v.too_close > 0.0 {
            self.too_close.apply(cost, v.too_close)
        } else if v.too_far > 0.0 {
            self.too_far.apply(cost, v.too_far)
        } else {
            cost
        }
    }
}

/// Any penalty, as configured in a scenario file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PenaltyFn {
    // Empty struct variants, so `deny_unknown_fields` also rejects stray keys here.
    None {},
    Doubling {},
    Scaled { too_close: SideTerm, too_far: SideTerm },
}

impl Penalty for PenaltyFn {
    #[inline]
    fn apply(&self, cost: f64, v: &Violation) -> f64 {
        match *self {
            PenaltyFn::None {} => NoPenalty {}.apply(cost, v),
            PenaltyFn::Doubling {} => Doubling {}.apply(cost, v),
            PenaltyFn::Scaled { too_close, too_far } => ScaledViolation { too_close, too_far }.apply(cost, v),
        }
    }
}

impl CheckFields for PenaltyFn {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let PenaltyFn::Scaled { too_close, too_far } = self {
            too_close.check_fields(&format!("{prefix}too_close."), p);
            too_far.check_fields(&format!("{prefix}too_far."), p);
        }
    }
}

impl CheckFields for PenaltyPair {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        self.primary.check_fields(&format!("{prefix}primary."), p);
        self.look_ahead.check_fields(&format!("{prefix}look_ahead."), p);
    }
}

/// The penalty at level 0 (primary) and at levels ≥ 1 (look-ahead), docs/models.md#hudson-penalties.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltyPair {
    pub primary: PenaltyFn,
    pub look_ahead: PenaltyFn,
}

/// Table 5.2's cases. Every preset is a reconstruction (docs/models.md#hudson-penalties): only the failure-point
/// ratios survive — Orig. 2:1 (eq. 13), Orig.² √2:1, Orig.³ ∛2:1, 5×Cost 12.5:1 at zero cost,
/// 5×Cost² 3.5:1, 5×Cost³ 2.3:1. The "New" look-ahead penalty (12) is invented: 2·C + v_TC³ or
/// 2·C + v_TF² (different powers per side, as the thesis says).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PenaltyCase {
    #[serde(rename = "1")]
    C1,
    #[serde(rename = "2a")]
    C2a,
    #[serde(rename = "2")]
    C2,
    #[serde(rename = "3")]
    C3,
    #[serde(rename = "4")]
    C4,
    #[serde(rename = "5")]
    C5,
    #[serde(rename = "6")]
    C6,
    #[serde(rename = "7")]
    C7,
    #[serde(rename = "8")]
    C8,
    #[serde(rename = "9")]
    C9,
    #[serde(rename = "10")]
    C10,
    #[serde(rename = "11")]
    C11,
    #[serde(rename = "12")]
    C12,
    #[serde(rename = "13")]
    C13,
    #[serde(rename = "2b")]
    C2b,
    #[serde(rename = "3a")]
    C3a,
    #[serde(rename = "4a")]
    C4a,
    #[serde(rename = "6a")]
    C6a,
    #[serde(rename = "8a")]
    C8a,
    #[serde(rename = "10a")]
    C10a,
    #[serde(rename = "12a")]
    C12a,
}

/// Primary-penalty shapes of Table 5.2.
#[derive(Clone, Copy)]
enum Primary {
    None,
    /// (4)/(5), (6), (7): C·(1 + 2v^p) too close, C·(1 + v^p) too far.
    Orig(f64),
    /// (8), (9), (10): 5·C + 25·v^p too close, C + 2·v^p too far.
    FiveCost(f64),
}

/// Look-ahead shapes of Table 5.2.
#[derive(Clone, Copy)]
enum LookAhead {
    None,
    Doubling,
    New,
}

fn side(a: f64, m: f64, b: f64, p: f64) -> SideTerm {
    SideTerm { cost_scale: a, cost_violation: m, violation: b, power: p }
}

impl Primary {
    fn build(self) -> PenaltyFn {
        match self {
            Primary::None => PenaltyFn::None {},
            Primary::Orig(p) => {
                PenaltyFn::Scaled { too_close: side(1.0, 2.0, 0.0, p), too_far: side(1.0, 1.0, 0.0, p) }
            }
            Primary::FiveCost(p) => {
                PenaltyFn::Scaled { too_close: side(5.0, 0.0, 25.0, p), too_far: side(1.0, 0.0, 2.0, p) }
            }
        }
    }
}

impl LookAhead {
    fn build(self) -> PenaltyFn {
        match self {
            LookAhead::None => PenaltyFn::None {},
            LookAhead::Doubling => PenaltyFn::Doubling {},
            LookAhead::New => {
                PenaltyFn::Scaled { too_close: side(2.0, 0.0, 1.0, 3.0), too_far: side(2.0, 0.0, 1.0, 2.0) }
            }
        }
    }
}

impl PenaltyCase {
    pub const ALL: [PenaltyCase; 21] = {
        use PenaltyCase::*;
        [C1, C2a, C2, C3, C4, C5, C6, C7, C8, C9, C10, C11, C12, C13, C2b, C3a, C4a, C6a, C8a, C10a, C12a]
    };

    fn shapes(self) -> (Primary, LookAhead) {
        use LookAhead as L;
        use PenaltyCase::*;
        use Primary as P;
        match self {
            C1 => (P::Orig(1.0), L::Doubling),
            C2a => (P::Orig(1.0), L::None),
            C2 => (P::None, L::None),
            C3 => (P::None, L::Doubling),
            C4 => (P::Orig(2.0), L::Doubling),
            C5 => (P::Orig(2.0), L::None),
            C6 => (P::Orig(3.0), L::Doubling),
            C7 => (P::Orig(3.0), L::None),
            C8 => (P::FiveCost(1.0), L::Doubling),
            C9 => (P::FiveCost(1.0), L::None),
            C10 => (P::FiveCost(2.0), L::Doubling),
            C11 => (P::FiveCost(2.0), L::None),
            C12 => (P::FiveCost(3.0), L::Doubling),
            C13 => (P::FiveCost(3.0), L::None),
            C2b => (P::Orig(1.0), L::New),
            C3a => (P::None, L::New),
            C4a => (P::Orig(2.0), L::New),
            C6a => (P::Orig(3.0), L::New),
            C8a => (P::FiveCost(1.0), L::New),
            C10a => (P::FiveCost(2.0), L::New),
            C12a => (P::FiveCost(3.0), L::New),
        }
    }

    /// The primary and look-ahead penalties of this case.
    pub fn penalties(self) -> PenaltyPair {
        let (p, l) = self.shapes();
        PenaltyPair { primary: p.build(), look_ahead: l.build() }
    }

    /// The case number as Table 5.2 writes it ("1", "2a", ...).
    pub fn id(self) -> &'static str {
        use PenaltyCase::*;
        match self {
            C1 => "1",
            C2a => "2a",
            C2 => "2",
            C3 => "3",
            C4 => "4",
            C5 => "5",
            C6 => "6",
            C7 => "7",
            C8 => "8",
            C9 => "9",
            C10 => "10",
            C11 => "11",
            C12 => "12",
            C13 => "13",
            C2b => "2b",
            C3a => "3a",
            C4a => "4a",
            C6a => "6a",
            C8a => "8a",
            C10a => "10a",
            C12a => "12a",
        }
    }

    pub fn from_id(id: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.id() == id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tc(v: f64) -> Violation {
        Violation { too_close: v, too_far: 0.0 }
    }
    fn tf(v: f64) -> Violation {
        Violation { too_close: 0.0, too_far: v }
    }

    #[test]
    fn orig_failure_point_is_two_to_one() {
        // Eq. (13): with equal base costs, too-far loses once v_TF > 2·v_TC, i.e. once
        // d_max + 2·d_min > 1200 m (1003 m vs 99 m flips it; 1001 m vs 99 m does not).
        let p = PenaltyCase::C1.penalties().primary;
        let c = 7.0;
        let close = p.apply(c, &tc(100.0 - 99.0));
        assert!(p.apply(c, &tf(1003.0 - 1000.0)) > close);
        assert!(p.apply(c, &tf(1001.0 - 1000.0)) < close);
    }

    #[test]
    fn five_cost_ratios_at_zero_cost() {
        for (case, ratio) in [
            (PenaltyCase::C8, 12.5),
            (PenaltyCase::C9, 12.5),
            (PenaltyCase::C10, 12.5f64.sqrt()),
            (PenaltyCase::C12, 12.5f64.cbrt()),
        ] {
            let p = case.penalties().primary;
            let v = 1.7;
            let close = p.apply(0.0, &tc(v));
            assert!(p.apply(0.0, &tf(ratio * v * 1.001)) > close, "{case:?}");
            assert!(p.apply(0.0, &tf(ratio * v * 0.999)) < close, "{case:?}");
        }
    }

    #[test]
    fn too_close_wins_and_penalties_never_lower_cost() {
        let both = Violation { too_close: 1.0, too_far: 500.0 };
        for case in PenaltyCase::ALL {
            let pair = case.penalties();
            for p in [pair.primary, pair.look_ahead] {
                p.validate("p.").unwrap();
                for v in [Violation::default(), tc(0.3), tf(40.0), both] {
                    assert!(p.apply(3.0, &v) >= 3.0);
                }
            }
            assert_eq!(PenaltyCase::from_id(case.id()), Some(case));
        }
        let orig = PenaltyCase::C1.penalties().primary;
        assert_eq!(orig.apply(2.0, &both), orig.apply(2.0, &tc(1.0)));
    }

    #[test]
    fn a_cost_lowering_family_is_rejected() {
        let p = PenaltyFn::Scaled { too_close: side(0.5, 0.0, 1.0, 1.0), too_far: side(1.0, 0.0, 1.0, 1.0) };
        let e = p.validate("planner.penalty.primary.").unwrap_err().to_string();
        assert!(e.contains("planner.penalty.primary.too_close.cost_scale = 0.5"), "{e}");
    }
}

/// Each penalty's value at hand-computed points, so that a changed operator or comparison in a
/// formula changes a checked number.
#[cfg(test)]
mod value_tests {
    use super::*;

    fn v(too_close: f64, too_far: f64) -> Violation {
        Violation { too_close, too_far }
    }

    #[test]
    fn a_violation_on_either_side_counts() {
        assert!(!v(0.0, 0.0).any());
        assert!(v(0.5, 0.0).any());
        assert!(v(0.0, 0.5).any());
        assert!(v(2.0, 3.0).any());
    }

    #[test]
    fn no_penalty_and_doubling_values() {
        assert_eq!(NoPenalty {}.apply(3.0, &v(1.0, 0.0)), 3.0);
        assert_eq!(PenaltyFn::None {}.apply(3.0, &v(0.0, 4.0)), 3.0);
        let d = Doubling {};
        assert_eq!(d.apply(3.0, &v(0.0, 0.0)), 3.0);
        assert_eq!(d.apply(3.0, &v(0.2, 0.0)), 6.0);
        assert_eq!(d.apply(3.0, &v(0.0, 0.2)), 6.0);
        assert_eq!(PenaltyFn::Doubling {}.apply(3.0, &v(0.0, 0.2)), 6.0);
    }

    #[test]
    fn side_term_is_a_c_plus_m_c_vp_plus_b_vp() {
        // a = 2, m = 3, b = 5, C = 4, v = 1.5: 2·4 + (3·4 + 5)·v^p.
        let linear = SideTerm { cost_scale: 2.0, cost_violation: 3.0, violation: 5.0, power: 1.0 };
        assert_eq!(linear.apply(4.0, 1.5), 8.0 + 17.0 * 1.5);
        let square = SideTerm { power: 2.0, ..linear };
        assert_eq!(square.apply(4.0, 1.5), 8.0 + 17.0 * 2.25);
        let cube = SideTerm { power: 3.0, ..linear };
        assert!((cube.apply(4.0, 1.5) - (8.0 + 17.0 * 3.375)).abs() < 1e-12);
    }

    #[test]
    fn the_violated_side_picks_the_term() {
        // Distinct terms per side, so the branch taken shows in the value.
        let close = SideTerm { cost_scale: 3.0, cost_violation: 0.0, violation: 1.0, power: 1.0 };
        let far = SideTerm { cost_scale: 5.0, cost_violation: 0.0, violation: 7.0, power: 1.0 };
        let p = ScaledViolation { too_close: close, too_far: far };
        assert_eq!(p.apply(2.0, &v(0.0, 0.0)), 2.0);
        assert_eq!(p.apply(2.0, &v(0.5, 0.0)), 6.0 + 0.5);
        assert_eq!(p.apply(2.0, &v(0.0, 0.5)), 10.0 + 3.5);
        assert_eq!(p.apply(2.0, &v(0.5, 9.0)), 6.0 + 0.5);
        let f = PenaltyFn::Scaled { too_close: close, too_far: far };
        assert_eq!(f.apply(2.0, &v(0.0, 0.5)), 10.0 + 3.5);
    }

    #[test]
    fn the_lower_limits_are_inclusive_and_named() {
        let ok = SideTerm { cost_scale: 1.0, cost_violation: 0.0, violation: 0.0, power: 1.0 };
        let fine = PenaltyFn::Scaled { too_close: ok, too_far: ok };
        fine.validate("p.").unwrap();
        let low_power = PenaltyFn::Scaled { too_close: ok, too_far: SideTerm { power: 0.5, ..ok } };
        let e = low_power.validate("p.").unwrap_err().to_string();
        assert!(e.contains("p.too_far.power = 0.5"), "{e}");
        let pair = PenaltyPair { primary: fine, look_ahead: low_power };
        let e = pair.validate("planner.penalty.").unwrap_err().to_string();
        assert!(e.contains("planner.penalty.look_ahead.too_far.power = 0.5"), "{e}");
        let pair = PenaltyPair { primary: low_power, look_ahead: fine };
        let e = pair.validate("planner.penalty.").unwrap_err().to_string();
        assert!(e.contains("planner.penalty.primary.too_far.power = 0.5"), "{e}");
    }

    #[test]
    fn presets_are_the_documented_shapes() {
        // docs/models.md#hudson-penalties: Orig.^p is C·(1 + 2v^p) / C·(1 + v^p), 5×Cost^p is
        // 5C + 25v^p / C + 2v^p, "New" is 2C + v_TC³ / 2C + v_TF².
        let s = |a, m, b, p| SideTerm { cost_scale: a, cost_violation: m, violation: b, power: p };
        let c4 = PenaltyCase::C4.penalties();
        assert_eq!(c4.primary, PenaltyFn::Scaled { too_close: s(1.0, 2.0, 0.0, 2.0), too_far: s(1.0, 1.0, 0.0, 2.0) });
        assert_eq!(c4.look_ahead, PenaltyFn::Doubling {});
        let c10a = PenaltyCase::C10a.penalties();
        assert_eq!(
            c10a.primary,
            PenaltyFn::Scaled { too_close: s(5.0, 0.0, 25.0, 2.0), too_far: s(1.0, 0.0, 2.0, 2.0) }
        );
        assert_eq!(
            c10a.look_ahead,
            PenaltyFn::Scaled { too_close: s(2.0, 0.0, 1.0, 3.0), too_far: s(2.0, 0.0, 1.0, 2.0) }
        );
        let c2 = PenaltyCase::C2.penalties();
        assert_eq!((c2.primary, c2.look_ahead), (PenaltyFn::None {}, PenaltyFn::None {}));
        assert_eq!(PenaltyCase::C12a.id(), "12a");
        assert_eq!(PenaltyCase::from_id("12a"), Some(PenaltyCase::C12a));
        assert_eq!(PenaltyCase::from_id("14"), None);
    }
}
