//! Thesis reproductions: each experiment is a named function that runs our models on the thesis's
//! set-up (or our recorded reconstruction of it), and returns our numbers beside the thesis's,
//! each thesis number compared in a stated band ([`ThesisTable`]), plus the property checks
//! (trends, orderings) that must hold.
//!
//! `coopnav reproduce <id>` runs one; CI runs the reduced forms through the sim crate's tests.

pub mod aiding;
pub mod closed_loop;
pub mod cna_navigation;
pub mod generalization;
pub mod gill;
pub mod hudson;
mod hudson_appendix_a;
pub mod missions;
pub mod nams;
pub mod study_dir;

use serde::Serialize;
use thiserror::Error;

/// How big a reproduction to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// The thesis's full set-up (number of runs, sweep ranges).
    Full,
    /// A reduced form for CI: fewer runs or a thinner sweep, with bands widened by the Monte
    /// Carlo standard error where the experiment is statistical.
    Reduced,
}

/// Called once after each simulation run a reproduction finishes, from any thread, with the number
/// of runs its current batch has finished (a reproduction may run several batches, each counting
/// from 1). Reproductions that run no closed-loop simulations (the planner-only tables) never call it.
pub type Progress<'a> = dyn Fn(u64) + Sync + 'a;

/// How to run a reproduction: its size, its base seed and whom to tell of its progress.
#[derive(Clone, Copy)]
pub struct ReproOptions<'a> {
    pub size: Size,
    /// Base seed; run i uses `coopnav_core::run_seed(seed, i)`.
    pub seed: u64,
    pub progress: &'a Progress<'a>,
}

impl ReproOptions<'static> {
    /// `size` from base seed `seed`, telling no one of its progress.
    pub fn new(size: Size, seed: u64) -> Self {
        ReproOptions { size, seed, progress: &|_| {} }
    }
}

impl Default for ReproOptions<'static> {
    fn default() -> Self {
        ReproOptions::new(Size::Full, 1)
    }
}

impl std::fmt::Debug for ReproOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReproOptions").field("size", &self.size).field("seed", &self.seed).finish_non_exhaustive()
    }
}

/// How a check or a thesis table came out. `Undecided` is itself a measured outcome: the run's
/// evidence cannot tell the two answers apart (a paired difference whose 95 % CI spans zero), or
/// the run does not reproduce the quantity compared (a reduced form's shortened missions), and
/// the output says which.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Pass,
    Fail,
    Undecided,
}

/// One property a reproduction must show (a trend, an ordering, a band).
#[derive(Debug, Clone, Serialize)]
pub struct Check {
    pub name: String,
    pub verdict: Verdict,
    pub detail: String,
    /// Set only when the run itself measured why the check failed (an experiment whose outcome
    /// is printed here); a failure with a measured cause still fails the check, and
    /// `coopnav reproduce` exits 3 instead of 1 when every failure has one.
    pub cause: Option<String>,
}

impl Check {
    pub fn new(name: impl Into<String>, passed: bool, detail: impl Into<String>) -> Self {
        let verdict = if passed { Verdict::Pass } else { Verdict::Fail };
        Check { name: name.into(), verdict, detail: detail.into(), cause: None }
    }

    /// A check with a three-way outcome.
    pub fn with_verdict(name: impl Into<String>, verdict: Verdict, detail: impl Into<String>) -> Self {
        Check { name: name.into(), verdict, detail: detail.into(), cause: None }
    }

    /// Attaches the cause the run measured for a failure (ignored unless the check failed: a
    /// cause explains a failure, it is never attached in advance).
    pub fn caused_by(self, measured: Option<String>) -> Self {
        match self.verdict {
            Verdict::Fail => Check { cause: measured, ..self },
            _ => self,
        }
    }

    pub fn passed(&self) -> bool {
        self.verdict == Verdict::Pass
    }

    /// Failed with no measured cause.
    pub fn unexplained(&self) -> bool {
        self.verdict == Verdict::Fail && self.cause.is_none()
    }

    /// What CI requires: passed, undecided, or failed with its measured cause printed.
    pub fn acceptable(&self) -> bool {
        !self.unexplained()
    }

    /// One report line: `[pass]`, `[FAIL]`, `[FAIL, measured cause]` or `[undecided]`, and the
    /// cause.
    pub fn line(&self) -> String {
        let tag = match (self.verdict, &self.cause) {
            (Verdict::Pass, _) => "pass",
            (Verdict::Undecided, _) => "undecided",
            (Verdict::Fail, None) => "FAIL",
            (Verdict::Fail, Some(_)) => "FAIL, measured cause",
        };
        let mut line = format!("[{tag}] {}: {}", self.name, self.detail);
        if let (Verdict::Fail, Some(why)) = (self.verdict, &self.cause) {
            line.push_str(&format!("\n      measured cause: {why}"));
        }
        line
    }
}

/// How far from a thesis number ours may lie and still count as reproducing it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Band {
    /// thesis ± `plus_minus` (in the number's unit).
    Absolute { plus_minus: f64 },
    /// thesis ± `percent` % of |thesis|.
    Relative { percent: f64 },
    /// The wider of the two.
    Wider { plus_minus: f64, percent: f64 },
    /// An explicit range (the thesis's own spread, e.g. a 95 % CI).
    Range { low: f64, high: f64 },
}

impl Band {
    /// The band's bounds around thesis value `thesis`.
    pub fn interval(&self, thesis: f64) -> (f64, f64) {
        let half = |pm: f64, pct: f64| pm.max(thesis.abs() * pct / 100.0);
        match *self {
            Band::Absolute { plus_minus } => (thesis - plus_minus, thesis + plus_minus),
            Band::Relative { percent } => (thesis - half(0.0, percent), thesis + half(0.0, percent)),
            Band::Wider { plus_minus, percent } => {
                (thesis - half(plus_minus, percent), thesis + half(plus_minus, percent))
            }
            Band::Range { low, high } => (low, high),
        }
    }

    /// Whether `ours` lies in the band around `thesis` (a non-finite value never does). The
    /// bounds get 1e-9 of slack so that a value printed to the thesis's precision on a bound
    /// is not lost to rounding.
    pub fn contains(&self, thesis: f64, ours: f64) -> bool {
        let (lo, hi) = self.interval(thesis);
        ours.is_finite() && ours >= lo - 1e-9 && ours <= hi + 1e-9
    }

    /// The band as printed: `±0.10`, `±20 %`, `±0.20 or ±17 %`, `[0.07, 0.37]`.
    pub fn describe(&self) -> String {
        match *self {
            Band::Absolute { plus_minus } => format!("±{plus_minus}"),
            Band::Relative { percent } => format!("±{percent} %"),
            Band::Wider { plus_minus, percent } => format!("±{plus_minus} or ±{percent} %"),
            Band::Range { low, high } => format!("[{low}, {high}]"),
        }
    }
}

/// One number the thesis prints, ours beside it, and its band.
#[derive(Debug, Clone, Serialize)]
pub struct ThesisNumber {
    pub label: String,
    pub thesis: f64,
    /// `None` when this run does not reproduce the number (a reduced form's shortened missions,
    /// a set-up the sweep skipped): it is listed and not compared.
    pub ours: Option<f64>,
    pub band: Band,
    /// The band's bounds around the thesis value.
    pub low: f64,
    pub high: f64,
    /// `Some(true)` inside the band, `Some(false)` outside, `None` not compared.
    pub within: Option<bool>,
}

impl ThesisNumber {
    pub fn new(label: impl Into<String>, thesis: f64, ours: Option<f64>, band: Band) -> Self {
        let (low, high) = band.interval(thesis);
        let within = ours.map(|o| band.contains(thesis, o));
        ThesisNumber { label: label.into(), thesis, ours, band, low, high, within }
    }
}

/// Share of a table's compared numbers that must lie inside their bands.
pub const SHARE_REQUIRED: f64 = 0.8;

/// A thesis table's numbers, compared in one band stated once with its reason. The table passes
/// when at least `share_required` of the numbers this run compares lie inside; it is undecided
/// when the run compares none of them.
#[derive(Debug, Clone, Serialize)]
pub struct ThesisTable {
    pub id: String,
    pub numbers: Vec<ThesisNumber>,
    pub share_required: f64,
    pub band_reason: String,
    /// How many numbers this run compares, and how many of those lie inside their bands.
    pub compared: usize,
    pub within: usize,
    pub verdict: Verdict,
    /// Set only when the run measured why the table fell below its share.
    pub cause: Option<String>,
    /// Why the numbers this run lists and does not compare were not compared (a reduced form's
    /// shortened missions, set-ups a full sweep did not run); printed beside the count.
    pub not_compared: Option<String>,
}

impl ThesisTable {
    pub fn new(id: impl Into<String>, band_reason: impl Into<String>, numbers: Vec<ThesisNumber>) -> Self {
        let compared = numbers.iter().filter(|n| n.within.is_some()).count();
        let within = numbers.iter().filter(|n| n.within == Some(true)).count();
        let verdict = table_verdict(compared, within, SHARE_REQUIRED);
        ThesisTable {
            id: id.into(),
            numbers,
            share_required: SHARE_REQUIRED,
            band_reason: band_reason.into(),
            compared,
            within,
            verdict,
            cause: None,
            not_compared: None,
        }
    }

    /// Says why the numbers not compared were not (ignored when the run compares every one).
    pub fn not_compared_because(self, why: impl Into<String>) -> Self {
        if self.compared < self.numbers.len() {
            ThesisTable { not_compared: Some(why.into()), ..self }
        } else {
            self
        }
    }

    /// `" (compares k of M: why)"` when the run compares fewer than it lists, else nothing.
    fn compared_note(&self) -> String {
        compared_note(self.compared, self.numbers.len(), self.not_compared.iter().map(String::as_str))
    }

    /// Attaches the cause the run measured for the table falling below its share (ignored
    /// unless it did).
    pub fn caused_by(self, measured: Option<String>) -> Self {
        match self.verdict {
            Verdict::Fail => ThesisTable { cause: measured, ..self },
            _ => self,
        }
    }

    pub fn unexplained(&self) -> bool {
        self.verdict == Verdict::Fail && self.cause.is_none()
    }

    /// The table as printed: every compared number with its band and whether ours lies inside
    /// (the numbers not compared are counted, not listed), then
    /// `"<id>: N of M thesis numbers within their bands"` and its verdict line.
    pub fn printed(&self) -> String {
        let mut s = format!("\n{} — band: {}\n", self.id, self.band_reason);
        for n in self.numbers.iter().filter(|n| n.within.is_some()) {
            let (ours, mark) = match (n.ours, n.within) {
                (Some(o), Some(true)) => (format!("{o:.3}"), "in"),
                (Some(o), _) => (format!("{o:.3}"), "OUT"),
                (None, _) => ("-".to_string(), "not compared"),
            };
            s.push_str(&format!(
                "  {:<44} thesis {:>9.3}  ours {:>9}  band {:>16} [{:.3}, {:.3}]  {mark}\n",
                n.label,
                n.thesis,
                ours,
                n.band.describe(),
                n.low,
                n.high
            ));
        }
        let mut summary =
            format!("{}: {} of {} thesis numbers within their bands", self.id, self.within, self.compared);
        summary.push_str(&self.compared_note());
        let tag = match (self.verdict, &self.cause) {
            (Verdict::Pass, _) => "pass",
            (Verdict::Undecided, _) => "undecided",
            (Verdict::Fail, None) => "FAIL",
            (Verdict::Fail, Some(_)) => "FAIL, measured cause",
        };
        s.push_str(&format!("[{tag}] {summary}; {:.0} % required\n", self.share_required * 100.0));
        if let (Verdict::Fail, Some(why)) = (self.verdict, &self.cause) {
            s.push_str(&format!("      measured cause: {why}\n"));
        }
        s
    }
}

/// `" (compares k of M: why; why2)"` when `compared < listed`, each distinct reason once in the
/// order given; `" (compares k of M: not said why)"` when no reason is given; else nothing.
fn compared_note<'a>(compared: usize, listed: usize, why: impl Iterator<Item = &'a str>) -> String {
    if compared >= listed {
        return String::new();
    }
    let mut reasons: Vec<&str> = Vec::new();
    for w in why {
        if !reasons.contains(&w) {
            reasons.push(w);
        }
    }
    let why = if reasons.is_empty() { "not said why".to_string() } else { reasons.join("; ") };
    format!(" (compares {compared} of {listed}: {why})")
}

/// A table's verdict from its counts: undecided when nothing is compared, else pass when
/// `within / compared >= share`.
pub fn table_verdict(compared: usize, within: usize, share: f64) -> Verdict {
    if compared == 0 {
        Verdict::Undecided
    } else if within as f64 >= share * compared as f64 - 1e-9 {
        Verdict::Pass
    } else {
        Verdict::Fail
    }
}

/// Totals over a report's thesis tables.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BandTotals {
    /// Every thesis number listed, compared or not.
    pub listed: usize,
    pub compared: usize,
    pub within: usize,
}

/// How a reproduction came out, as `coopnav reproduce`'s exit status reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// No check and no table failed (some may be undecided): exit 0.
    NoFailure,
    /// `n` checks or tables failed, each with its measured cause printed: exit 3.
    CausesMeasured(usize),
    /// `n` checks or tables failed without a measured cause: exit 1.
    Unexplained(usize),
}

/// What a reproduction returns: a human-readable table (ours beside the thesis's), the checks,
/// the thesis numbers compared in their bands, the same numbers as JSON, and its plots (SVG,
/// each with its file name; `reproduce -o` writes them).
#[derive(Debug, Clone, Serialize)]
pub struct ReproReport {
    pub id: String,
    pub table: String,
    pub checks: Vec<Check>,
    pub thesis_tables: Vec<ThesisTable>,
    pub band_totals: BandTotals,
    pub data: serde_json::Value,
    #[serde(skip)]
    pub plots: Vec<(String, String)>,
}

impl ReproReport {
    pub fn new(id: String, table: String, checks: Vec<Check>, data: serde_json::Value) -> Self {
        ReproReport {
            id,
            table,
            checks,
            thesis_tables: Vec::new(),
            band_totals: BandTotals::default(),
            data,
            plots: Vec::new(),
        }
    }

    /// Adds thesis tables (and updates the totals).
    pub fn with_tables(mut self, tables: Vec<ThesisTable>) -> Self {
        self.thesis_tables.extend(tables);
        self.band_totals = BandTotals {
            listed: self.thesis_tables.iter().map(|t| t.numbers.len()).sum(),
            compared: self.thesis_tables.iter().map(|t| t.compared).sum(),
            within: self.thesis_tables.iter().map(|t| t.within).sum(),
        };
        self
    }

    pub fn all_passed(&self) -> bool {
        self.checks.iter().all(Check::passed) && self.thesis_tables.iter().all(|t| t.verdict == Verdict::Pass)
    }

    /// Whether every check and table is acceptable to CI: passed, undecided, or failed with its
    /// measured cause.
    pub fn acceptable(&self) -> bool {
        self.checks.iter().all(Check::acceptable) && self.thesis_tables.iter().all(|t| !t.unexplained())
    }

    /// The outcome over every check and thesis table.
    pub fn outcome(&self) -> Outcome {
        let failed = self.checks.iter().filter(|c| c.verdict == Verdict::Fail).count()
            + self.thesis_tables.iter().filter(|t| t.verdict == Verdict::Fail).count();
        let unexplained = self.checks.iter().filter(|c| c.unexplained()).count()
            + self.thesis_tables.iter().filter(|t| t.unexplained()).count();
        match (failed, unexplained) {
            (0, _) => Outcome::NoFailure,
            (n, 0) => Outcome::CausesMeasured(n),
            (_, n) => Outcome::Unexplained(n),
        }
    }

    /// The table, the thesis numbers in their bands, and one line per check, as
    /// `coopnav reproduce` prints it (and writes it to `table.txt`).
    pub fn printed(&self) -> String {
        let mut out = self.table.clone();
        for t in &self.thesis_tables {
            out.push_str(&t.printed());
        }
        if !self.thesis_tables.is_empty() {
            let b = self.band_totals;
            let mut line = format!("{}: {} of {} thesis numbers within their bands", self.id, b.within, b.compared);
            if b.compared > 0 {
                line.push_str(&format!(" ({:.0} %)", 100.0 * b.within as f64 / b.compared as f64));
            }
            let why = self.thesis_tables.iter().filter_map(|t| t.not_compared.as_deref());
            line.push_str(&compared_note(b.compared, b.listed, why));
            out.push_str(&format!("\n{line}\n"));
        }
        let lines: Vec<String> = self.checks.iter().map(Check::line).collect();
        format!("{}\n{}", out, lines.join("\n"))
    }
}

/// The three-way verdict of an ordering measured as a difference with a 95 % CI
/// `[low, high]` (ours oriented so that the thesis's ordering is `low > 0`): pass when the CI
/// lies above zero, fail when it lies below (significantly reversed), undecided when it spans
/// zero.
pub fn ordering_verdict(low: f64, high: f64) -> Verdict {
    if !(low.is_finite() && high.is_finite()) {
        Verdict::Fail
    } else if low > 0.0 {
        Verdict::Pass
    } else if high < 0.0 {
        Verdict::Fail
    } else {
        Verdict::Undecided
    }
}

#[derive(Debug, Error)]
pub enum ExperimentError {
    #[error("unknown experiment '{0}'; run `coopnav reproduce --list` to see the available ones")]
    Unknown(String),
    #[error("experiment {id}: {message}")]
    Failed { id: String, message: String },
}

/// A registered reproduction.
pub struct Experiment {
    pub id: &'static str,
    pub about: &'static str,
    pub run: fn(&ReproOptions) -> Result<ReproReport, ExperimentError>,
}

/// Every reproduction coopnav knows, in a stable order. Each thesis adds its own entries
/// from its own module.
pub fn registry() -> Vec<Experiment> {
    let mut all = Vec::new();
    all.extend(hudson::experiments());
    all.extend(gill::experiments());
    all.extend(nams::experiments());
    all.extend(closed_loop::experiments());
    all.extend(cna_navigation::experiments());
    all.extend(generalization::experiments());
    all.extend(aiding::experiments());
    all
}

/// The reproductions whose cells are a sweep file and whose report a sweep's merged runs give
/// (the sweep file's `report` key).
pub const SWEEP_REPORTS: [&str; 1] = ["closed-loop-vs-baselines"];

/// The report of reproduction `id` (one of [`SWEEP_REPORTS`]) from cells already run: each
/// cell's (base scenario name, scenario) and its comparison, `runs` runs per policy, every cell
/// from the same base seed.
pub fn sweep_report(
    id: &str,
    cells: &[(&str, &crate::scenario::Scenario)],
    comparisons: Vec<crate::batch::mc::Comparison>,
    runs: usize,
) -> Result<ReproReport, ExperimentError> {
    if !SWEEP_REPORTS.contains(&id) {
        return Err(ExperimentError::Unknown(id.to_string()));
    }
    let seeds: std::collections::BTreeSet<u64> = cells.iter().map(|(_, s)| s.seed).collect();
    let [seed] = seeds.iter().copied().collect::<Vec<_>>()[..] else {
        let message = format!("its cells must share one base seed, and they have {seeds:?}");
        return Err(ExperimentError::Failed { id: id.to_string(), message });
    };
    closed_loop::report(cells, comparisons, runs, seed)
}

/// Runs the experiment named `id`.
pub fn run(id: &str, opts: &ReproOptions) -> Result<ReproReport, ExperimentError> {
    let exp = registry().into_iter().find(|e| e.id == id).ok_or_else(|| ExperimentError::Unknown(id.to_string()))?;
    (exp.run)(opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_hold_their_bounds_and_reject_outside() {
        let abs = Band::Absolute { plus_minus: 0.10 };
        assert!(abs.contains(2.22, 2.32) && abs.contains(2.22, 2.12));
        assert!(!abs.contains(2.22, 2.33) && !abs.contains(2.22, 2.11));
        let rel = Band::Relative { percent: 20.0 };
        assert!(rel.contains(5.0, 6.0) && !rel.contains(5.0, 6.01) && !rel.contains(-5.0, -6.01));
        let wider = Band::Wider { plus_minus: 0.20, percent: 17.0 };
        // ±0.20 wins at small values, ±17 % at large ones.
        assert!(wider.contains(0.0, 0.2) && !wider.contains(0.0, 0.21));
        assert!(wider.contains(2.0, 2.34) && !wider.contains(2.0, 2.35));
        let range = Band::Range { low: 0.07, high: 0.37 };
        assert!(range.contains(0.22, 0.07) && !range.contains(0.22, 0.05));
        assert!(!abs.contains(2.22, f64::NAN) && !abs.contains(2.22, f64::INFINITY));
    }

    #[test]
    fn a_table_passes_at_its_share_and_fails_below_it() {
        let band = Band::Relative { percent: 20.0 };
        let numbers =
            |ours: &[Option<f64>]| ours.iter().map(|&o| ThesisNumber::new("x", 10.0, o, band)).collect::<Vec<_>>();
        // Four of five inside: exactly 80 %.
        let t = ThesisTable::new("t", "r", numbers(&[Some(10.0), Some(11.0), Some(9.0), Some(12.0), Some(13.0)]));
        assert_eq!((t.compared, t.within, t.verdict), (5, 4, Verdict::Pass));
        // Three of five: below.
        let t = ThesisTable::new("t", "r", numbers(&[Some(10.0), Some(11.0), Some(9.0), Some(14.0), Some(13.0)]));
        assert_eq!(t.verdict, Verdict::Fail);
        assert!(t.unexplained() && !t.clone().caused_by(Some("m".into())).unexplained());
        // Nothing reproduced: undecided, and the output says how many it compares.
        let t = ThesisTable::new("t", "r", numbers(&[None, None]));
        assert_eq!(t.verdict, Verdict::Undecided);
        assert!(t.printed().contains("t: 0 of 0 thesis numbers within their bands (compares 0 of 2: not said why)"));
        // Only the compared numbers count.
        let t = ThesisTable::new("t", "r", numbers(&[Some(10.0), None, Some(30.0)]));
        assert_eq!((t.compared, t.within, t.verdict), (2, 1, Verdict::Fail));
        assert_eq!(table_verdict(10, 8, 0.8), Verdict::Pass);
        assert_eq!(table_verdict(10, 7, 0.8), Verdict::Fail);
    }

    #[test]
    fn the_count_of_numbers_compared_says_why_the_rest_were_not() {
        let band = Band::Relative { percent: 20.0 };
        let numbers =
            |ours: &[Option<f64>]| ours.iter().map(|&o| ThesisNumber::new("x", 10.0, o, band)).collect::<Vec<_>>();
        let report = |tables: Vec<ThesisTable>| {
            ReproReport::new("r".into(), String::new(), vec![], serde_json::Value::Null).with_tables(tables)
        };
        // A reduced form that compares none of its numbers says it is reduced.
        let reduced = ThesisTable::new("a", "r", numbers(&[None, None, None]))
            .not_compared_because("reduced form: 900 s missions");
        let text = reduced.printed();
        assert!(text
            .contains("a: 0 of 0 thesis numbers within their bands (compares 0 of 3: reduced form: 900 s missions)"));
        // A full form that skipped set-ups says so, and does not call itself reduced.
        let skipped = ThesisTable::new("b", "r", numbers(&[Some(10.0), Some(10.0), None, None]))
            .not_compared_because("2 set-ups over the leaf cap not run");
        let text = skipped.printed();
        assert!(text.contains(
            "b: 2 of 2 thesis numbers within their bands (compares 2 of 4: 2 set-ups over the leaf cap not run)"
        ));
        assert!(!text.contains("reduced"));
        // A table that compares every number prints no note, even when given a reason.
        let whole = ThesisTable::new("c", "r", numbers(&[Some(10.0)])).not_compared_because("never printed");
        assert!(whole.not_compared.is_none() && !whole.printed().contains("compares"));
        // The report's total names each table's reason once.
        let again = ThesisTable::new("d", "r", numbers(&[None])).not_compared_because("reduced form: 900 s missions");
        let text = report(vec![reduced, skipped, whole, again]).printed();
        assert!(text.contains(
            "r: 3 of 3 thesis numbers within their bands (100 %) (compares 3 of 9: reduced form: 900 s missions; \
             2 set-ups over the leaf cap not run)"
        ));
    }

    #[test]
    fn orderings_are_three_way() {
        assert_eq!(ordering_verdict(0.07, 0.37), Verdict::Pass);
        assert_eq!(ordering_verdict(-0.10, 0.20), Verdict::Undecided);
        assert_eq!(ordering_verdict(-0.30, -0.01), Verdict::Fail);
        assert_eq!(ordering_verdict(f64::NAN, 1.0), Verdict::Fail);
    }

    #[test]
    fn a_cause_is_kept_only_on_a_failure() {
        let pass = Check::new("a", true, "").caused_by(Some("m".into()));
        assert!(pass.cause.is_none() && pass.line().starts_with("[pass]"));
        let und = Check::with_verdict("u", Verdict::Undecided, "").caused_by(Some("m".into()));
        assert!(und.cause.is_none() && und.acceptable() && und.line().starts_with("[undecided]"));
        let bad = Check::new("c", false, "");
        assert!(!bad.acceptable() && bad.line().starts_with("[FAIL] c"));
        let known = bad.clone().caused_by(Some("measured".into()));
        assert!(known.acceptable() && known.line().starts_with("[FAIL, measured cause] c"));
    }

    #[test]
    fn the_outcome_counts_checks_and_tables() {
        let table = |ours: f64| {
            ThesisTable::new(
                "t",
                "r",
                vec![ThesisNumber::new("x", 1.0, Some(ours), Band::Absolute { plus_minus: 0.1 })],
            )
        };
        let report = |checks: Vec<Check>, tables: Vec<ThesisTable>| {
            ReproReport::new("r".into(), String::new(), checks, serde_json::Value::Null).with_tables(tables)
        };
        let pass = Check::new("a", true, "");
        let undecided = Check::with_verdict("u", Verdict::Undecided, "");
        let caused = Check::new("b", false, "").caused_by(Some("m".into()));
        assert_eq!(report(vec![pass.clone(), undecided], vec![table(1.0)]).outcome(), Outcome::NoFailure);
        assert_eq!(report(vec![pass.clone(), caused.clone()], vec![table(1.0)]).outcome(), Outcome::CausesMeasured(1));
        assert_eq!(report(vec![pass.clone(), caused.clone()], vec![table(2.0)]).outcome(), Outcome::Unexplained(1));
        let explained_table = table(2.0).caused_by(Some("m".into()));
        assert_eq!(report(vec![pass, caused], vec![explained_table]).outcome(), Outcome::CausesMeasured(2));
        let r = report(vec![], vec![table(1.0), table(2.0)]);
        assert_eq!(r.band_totals, BandTotals { listed: 2, compared: 2, within: 1 });
        assert!(r.printed().contains("r: 1 of 2 thesis numbers within their bands (50 %)"));
    }
}
