//! Rate-selection policies (Nams 2014, §5.3–5.4; the adaptation rule reconstructed,
//! docs/models.md#nams-selector): at each own TDMA slot a policy
//! decides whether to transmit and at which WHOI rate. Each policy is one type behind
//! [`RatePolicy`]: [`FixedRate`] (controls 1 and 2: rate 0, rate 1), [`Alternating`] (control 3:
//! rates 0 and 5 in turn) and [`AdaptiveBins`] (the thesis's adaptive distance-bin selector).

use crate::rates::Rate;
use coopnav_core::validation::{CheckFields, InvalidFields, Problems};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};
use thiserror::Error;

/// A policy's decision for one own slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Choice {
    Silent,
    Transmit(Rate),
}

/// A resolved own transmission: `success` = the collaborator got at least one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outcome {
    pub slot: u64,
    pub success: bool,
}

/// A rate-selection policy.
pub trait RatePolicy: Send + RatePolicyClone {
    fn name(&self) -> String;
    /// Every rate the policy may use (drives the TDMA slot length and the header mask width).
    fn rates(&self) -> Vec<Rate>;
    /// Outcomes the tracker resolved since the last call, and whether the peer was heard since.
    fn feedback(&mut self, resolved: &[Outcome], heard_peer: bool);
    /// Decision for own slot `slot`, given the estimated distance to the recipient (None when
    /// nothing is known of it yet).
    fn choose(&mut self, slot: u64, distance: Option<f64>) -> Choice;
    /// The success a planner may count on for this policy's packet to a recipient at one distance,
    /// given each rate's modelled success there (`success`), once the policy has settled on the
    /// link: what it sends there, weighted by how often (silence counts as 0).
    fn settled_success(&self, success: &dyn Fn(Rate) -> f64) -> f64;
}

/// A boxed [`RatePolicy`] can be copied with its state (a forked mission copies its vehicles'
/// selectors); every `Clone` policy has it.
pub trait RatePolicyClone {
    fn clone_box(&self) -> Box<dyn RatePolicy>;
}

impl<T: RatePolicy + Clone + 'static> RatePolicyClone for T {
    fn clone_box(&self) -> Box<dyn RatePolicy> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn RatePolicy> {
    fn clone(&self) -> Self {
        (**self).clone_box()
    }
}

/// A rate policy as a file names it (`kind = "fixed" | "alternating" | "adaptive"`): the one
/// list of policies, each name written once here; [`RatePolicySpec::build`] makes the policy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RatePolicySpec {
    /// Every own slot at `rate` (Nams's controls 1 and 2).
    Fixed { rate: Rate },
    /// Every own slot, cycling through `rates` (control 3: rates 0 and 5).
    Alternating { rates: Vec<Rate> },
    /// The adaptive distance-bin selector (Nams §5.3; its fields are [`AdaptiveConfig`]'s).
    Adaptive(AdaptiveConfig),
}

/// Why a rate policy's specification makes no policy: its field and what is allowed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RatePolicyError {
    #[error("rate {0}: allowed 0, 1, 4 or 5")]
    Rate(Rate),
    #[error("rates {0:?}: allowed a non-empty list of 0, 1, 4 or 5")]
    Rates(Vec<Rate>),
    #[error("the adaptive selector: {0}")]
    Adaptive(#[from] InvalidFields),
}

impl RatePolicySpec {
    /// The policy, or what is wrong with the specification.
    pub fn build(&self) -> Result<Box<dyn RatePolicy>, RatePolicyError> {
        let usable = |r: &Rate| !r.spec().deprecated;
        Ok(match self {
            RatePolicySpec::Fixed { rate } if usable(rate) => Box::new(FixedRate { rate: *rate }),
            RatePolicySpec::Alternating { rates } if !rates.is_empty() && rates.iter().all(usable) => {
                Box::new(Alternating::new(rates.clone()))
            }
            RatePolicySpec::Fixed { rate } => return Err(RatePolicyError::Rate(*rate)),
            RatePolicySpec::Alternating { rates } => return Err(RatePolicyError::Rates(rates.clone())),
            RatePolicySpec::Adaptive(cfg) => Box::new(AdaptiveBins::new(cfg.clone())?),
        })
    }

    /// Every rate the policy may use, or what is wrong with it.
    pub fn rates(&self) -> Result<Vec<Rate>, RatePolicyError> {
        Ok(self.build()?.rates())
    }

    /// The policy's name in tables ("fixed rate 1", "alternating 0/5", "adaptive"), or "invalid".
    pub fn label(&self) -> String {
        self.build().map_or_else(|_| "invalid".into(), |p| p.name())
    }

    /// The thesis's four (§5.4): controls 1–3 (fixed rate 0, fixed rate 1, rates 0 and 5 in turn)
    /// and the adaptive selector without rate 5 (Table 8 values).
    pub fn thesis() -> Vec<RatePolicySpec> {
        vec![
            RatePolicySpec::Fixed { rate: Rate::R0 },
            RatePolicySpec::Fixed { rate: Rate::R1 },
            RatePolicySpec::Alternating { rates: vec![Rate::R0, Rate::R5] },
            RatePolicySpec::Adaptive(AdaptiveConfig::default()),
        ]
    }

    /// A control: a policy that does not learn from the channel.
    pub fn is_control(&self) -> bool {
        !matches!(self, RatePolicySpec::Adaptive(_))
    }
}

/// Always transmit at one rate.
#[derive(Debug, Clone)]
pub struct FixedRate {
    pub rate: Rate,
}

impl RatePolicy for FixedRate {
    fn name(&self) -> String {
        format!("fixed rate {}", self.rate)
    }
    fn rates(&self) -> Vec<Rate> {
        vec![self.rate]
    }
    fn feedback(&mut self, _: &[Outcome], _: bool) {}
    fn choose(&mut self, _: u64, _: Option<f64>) -> Choice {
        Choice::Transmit(self.rate)
    }
    fn settled_success(&self, success: &dyn Fn(Rate) -> f64) -> f64 {
        success(self.rate)
    }
}

/// Transmit every own slot, cycling through `rates` (Schneider & Schmidt: 0 and 5).
#[derive(Debug, Clone)]
pub struct Alternating {
    pub rates: Vec<Rate>,
    turn: usize,
}

impl Alternating {
    pub fn new(rates: Vec<Rate>) -> Self {
        Alternating { rates, turn: 0 }
    }
}

impl RatePolicy for Alternating {
    fn name(&self) -> String {
        format!("alternating {}", self.rates.iter().map(Rate::to_string).collect::<Vec<_>>().join("/"))
    }
    fn rates(&self) -> Vec<Rate> {
        self.rates.clone()
    }
    fn feedback(&mut self, _: &[Outcome], _: bool) {}
    fn choose(&mut self, _: u64, _: Option<f64>) -> Choice {
        let r = self.rates[self.turn % self.rates.len()];
        self.turn += 1;
        Choice::Transmit(r)
    }
    /// Each rate of the cycle equally often.
    fn settled_success(&self, success: &dyn Fn(Rate) -> f64) -> f64 {
        self.rates.iter().map(|r| success(*r)).sum::<f64>() / self.rates.len() as f64
    }
}

/// Parameters of the adaptive selector (thesis Table 8 tuned values as defaults; the initial
/// thresholds, D_max and the status-mode exit rule are reconstructed: docs/models.md#nams-selector).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdaptiveConfig {
    /// Memory M: resolved outcomes in each success estimate.
    pub memory: usize,
    /// Tolerance τ around the target success ratio.
    pub tolerance: f64,
    /// Bin increment Δ, m.
    pub step: f64,
    /// T: sequential unconfirmed attempts before switching to the status bins.
    pub t_status: u32,
    /// Target success ratio Π per rate 0, 1, 4, 5; 0 disables the rate.
    pub targets: [f64; 4],
    /// Initial data-bin upper thresholds for rates 0, 1, 4, 5, m.
    pub data_thresholds: [f64; 4],
    /// Initial status-bin thresholds for rates 0 and 1, m (status bins use low rates only).
    pub status_thresholds: [f64; 2],
    pub d_max: f64,
    /// Leave status mode when any packet from the peer is heard (not only on a confirmed success).
    pub exit_status_on_heard: bool,
    /// Exploration of collapsed bins (invented; the thesis has none, docs/models.md#nams-selector):
    /// after this many own slots without a sample at a rate whose bin lies wholly nearer
    /// than the recipient, that bin's threshold drifts out by Δ, so a rate learnt away far out
    /// can be tried again once the vehicles close in. 0: never (the thesis's selector).
    #[serde(skip_serializing_if = "is_zero")]
    pub drift_after_slots: u32,
}

impl Default for AdaptiveConfig {
    fn default() -> Self {
        AdaptiveConfig {
            memory: 10,
            tolerance: 0.05,
            step: 5.0,
            t_status: 3,
            targets: [0.0, 0.4, 0.3, 0.0],
            data_thresholds: [1500.0, 1500.0, 400.0, 100.0],
            status_thresholds: [2500.0, 2500.0],
            d_max: 5000.0,
            exit_status_on_heard: true,
            drift_after_slots: 0,
        }
    }
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

impl CheckFields for AdaptiveConfig {
    /// Every field in its range, the thresholds within `d_max`, at least one rate enabled.
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let field = |name: &str| format!("{prefix}{name}");
        if self.memory == 0 {
            p.push(field("memory"), "0", "an integer >= 1");
        }
        p.check(&field("tolerance"), self.tolerance, |v| (0.0..=0.5).contains(&v), "a number in [0, 0.5]");
        p.positive(&field("step"), self.step);
        p.positive(&field("d_max"), self.d_max);
        for (k, &t) in self.targets.iter().enumerate() {
            p.check(
                &field(&format!("targets[{k}]")),
                t,
                |v| (0.0..=1.0).contains(&v),
                "a number in [0, 1] (0 disables the rate)",
            );
        }
        if self.targets.iter().all(|t| *t == 0.0) {
            p.push(field("targets"), format!("{:?}", self.targets), "at least one rate with a target > 0");
        }
        for (name, list) in
            [("data_thresholds", &self.data_thresholds[..]), ("status_thresholds", &self.status_thresholds[..])]
        {
            for (k, &d) in list.iter().enumerate() {
                let allowed = format!("a distance in [0, d_max = {}] m", self.d_max);
                p.check(&field(&format!("{name}[{k}]")), d, |v| (0.0..=self.d_max).contains(&v), &allowed);
            }
        }
    }
}

/// One array of distance bins: fastest rate nearest; beyond the last threshold, silence.
#[derive(Debug, Clone)]
struct BinArray {
    rates: Vec<Rate>,
    targets: Vec<f64>,
    th: Vec<f64>,
    hist: Vec<VecDeque<bool>>,
    fresh: Vec<bool>,
    /// Own slots since the last choice of each rate.
    idle: Vec<u32>,
}

impl BinArray {
    fn new(entries: Vec<(Rate, f64, f64)>) -> Self {
        let n = entries.len();
        let mut a = BinArray {
            rates: entries.iter().map(|e| e.0).collect(),
            targets: entries.iter().map(|e| e.1).collect(),
            th: entries.iter().map(|e| e.2).collect(),
            hist: vec![VecDeque::new(); n],
            fresh: vec![false; n],
            idle: vec![0; n],
        };
        for i in 0..n {
            a.make_monotone(i);
        }
        a
    }

    fn bin(&self, d: f64) -> Option<usize> {
        self.th.iter().position(|t| d < *t)
    }

    /// Keeps th non-decreasing from fastest to slowest after th[i] moved.
    fn make_monotone(&mut self, i: usize) {
        let v = self.th[i];
        for t in &mut self.th[..i] {
            *t = t.min(v);
        }
        for t in &mut self.th[i + 1..] {
            *t = t.max(v);
        }
    }

    fn record(&mut self, i: usize, success: bool, memory: usize) {
        self.hist[i].push_back(success);
        while self.hist[i].len() > memory {
            self.hist[i].pop_front();
        }
        self.fresh[i] = true;
    }

    /// The bin for distance `d` in an own slot; first, each rate whose bin lies wholly nearer
    /// than `d` and has gone `drift_after` slots unchosen has its threshold moved out by `step`.
    fn choose(&mut self, d: f64, drift_after: u32, step: f64, d_max: f64) -> Option<usize> {
        for i in 0..self.th.len() {
            if drift_after > 0 && self.th[i] <= d && self.idle[i] >= drift_after {
                self.th[i] = (self.th[i] + step).min(d_max);
                self.make_monotone(i);
                self.idle[i] = 0;
            }
        }
        let chosen = self.bin(d);
        for (i, idle) in self.idle.iter_mut().enumerate() {
            *idle = if Some(i) == chosen { 0 } else { *idle + 1 };
        }
        chosen
    }

    /// The success of the fastest rate whose success reaches its target, if any (the bin a settled
    /// array picks at the distance `success` describes).
    fn settled_success(&self, success: &dyn Fn(Rate) -> f64) -> Option<f64> {
        self.rates.iter().zip(&self.targets).map(|(r, t)| (success(*r), *t)).find(|(p, t)| p >= t).map(|(p, _)| p)
    }

    /// Moves each bin that got new outcomes by Δ toward its target success ratio.
    fn adapt(&mut self, c: &AdaptiveConfig) {
        for i in 0..self.th.len() {
            if !std::mem::take(&mut self.fresh[i]) {
                continue;
            }
            let h = &self.hist[i];
            let p = h.iter().filter(|s| **s).count() as f64 / h.len() as f64;
            let target = self.targets[i];
            let delta = if p < target - c.tolerance {
                -c.step
            } else if p > target + c.tolerance {
                c.step
            } else {
                continue;
            };
            self.th[i] = (self.th[i] + delta).clamp(0.0, c.d_max);
            self.make_monotone(i);
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Mode {
    Data,
    Status,
}

/// The adaptive distance-bin selector.
#[derive(Debug, Clone)]
pub struct AdaptiveBins {
    cfg: AdaptiveConfig,
    data: BinArray,
    status: BinArray,
    /// Own attempts since the last confirmed success (unresolved ones count as failures).
    drought: u32,
    pending: BTreeMap<u64, (Mode, usize)>,
}

/// (rate, upper distance threshold m) from fastest to slowest.
pub type Thresholds = Vec<(Rate, f64)>;

const RATE_ORDER: [(usize, Rate); 4] = [(3, Rate::R5), (2, Rate::R4), (1, Rate::R1), (0, Rate::R0)];

impl AdaptiveBins {
    pub fn new(cfg: AdaptiveConfig) -> Result<Self, InvalidFields> {
        let mut problems = Problems::new();
        cfg.check_fields("", &mut problems);
        problems.finish()?;
        let enabled = |k: usize| cfg.targets[k] > 0.0;
        let data = RATE_ORDER
            .iter()
            .filter(|(k, _)| enabled(*k))
            .map(|&(k, r)| (r, cfg.targets[k], cfg.data_thresholds[k]))
            .collect();
        let mut status: Vec<(Rate, f64, f64)> = [(1usize, Rate::R1), (0, Rate::R0)]
            .iter()
            .filter(|(k, _)| enabled(*k))
            .map(|&(k, r)| (r, cfg.targets[k], cfg.status_thresholds[k]))
            .collect();
        if status.is_empty() {
            // No low rate enabled: the status bins use rate 1 at the lowest enabled target.
            let t = cfg.targets.iter().copied().filter(|t| *t > 0.0).fold(1.0, f64::min);
            status.push((Rate::R1, t, cfg.status_thresholds[1]));
        }
        Ok(AdaptiveBins {
            data: BinArray::new(data),
            status: BinArray::new(status),
            cfg,
            drought: 0,
            pending: BTreeMap::new(),
        })
    }

    pub fn mode(&self) -> Mode {
        if self.drought >= self.cfg.t_status {
            Mode::Status
        } else {
            Mode::Data
        }
    }

    /// Current thresholds (rate, upper distance m) of the data and status arrays.
    pub fn thresholds(&self) -> (Thresholds, Thresholds) {
        let z = |a: &BinArray| a.rates.iter().copied().zip(a.th.iter().copied()).collect();
        (z(&self.data), z(&self.status))
    }

    fn array(&mut self, m: Mode) -> &mut BinArray {
        match m {
            Mode::Data => &mut self.data,
            Mode::Status => &mut self.status,
        }
    }
}

impl RatePolicy for AdaptiveBins {
    fn name(&self) -> String {
        "adaptive".into()
    }
    fn rates(&self) -> Vec<Rate> {
        let mut r: Vec<Rate> = self.data.rates.iter().chain(&self.status.rates).copied().collect();
        r.sort();
        r.dedup();
        r
    }
    fn feedback(&mut self, resolved: &[Outcome], heard_peer: bool) {
        let memory = self.cfg.memory;
        for o in resolved {
            if let Some((m, i)) = self.pending.remove(&o.slot) {
                self.array(m).record(i, o.success, memory);
            }
            if o.success {
                self.drought = 0;
            }
        }
        if heard_peer && self.cfg.exit_status_on_heard {
            self.drought = 0;
        }
        let cfg = self.cfg.clone();
        self.data.adapt(&cfg);
        self.status.adapt(&cfg);
    }
    fn choose(&mut self, slot: u64, distance: Option<f64>) -> Choice {
        let mode = self.mode();
        // Unknown position: treat the peer as in range so a wrong or missing estimate cannot
        // lock the vehicle out (the thesis's field-trial bug, Nams 2014, §6.2).
        let d = distance.unwrap_or(0.0);
        let (drift_after, step, d_max) = (self.cfg.drift_after_slots, self.cfg.step, self.cfg.d_max);
        let a = self.array(mode);
        match a.choose(d, drift_after, step, d_max) {
            Some(i) => {
                let r = a.rates[i];
                self.pending.insert(slot, (mode, i));
                self.drought += 1;
                Choice::Transmit(r)
            }
            None => Choice::Silent,
        }
    }
    /// Invented (docs/models.md#nams-selector; the thesis never asks what its selector converges to): each
    /// bin's threshold moves until its rate's success there meets the rate's target, so with
    /// success falling with distance the settled selector sends at the fastest data rate whose
    /// success reaches its target; where none does, at the fastest such status rate (status
    /// mode); where none of those does either, it is silent.
    fn settled_success(&self, success: &dyn Fn(Rate) -> f64) -> f64 {
        [&self.data, &self.status].into_iter().find_map(|a| a.settled_success(success)).unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adaptive() -> AdaptiveBins {
        AdaptiveBins::new(AdaptiveConfig::default()).unwrap()
    }

    #[test]
    fn controls() {
        let mut f = FixedRate { rate: Rate::R1 };
        assert_eq!(f.choose(0, Some(1e9)), Choice::Transmit(Rate::R1));
        let mut a = Alternating::new(vec![Rate::R0, Rate::R5]);
        let picks: Vec<Choice> = (0..4).map(|k| a.choose(k, None)).collect();
        assert_eq!(
            picks,
            vec![
                Choice::Transmit(Rate::R0),
                Choice::Transmit(Rate::R5),
                Choice::Transmit(Rate::R0),
                Choice::Transmit(Rate::R5)
            ]
        );
        assert_eq!(a.name(), "alternating 0/5");
    }

    #[test]
    fn default_bins_pick_fast_near_slow_far_silent_beyond() {
        let mut s = adaptive();
        assert_eq!(s.rates(), vec![Rate::R1, Rate::R4]);
        assert_eq!(s.choose(0, Some(100.0)), Choice::Transmit(Rate::R4));
        assert_eq!(s.choose(2, Some(1000.0)), Choice::Transmit(Rate::R1));
        assert_eq!(s.choose(4, Some(2000.0)), Choice::Silent);
        assert_eq!(s.choose(6, None), Choice::Transmit(Rate::R4), "unknown position counts as in range");
    }

    /// Rate 4's bin collapsed by failures far out stays collapsed in the thesis's selector; with
    /// drift it moves out by Δ every `drift_after_slots` slots without a rate-4 choice, and rate 4
    /// is tried again once its bin reaches the recipient.
    #[test]
    fn a_collapsed_bin_drifts_back_out_only_when_asked() {
        let collapsed = |drift_after_slots| {
            let cfg = AdaptiveConfig { step: 100.0, memory: 2, drift_after_slots, ..AdaptiveConfig::default() };
            let mut s = AdaptiveBins::new(cfg).unwrap();
            for k in 0..4u64 {
                assert_eq!(s.choose(k, Some(50.0)), Choice::Transmit(Rate::R4));
                s.feedback(&[Outcome { slot: k, success: false }], true);
            }
            assert_eq!(s.thresholds().0[0], (Rate::R4, 0.0), "four failures at 100 m steps from 400 m");
            s
        };
        // The peer is heard every slot (no status mode).
        let choose_heard = |s: &mut AdaptiveBins, k| {
            s.feedback(&[], true);
            s.choose(k, Some(150.0))
        };
        let mut thesis = collapsed(0);
        assert!((4..100u64).all(|k| choose_heard(&mut thesis, k) == Choice::Transmit(Rate::R1)));
        let mut drifting = collapsed(3);
        let r4_at: Vec<u64> =
            (4..12u64).filter(|k| choose_heard(&mut drifting, *k) == Choice::Transmit(Rate::R4)).collect();
        // Slots 4–6 leave rate 4 idle; slot 7 moves its bin out to 100 m (short of 150 m), slot 10
        // to 200 m, and from then on 150 m falls in it.
        assert_eq!(r4_at, vec![10, 11]);
        assert_eq!(drifting.thresholds().0[0], (Rate::R4, 200.0));
    }

    /// `drift_after_slots` in a file: a count, refused otherwise naming the key; left out of
    /// what is written when 0 (the thesis's selector), so older manifests read the same.
    #[test]
    fn drift_after_slots_is_read_checked_and_written_only_when_set() {
        let parse = |text: &str| toml::from_str::<RatePolicySpec>(text);
        let err = parse("kind = \"adaptive\"\ndrift_after_slots = -1").unwrap_err().to_string();
        assert!(err.contains("drift_after_slots") || err.contains("u32"), "{err}");
        assert!(parse("kind = \"adaptive\"\ndrift_after_slot = 3")
            .unwrap_err()
            .to_string()
            .contains("drift_after_slots"));
        let RatePolicySpec::Adaptive(cfg) = parse("kind = \"adaptive\"\ndrift_after_slots = 10").unwrap() else {
            panic!("adaptive")
        };
        assert_eq!(cfg.drift_after_slots, 10);
        let written = |cfg: AdaptiveConfig| toml::to_string(&RatePolicySpec::Adaptive(cfg)).unwrap();
        assert!(written(cfg).contains("drift_after_slots = 10"));
        assert!(!written(AdaptiveConfig::default()).contains("drift_after_slots"));
    }

    #[test]
    fn bins_shrink_in_a_poor_channel_and_grow_in_a_good_one() {
        let mut s = adaptive();
        for k in 0..20u64 {
            assert_eq!(s.choose(2 * k, Some(100.0)), Choice::Transmit(Rate::R4));
            s.feedback(&[Outcome { slot: 2 * k, success: false }], true);
        }
        let (data, _) = s.thresholds();
        assert_eq!(data[0], (Rate::R4, 400.0 - 20.0 * 5.0));
        let mut g = adaptive();
        for k in 0..20u64 {
            g.choose(2 * k, Some(1000.0));
            g.feedback(&[Outcome { slot: 2 * k, success: true }], true);
        }
        assert_eq!(g.thresholds().0[1], (Rate::R1, 1600.0));
        // On target (p within τ of Π): no movement.
        let mut t = adaptive();
        for k in 0..10u64 {
            t.choose(2 * k, Some(100.0));
            t.feedback(&[Outcome { slot: 2 * k, success: k % 10 < 3 }], true);
        }
        let before = t.thresholds().0[0].1;
        t.choose(100, Some(100.0));
        t.feedback(&[Outcome { slot: 100, success: true }], true); // window: 3/10 → on target
        assert_eq!(t.thresholds().0[0].1, before);
    }

    #[test]
    fn settled_success_is_what_each_policy_delivers_once_it_has_learnt_the_link() {
        use rand::{rngs::StdRng, Rng, SeedableRng};
        // The share of own slots delivered over the last 2,000 of 4,000 at one distance, the
        // link giving each rate the success `table` says.
        let delivered = |policy: &mut dyn RatePolicy, d: f64, table: &dyn Fn(Rate) -> f64| {
            let mut rng = StdRng::seed_from_u64(7);
            let mut hits = 0;
            for slot in 0..4000u64 {
                let success = match policy.choose(slot, Some(d)) {
                    Choice::Transmit(r) => rng.gen_bool(table(r)),
                    Choice::Silent => false,
                };
                policy.feedback(&[Outcome { slot, success }], true);
                hits += usize::from(slot >= 2000 && success);
            }
            hits as f64 / 2000.0
        };
        let link = |r4: f64, r1: f64| {
            move |r: Rate| {
                if r == Rate::R4 {
                    r4
                } else if r == Rate::R1 {
                    r1
                } else {
                    0.95
                }
            }
        };
        // Rate 4 meets its target; it does not but rate 1 does; neither does (silent).
        for (d, r4, r1, settled) in [(300.0, 0.7, 0.9, 0.7), (300.0, 0.05, 0.8, 0.8), (1000.0, 0.0, 0.1, 0.0)] {
            let table = link(r4, r1);
            let mut s = adaptive();
            assert_eq!(s.settled_success(&table), settled);
            let got = delivered(&mut s, d, &table);
            assert!((got - settled).abs() < 0.05, "{d} m, r4 {r4} r1 {r1}: delivered {got}, settled {settled}");
        }
        let table = link(0.2, 0.6);
        let mut alternating = Alternating::new(vec![Rate::R4, Rate::R1]);
        assert!((alternating.settled_success(&table) - 0.4).abs() < 1e-12);
        assert!((delivered(&mut alternating, 1000.0, &table) - 0.4).abs() < 0.05);
        assert_eq!(FixedRate { rate: Rate::R1 }.settled_success(&table), 0.6);
    }

    #[test]
    fn thresholds_stay_monotone_and_bounded() {
        let mut s = adaptive();
        for k in 0..1000u64 {
            s.choose(2 * k, Some(1.0));
            s.feedback(&[Outcome { slot: 2 * k, success: true }], true);
        }
        let (d, _) = s.thresholds();
        assert_eq!(d[0].1, 5000.0);
        assert!(d[1].1 >= d[0].1, "rate 1's bin is pushed out with rate 4's: {d:?}");
    }

    #[test]
    fn drought_switches_to_status_bins_and_a_success_returns() {
        let mut s = adaptive();
        for k in 0..3u64 {
            assert_eq!(s.mode(), Mode::Data);
            s.choose(2 * k, Some(1000.0));
            s.feedback(&[], false);
        }
        assert_eq!(s.mode(), Mode::Status);
        assert_eq!(s.choose(6, Some(2000.0)), Choice::Transmit(Rate::R1), "status bins reach further");
        s.feedback(&[Outcome { slot: 6, success: true }], false);
        assert_eq!(s.mode(), Mode::Data);
    }

    #[test]
    fn policies_are_named_by_kind_in_a_file_and_bad_ones_are_refused() {
        let parse = |text: &str| toml::from_str::<RatePolicySpec>(text);
        let fixed = parse("kind = \"fixed\"\nrate = 1").unwrap();
        assert_eq!(fixed, RatePolicySpec::Fixed { rate: Rate::R1 });
        assert_eq!(fixed.build().unwrap().name(), "fixed rate 1");
        let alternating = parse("kind = \"alternating\"\nrates = [0, 5]").unwrap();
        assert_eq!(alternating.rates().unwrap(), [Rate::R0, Rate::R5]);
        let adaptive = parse("kind = \"adaptive\"\nmemory = 4").unwrap();
        assert_eq!(adaptive, RatePolicySpec::Adaptive(AdaptiveConfig { memory: 4, ..AdaptiveConfig::default() }));
        assert_eq!(adaptive.rates().unwrap(), [Rate::R1, Rate::R4]);
        assert!(parse("kind = \"fixed\"\nrate = 1\nspeed = 2").is_err(), "unknown fields are refused");
        assert!(parse("kind = \"adaptive\"\nmemroy = 4").is_err(), "unknown fields are refused");
        assert!(parse("kind = \"greedy\"").is_err());
        let deprecated = RatePolicySpec::Fixed { rate: Rate::new(2).unwrap() };
        assert_eq!(deprecated.rates().unwrap_err(), RatePolicyError::Rate(Rate::new(2).unwrap()));
        assert!(deprecated.rates().unwrap_err().to_string().contains("allowed 0, 1, 4 or 5"));
        assert_eq!(RatePolicySpec::Alternating { rates: vec![] }.rates().unwrap_err(), RatePolicyError::Rates(vec![]));
        let bad = RatePolicySpec::Adaptive(AdaptiveConfig { memory: 0, ..AdaptiveConfig::default() });
        let message = bad.rates().unwrap_err().to_string();
        assert!(message.contains("adaptive selector") && message.contains("field memory"), "{message}");
        assert_eq!(bad.label(), "invalid");
        let thesis = RatePolicySpec::thesis();
        let labels: Vec<String> = thesis.iter().map(RatePolicySpec::label).collect();
        assert_eq!(labels, ["fixed rate 0", "fixed rate 1", "alternating 0/5", "adaptive"]);
        assert_eq!(thesis.iter().map(RatePolicySpec::is_control).collect::<Vec<_>>(), [true, true, true, false]);
    }

    #[test]
    fn config_validation_names_the_field() {
        let bad = AdaptiveConfig { tolerance: 0.9, ..AdaptiveConfig::default() };
        assert_eq!(AdaptiveBins::new(bad).unwrap_err().0[0].field, "tolerance");
        let none = AdaptiveConfig { targets: [0.0; 4], ..AdaptiveConfig::default() };
        assert_eq!(AdaptiveBins::new(none).unwrap_err().0[0].field, "targets");
        let far = AdaptiveConfig { data_thresholds: [1.0, 1.0, 9999.0, 1.0], ..AdaptiveConfig::default() };
        assert_eq!(AdaptiveBins::new(far).unwrap_err().0[0].field, "data_thresholds[2]");
        // Every bad field at once, each named.
        let many = AdaptiveConfig { memory: 0, step: -1.0, targets: [0.0, 2.0, 0.3, 0.0], ..AdaptiveConfig::default() };
        let fields: Vec<String> = AdaptiveBins::new(many).unwrap_err().0.into_iter().map(|p| p.field).collect();
        assert_eq!(fields, ["memory", "step", "targets[1]"]);
    }
}
