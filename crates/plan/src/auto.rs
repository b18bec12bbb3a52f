//! The estimator-aware planner's settings configured from the mission: [`for_mission`] turns the
//! facts a scenario states ([`MissionFacts`]: how many survey AUVs, the CNA's kind and its own
//! navigation diffusion, the current its ADCP measures, whether the AUVs' filters estimate the
//! current) into every `planner-estimator` setting ([`EstimatorSettings`]). A scenario file sets a
//! key to override one setting; every key it leaves unset comes from this rule, so a user's
//! `simulate` flies what `reproduce closed-loop-vs-baselines` evaluates.
//!
//! The rule (each constant below says where its value comes from):
//! - **Tree.** With the ASC, A = 5 and L = [`TRUE_ERROR_LOOK_AHEAD`]. With an AUV CNA, the pitch
//!   options at level 0 only ([`AUV_CNA_PITCH_LEVELS`]) and the fine tree [`FINE_AUV_CNA`] (A = 9,
//!   L = 3, H = 40), except at N = 2, where A = 5, L = 5 and the filters' covariances are scored.
//!   From [`FINE_HEADINGS_MIN_AUVS`] AUVs on, with either CNA, A = 21, L = 2, H = 40 and the
//!   trace sum ([`fine_headings`]).
//! - **Cost.** The true-error cost ([`ASC_TRUTH`], or [`auv_cna_truth`] with the CNA's own
//!   diffusion), with the ADCP's current as the mean error of filters that do not model it, or as
//!   the water that filters estimating the current start from zero against; σ-sum aggregate
//!   ([`AGGREGATE`]); range bias k_b [`BIAS_PER_KM`]; H = [`TERMINAL_LEVELS`].
//! - **Spread fleets.** From [`SPREAD_FLEET_MIN_AUVS`] AUVs on, no level-0 distance penalty
//!   (Table 5.2 case 3) and the reach cost-to-go ([`REACH_SUCCESS`], [`SPREAD_TERMINAL_LEVELS`]).
//! - **Depth.** An AUV CNA from [`DEPTH_AWARE_MIN_AUVS`] AUVs on chooses its depth by the
//!   sound-speed profile (bias profile, level-off, k_b [`DEPTH_AWARE_BIAS_PER_KM`], or
//!   [`FINE_HEADINGS_AUV_CNA_BIAS_PER_KM`] with the fine headings).
//! - **Schedule.** The planner knows its slots' half-duplex reach ([`SLOT_REACH`]) and scores
//!   every broadcast position as exact ([`CNA_VARIANCE`]).
//!
//! Every value is invented (docs/models.md#mission-rule): the thesis plans with A = 5, L = 5 and
//! the filters' covariance. The values were chosen on runs of `reproduce closed-loop-vs-baselines`'
//! two missions from base seed 1000, disjoint from the evaluation's (docs/evaluation.md).

use crate::estimator::Aggregate;
use crate::penalty::PenaltyCase;
use crate::true_error::TruthSpec;
use crate::RangeNoise;

/// What the CNA is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CnaFact {
    /// A surface craft with GPS: its position error does not grow.
    Asc,
    /// An AUV: its navigation error grows by `nav_diffusion_m2_s` per axis between fixes.
    Auv { nav_diffusion_m2_s: f64 },
}

/// The facts of a mission the rule reads: all of them stated by the scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionFacts {
    /// Survey AUVs.
    pub n_auvs: usize,
    pub cna: CnaFact,
    /// The water current east and north (m/s) as the CNA's ADCP measures it (0: none measured).
    pub adcp_current: [f64; 2],
    /// Whether the survey AUVs' filters estimate the current (7 states) or not (the thesis's 5).
    pub filters_estimate_current: bool,
}

/// Every setting of `planner-estimator` the rule chooses (Hudson's own planner keeps its file's).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EstimatorSettings {
    /// A: heading options per level.
    pub heading_options: usize,
    /// L: levels of the exact look-ahead tree.
    pub look_ahead: usize,
    /// With an AUV CNA, the levels that offer the pitch options (None: every level).
    pub pitch_levels: Option<usize>,
    /// How the AUVs' terms are joined into a level's cost.
    pub aggregate: Aggregate,
    /// k_b: the range bias assumed, m of 1-σ per km of range (estimator step 4).
    pub bias_per_km: f64,
    /// Price the scale error of the sound-speed profile between the CNA's depth and each AUV's.
    pub bias_profile: bool,
    /// Model each AUV-CNA step as level-starting, cut at the pitch and depth limits.
    pub level_off: bool,
    /// Know the schedule's half-duplex reach.
    pub slot_reach: bool,
    /// H: levels of cost-to-go at each leaf (estimator step 6).
    pub terminal_levels: f64,
    /// p_u of the reach cost-to-go (estimator step 7; 0 = none).
    pub reach_success: f64,
    /// The Table 5.2 penalty case of the estimator's tree (None: Hudson's planner's own case).
    pub penalty_case: Option<PenaltyCase>,
    /// Add the CNA's own horizontal variance to each ping's range variance.
    pub cna_variance: bool,
    /// Some: score the AUVs' expected true error (`true_error`); None: the filters' covariances.
    pub truth: Option<TruthSpec>,
    /// The current the filters do not model (estimator step 1b), east and north, m/s.
    pub unmodelled_current: [f64; 2],
    /// The water the current-estimating filters start from zero against (`current_states`).
    pub current: [f64; 2],
}

/// σ-sum: one AUV with a huge variance does not outweigh the rest as in the trace sum.
pub const AGGREGATE: Aggregate = Aggregate::SigmaSum;

/// k_b (docs/models.md#estimator-cost; Gill 2013 gives no sound-speed error model). Chosen on
/// tuning runs: three times the filters' configured 3 m/s sound-speed uncertainty, within the
/// ±11 m/s span of the scenarios' profiles. The bias and the terminal levels pay together, not
/// apart, on the default mission with current.
pub const BIAS_PER_KM: f64 = 6.0;

/// H: levels of cost-to-go at each leaf (chosen with [`BIAS_PER_KM`]).
pub const TERMINAL_LEVELS: f64 = 10.0;

/// Off: on tuning runs counting the CNA's own variance changed nothing measurable, and on
/// auv-cna-tdma.toml it costs. A common CNA offset moves every AUV's estimate alike, which a
/// per-ping noise term cannot express.
pub const CNA_VARIANCE: bool = false;

/// The planner knows its schedule's half-duplex reach: with Hudson's schedule at τ = 44 s and 8
/// AUVs, the first slot's AUV hears no broadcast sent from beyond about 2 km (its own status
/// starts first), which the link's range-only model missed (docs/models.md#closed-loop-schedule).
/// Chosen on tuning runs; up to 3 AUVs every reach exceeds 6 km and nothing changes.
pub const SLOT_REACH: bool = true;

/// The true-error model with the ASC (invented, docs/models.md#true-error-cost, no thesis
/// values): the AUVs' true dead-reckoning drift 0.002 m²/s, the channel's ranges σ 1.8 m (Gill's
/// outliers, E[n²] ≈ 3.2 m²), an ASC whose GPS error does not drift. Chosen on tuning runs of the
/// default mission with a current: it lowers the error at every N (docs/evaluation.md). The
/// values are those `scenarios/auv-cna-tdma.toml` uses, with no CNA drift.
pub const ASC_TRUTH: TruthSpec =
    TruthSpec { drift_m2_s: 0.002, range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 }, cna_diffusion_m2_s: 0.0 };

/// The AUVs' true drift with an AUV CNA, m²/s (invented, docs/models.md#true-error-cost; chosen on
/// tuning runs of the sloping scenario).
pub const AUV_CNA_DRIFT_M2_S: f64 = 0.01;

/// The true-error model with an AUV CNA: drift [`AUV_CNA_DRIFT_M2_S`], the channel's ranges σ
/// 1.8 m (Gill's outliers), and the CNA's own navigation diffusion, the mission's fact.
pub fn auv_cna_truth(nav_diffusion_m2_s: f64) -> TruthSpec {
    TruthSpec {
        drift_m2_s: AUV_CNA_DRIFT_M2_S,
        range_noise: ASC_TRUTH.range_noise,
        cna_diffusion_m2_s: nav_diffusion_m2_s,
    }
}

/// L with the ASC and [`ASC_TRUTH`] (chosen on tuning runs). The true-error cost's lower bound
/// below a node is loose, so its search costs about brute force's: L = 4 gives about the error of
/// L = 5 at about a third of the time.
pub const TRUE_ERROR_LOOK_AHEAD: usize = 4;

/// With an AUV CNA, the levels that offer the pitch options. All 15 options at every level make
/// L = 5 about 20× slower than L = 3; a ±45° pitch step (1.5°/s over τ) breaks the 30° limit, so
/// level 0 drops them and deeper levels double their cost: with pitch options at level 0 only the
/// same runs give the same error at a fraction of the time (chosen on tuning runs).
pub const AUV_CNA_PITCH_LEVELS: usize = 1;

/// The AUV CNA's fine tree (A, L, H): with one AUV the finer headings and the longer cost-to-go
/// pay under the true-error cost, not under the covariance cost; at N = 3 and 5 the same tree does
/// better than A = 5, L = 5 at a fraction of the search time; at N = 2 and 8 it does not (chosen
/// on tuning runs, docs/evaluation.md). From [`SPREAD_FLEET_MIN_AUVS`] AUVs on H is the spread
/// fleets' [`SPREAD_TERMINAL_LEVELS`].
pub const FINE_AUV_CNA: (usize, usize, f64) = (9, 3, 40.0);

/// The AUV CNA's tree at N = 2 (A, L): A = 5 and the filters' covariances; L = 5 is the deepest
/// tree whose gain pays for its time, and the true-error cost does not pay for its time there.
pub const TWO_AUVS_AUV_CNA: (usize, usize) = (5, 5);

/// From this many AUVs on (a fleet spread wider than the link's plateau) the tree runs without
/// the level-0 distance penalty (Table 5.2 case 3, look-ahead doubling only) and with the
/// reach-time cost-to-go in its place. With 5 or 8 AUVs spread over 3–4.8 km every option breaks
/// the 1 km limit for some AUV, and the penalty, C·(1 + v) with v in metres, then decides alone
/// (the CNA minimises its largest distance, Hudson's planner's path). Chosen on tuning runs of
/// the default mission with current.
pub const SPREAD_FLEET_MIN_AUVS: usize = 5;

/// p_u of the reach-time cost-to-go for spread fleets: just below the 0.8 plateau of the rate-0
/// success curve, so the useful range r_u ≈ 0.93 km is where pings start being lost. Smaller p_u
/// (a useful range of 2–2.5 km, farther than most AUVs ever are) changes nothing.
pub const REACH_SUCCESS: f64 = 0.79;

/// H for spread fleets: the reach term's growth saturates at qτ·H/2, and with H = 10 it is too
/// weak to replace the penalty.
pub const SPREAD_TERMINAL_LEVELS: f64 = 20.0;

/// From this many AUVs on, with either CNA, the fine headings of [`fine_headings`].
pub const FINE_HEADINGS_MIN_AUVS: usize = 6;

/// k_b with an AUV CNA that chooses its depth, on top of the profile's own scale error. Chosen on
/// tuning runs of the sloping scenario: the profile alone cannot move a CNA whose ±45° pitch steps
/// break the 30° limit, levelling off without the profile dives the CNA towards deep AUVs into
/// slower water, and the two together with every step starting level do best; with the filters
/// expecting Gill's outliers k_b 6 does better than 3 (docs/evaluation.md).
pub const DEPTH_AWARE_BIAS_PER_KM: f64 = 6.0;

/// From this many AUVs on an AUV CNA chooses its depth: with one AUV, over the shallow end of the
/// shelf where the profile's scale error is small at 10 m, it does worse.
pub const DEPTH_AWARE_MIN_AUVS: usize = 2;

/// k_b with an AUV CNA and the fine headings (on top of the profile's scale error). Chosen on
/// tuning runs at N = 8 on the slope: the fine headings keep the CNA closer to the AUVs than A = 5
/// did, and a smaller k_b than [`DEPTH_AWARE_BIAS_PER_KM`] does better there (docs/evaluation.md).
pub const FINE_HEADINGS_AUV_CNA_BIAS_PER_KM: f64 = 1.5;

/// The fine headings for large fleets (A, L, H): A = 21, about 17° apart within the turn limit's
/// ±176°, against A = 5's 88°; L = 2; H = 40; the true error joined by the trace sum. Chosen on
/// tuning runs at N = 8 with a schedule sized for the fleet: with A = 5 the CNA sits west of the
/// fleet's centroid, and centroid wins the current cell; finer headings win it from A = 7 on,
/// best at A = 21 with L = 2 (A = 31 no better), and the same tree ties centroid-standoff on the
/// slope where A = 5 loses (docs/evaluation.md).
pub const FINE_HEADINGS: (usize, usize, f64) = (21, 2, 40.0);

/// The aggregate with [`FINE_HEADINGS`].
pub const FINE_HEADINGS_AGGREGATE: Aggregate = Aggregate::TraceSum;

/// The settings of `planner-estimator` for the mission `f` (the module's rule).
pub fn for_mission(f: &MissionFacts) -> EstimatorSettings {
    let n = f.n_auvs;
    let auv_nav = match f.cna {
        CnaFact::Asc => None,
        CnaFact::Auv { nav_diffusion_m2_s } => Some(nav_diffusion_m2_s),
    };
    let truth = auv_nav.map_or(ASC_TRUTH, auv_cna_truth);
    let spread = n >= SPREAD_FLEET_MIN_AUVS;
    let depth_aware = auv_nav.is_some() && n >= DEPTH_AWARE_MIN_AUVS;
    let mut s = EstimatorSettings {
        heading_options: 5,
        look_ahead: TRUE_ERROR_LOOK_AHEAD,
        pitch_levels: auv_nav.map(|_| AUV_CNA_PITCH_LEVELS),
        aggregate: AGGREGATE,
        bias_per_km: if depth_aware { DEPTH_AWARE_BIAS_PER_KM } else { BIAS_PER_KM },
        bias_profile: depth_aware,
        level_off: depth_aware,
        slot_reach: SLOT_REACH,
        terminal_levels: if spread { SPREAD_TERMINAL_LEVELS } else { TERMINAL_LEVELS },
        reach_success: if spread { REACH_SUCCESS } else { 0.0 },
        penalty_case: spread.then_some(PenaltyCase::C3),
        cna_variance: CNA_VARIANCE,
        truth: Some(truth),
        unmodelled_current: [0.0, 0.0],
        current: [0.0, 0.0],
    };
    if n >= FINE_HEADINGS_MIN_AUVS {
        (s.heading_options, s.look_ahead, s.terminal_levels) = FINE_HEADINGS;
        s.aggregate = FINE_HEADINGS_AGGREGATE;
        if auv_nav.is_some() {
            s.bias_per_km = FINE_HEADINGS_AUV_CNA_BIAS_PER_KM;
        }
    } else if auv_nav.is_some() && n == 2 {
        (s.heading_options, s.look_ahead) = TWO_AUVS_AUV_CNA;
        s.truth = None;
    } else if auv_nav.is_some() {
        let (a, l, h) = FINE_AUV_CNA;
        (s.heading_options, s.look_ahead) = (a, l);
        if !spread {
            s.terminal_levels = h;
        }
    }
    if s.truth.is_some() {
        if f.filters_estimate_current {
            s.current = f.adcp_current;
        } else {
            s.unmodelled_current = f.adcp_current;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asc(n: usize) -> MissionFacts {
        MissionFacts { n_auvs: n, cna: CnaFact::Asc, adcp_current: [0.05, 0.0], filters_estimate_current: false }
    }

    fn auv(n: usize) -> MissionFacts {
        MissionFacts {
            n_auvs: n,
            cna: CnaFact::Auv { nav_diffusion_m2_s: 0.01 },
            adcp_current: [0.0, 0.0],
            filters_estimate_current: false,
        }
    }

    /// What every cell of `reproduce closed-loop-vs-baselines` flew when its settings were
    /// written per cell in the experiment, written out: the ASC in the default mission's 0.05 m/s
    /// current, and the sloping scenario's AUV CNA (diffusion 0.01 m²/s, no current), N = 1, 2,
    /// 3, 5 and 8. Columns: A, L, pitch levels, aggregate, k_b, bias profile, level-off, H, p_u,
    /// penalty case, truth (drift, CNA diffusion), unmodelled current.
    #[test]
    fn the_rule_gives_every_evaluation_cell_its_settings() {
        let asc_truth = TruthSpec {
            drift_m2_s: 0.002,
            range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 },
            cna_diffusion_m2_s: 0.0,
        };
        let auv_truth = TruthSpec {
            drift_m2_s: 0.01,
            range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 },
            cna_diffusion_m2_s: 0.01,
        };
        let (sig, tr) = (Aggregate::SigmaSum, Aggregate::TraceSum);
        let c3 = Some(PenaltyCase::C3);
        let w = [0.05, 0.0];
        let still = [0.0, 0.0];
        #[rustfmt::skip]
        let cells: [(MissionFacts, usize, usize, Option<usize>, Aggregate, f64, bool, bool, f64, f64, Option<PenaltyCase>, Option<TruthSpec>, [f64; 2]); 10] = [
            (asc(1), 5, 4, None, sig, 6.0, false, false, 10.0, 0.0, None, Some(asc_truth), w),
            (asc(2), 5, 4, None, sig, 6.0, false, false, 10.0, 0.0, None, Some(asc_truth), w),
            (asc(3), 5, 4, None, sig, 6.0, false, false, 10.0, 0.0, None, Some(asc_truth), w),
            (asc(5), 5, 4, None, sig, 6.0, false, false, 20.0, 0.79, c3, Some(asc_truth), w),
            (asc(8), 21, 2, None, tr, 6.0, false, false, 40.0, 0.79, c3, Some(asc_truth), w),
            (auv(1), 9, 3, Some(1), sig, 6.0, false, false, 40.0, 0.0, None, Some(auv_truth), still),
            (auv(2), 5, 5, Some(1), sig, 6.0, true, true, 10.0, 0.0, None, None, still),
            (auv(3), 9, 3, Some(1), sig, 6.0, true, true, 40.0, 0.0, None, Some(auv_truth), still),
            (auv(5), 9, 3, Some(1), sig, 6.0, true, true, 20.0, 0.79, c3, Some(auv_truth), still),
            (auv(8), 21, 2, Some(1), tr, 1.5, true, true, 40.0, 0.79, c3, Some(auv_truth), still),
        ];
        for (facts, a, l, pitch, aggregate, k_b, profile, level_off, h, p_u, case, truth, unmodelled) in cells {
            let expected = EstimatorSettings {
                heading_options: a,
                look_ahead: l,
                pitch_levels: pitch,
                aggregate,
                bias_per_km: k_b,
                bias_profile: profile,
                level_off,
                slot_reach: true,
                terminal_levels: h,
                reach_success: p_u,
                penalty_case: case,
                cna_variance: false,
                truth,
                unmodelled_current: unmodelled,
                current: [0.0, 0.0],
            };
            assert_eq!(for_mission(&facts), expected, "{facts:?}");
        }
    }

    /// Filters that estimate the current start from zero against the ADCP's current; filters that
    /// do not carry it as their mean error; with the covariance cost neither is used.
    #[test]
    fn the_adcp_current_goes_where_the_filters_model_it() {
        let seven = MissionFacts { filters_estimate_current: true, ..asc(3) };
        let s = for_mission(&seven);
        assert_eq!((s.current, s.unmodelled_current), ([0.05, 0.0], [0.0, 0.0]));
        let five = for_mission(&asc(3));
        assert_eq!((five.current, five.unmodelled_current), ([0.0, 0.0], [0.05, 0.0]));
        let covariance = for_mission(&MissionFacts { adcp_current: [0.1, 0.0], ..auv(2) });
        assert_eq!((covariance.current, covariance.unmodelled_current), ([0.0, 0.0], [0.0, 0.0]));
        // The AUV CNA's own diffusion is the mission's.
        let slow = for_mission(&MissionFacts { cna: CnaFact::Auv { nav_diffusion_m2_s: 0.002 }, ..auv(3) });
        assert_eq!(slow.truth.map(|t| t.cna_diffusion_m2_s), Some(0.002));
    }
}
