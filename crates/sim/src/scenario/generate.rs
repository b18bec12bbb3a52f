//! Seeded mission generator: the missions a field team flies, drawn from ranges stated in a file
//! (`scenarios/generators/generalization.toml`, `scenarios/generators/aiding-never-hurts.toml`), each a full closed-loop
//! scenario that `coopnav simulate` accepts.
//!
//! The file holds the data (how many AUVs, which block layouts, lane headings, currents, CNA
//! kinds, channels, filters, durations); this module holds the model that turns one draw into a
//! mission. A mission starts from the embedded example (`coopnav simulate --example`) and changes
//! only the facts a team knows before launch:
//! - **Fleet**: N AUVs, each on its own lawnmower block (lane length, spacing and count drawn per
//!   mission, shared by the fleet), every lane on the drawn heading, lanes stepping right.
//! - **Layout** ([`Layout`]): blocks side by side, side by side with gaps, corner to corner along a
//!   diagonal, or in groups more than a kilometre apart. The fleet's footprint is centred on the
//!   origin.
//! - **Current**: a constant current of the drawn speed towards the drawn compass direction; the
//!   CNA's ADCP measures it (`cna.adcp_current`), as a team's would.
//! - **CNA**: it starts 100 m short of the first lane of a drawn block, on the lane heading (where
//!   a team launching from that block would put it in the water).
//! - **Duration**: drawn in hours, to the whole minute. Headings are drawn to 0.1°, lengths and
//!   depths to 1 m, current speeds to 1 mm/s and directions to 1°, as a team would state them.
//! - Named variants (CNA kind, channel, filter) and fleet-size rules (a schedule sized for the
//!   fleet) are TOML tables laid over the scenario ([`overlay`]): what each means is in the file.
//!   A filter variant may also set the position process noise from the drawn current
//!   ([`PositionNoise`]).
//!
//! A generated mission states no policy keys: its policies are what a file without `[policy]`
//! gets ([`Policies::default`]), `planner-estimator`'s settings the planner's rule for the mission
//! (coopnav_plan `auto`). Mission i's seed is the file's `seed` + i: the same file and index
//! always give the same mission, and its Monte Carlo run j uses `run_seed(mission seed, j)`.
//! Every draw of a mission comes from its own seed, in a fixed order, whether or not the layout
//! uses it, so one mission never depends on another.

use crate::models::mower::{MowerSpec, Turn};
use crate::scenario::file::{self as scenario_file, overlay, Problems, ScenarioError};
use crate::scenario::world::{Policies, Scenario};
use coopnav_core::{CompassDeg, Heading};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How the survey blocks lie relative to each other.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// Side by side, one lane spacing apart.
    Adjacent,
    /// Side by side with a gap drawn from `spread_gap_m`.
    Spread,
    /// Corner to corner: each block one block length along and one block width across from the
    /// previous one (plus a lane spacing each way).
    Diagonal,
    /// In groups of adjacent blocks (`separated_groups`), the groups `separated_gap_m` apart, so a
    /// CNA serving every group must commute between them.
    Separated,
}

impl Layout {
    pub fn name(self) -> &'static str {
        match self {
            Layout::Adjacent => "adjacent",
            Layout::Spread => "spread",
            Layout::Diagonal => "diagonal",
            Layout::Separated => "separated",
        }
    }
}

/// A named variant: a TOML table laid over the scenario (empty: the example's own).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub name: String,
    #[serde(default)]
    pub patch: toml::Table,
    /// A filter variant's horizontal position process noise from the mission's stated current
    /// ([`PositionNoise`]); absent: the patched scenario's own `filter.q`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_noise: Option<PositionNoise>,
}

/// The survey AUVs' horizontal position process noise set from the current the team states
/// (`cna.adcp_current`, the mission's drawn current): per axis, `still_m2_s` + `per_current_s`·|c|²
/// m²/s, written as `filter.q[0]` and `filter.q[1]` per filter step (`filter.step_s`).
///
/// Why: a filter that does not model the current stands for it by this random walk. One constant
/// is too large in near-still water (the position σ across a steady line of sight grows far faster
/// than the true error, and the filter is under-confident) and too small in a strong current. The
/// current's drift c·t matches a random walk q·t over t = q/c², so the noise grows as c². Both
/// coefficients are invented and were set on the embedded example's seed 1 only
/// (docs/models.md#position-noise): `still_m2_s` where its ranged filters' mean NEES is near 2 in
/// still water, `per_current_s` so that its own 0.05 m/s current gives back the closed loop's
/// position noise (`scenario::world::CLOSED_LOOP_Q_EN`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PositionNoise {
    /// Position noise in still water, m²/s per axis (≥ 0).
    pub still_m2_s: f64,
    /// Seconds of the current's drift the noise adds per (m/s)² of stated current (≥ 0).
    pub per_current_s: f64,
}

impl PositionNoise {
    /// Per-axis position noise per filter step of `step_s` seconds at a stated current of
    /// `speed_m_s`.
    pub fn per_step(&self, speed_m_s: f64, step_s: f64) -> f64 {
        (self.still_m2_s + self.per_current_s * speed_m_s * speed_m_s) * step_s
    }
}

/// A table laid over every mission of at least `min_auvs` AUVs (after the variants; rules apply
/// in file order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizeRule {
    pub min_auvs: usize,
    pub patch: toml::Table,
}

/// The generator's file: its seed, how many missions, and the ranges every fact is drawn from
/// (`[lo, hi]`, uniform, both ends included; lists: one entry drawn uniformly).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ranges {
    /// Mission i's seed is `seed + i`.
    pub seed: u64,
    pub missions: usize,
    pub n_auvs: [usize; 2],
    pub layouts: Vec<Layout>,
    pub lane_heading_deg: [f64; 2],
    pub lane_length_m: [f64; 2],
    pub lane_spacing_m: [f64; 2],
    pub lanes: [usize; 2],
    /// Gap between blocks of the `spread` layout, m.
    pub spread_gap_m: [f64; 2],
    /// Gap between groups of the `separated` layout, m.
    pub separated_gap_m: [f64; 2],
    /// Groups of the `separated` layout (at most N).
    pub separated_groups: [usize; 2],
    /// Current speed, m/s (its compass direction is drawn from 0–360°).
    pub current_m_s: [f64; 2],
    pub duration_h: [f64; 2],
    /// The survey AUVs' depth, m.
    pub depth_m: [f64; 2],
    pub cna: Vec<Variant>,
    pub channel: Vec<Variant>,
    pub filter: Vec<Variant>,
    #[serde(default)]
    pub fleet_size: Vec<SizeRule>,
}

/// What was drawn for one mission: the facts its report names.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Facts {
    pub index: usize,
    pub seed: u64,
    pub n_auvs: usize,
    pub layout: Layout,
    /// Gap between neighbouring blocks (spread) or groups (separated), m; None otherwise.
    pub gap_m: Option<f64>,
    pub groups: usize,
    pub lane_heading_deg: f64,
    pub lane_length_m: f64,
    pub lane_spacing_m: f64,
    pub lanes: usize,
    pub current_m_s: f64,
    /// Compass direction the current flows towards, deg.
    pub current_towards_deg: f64,
    pub cna: String,
    pub channel: String,
    pub filter: String,
    pub duration_s: f64,
    pub depth_m: f64,
    /// The block the CNA starts at.
    pub cna_block: usize,
    /// Largest distance between two blocks' centres, m.
    pub fleet_span_m: f64,
}

impl Facts {
    /// One line naming every fact.
    pub fn line(&self) -> String {
        let gap = self.gap_m.map_or(String::new(), |g| format!(" gap {g:.0} m"));
        let groups =
            if self.layout == Layout::Separated { format!(" in {} groups", self.groups) } else { String::new() };
        format!(
            "N={} {}{gap}{groups} (span {:.0} m), lanes {:.0}°, {}x{:.0} m every {:.0} m, current {:.3} m/s towards \
             {:.0}°, CNA {} (at block {}), channel {}, filter {}, {:.0} min",
            self.n_auvs,
            self.layout.name(),
            self.fleet_span_m,
            self.lane_heading_deg,
            self.lanes,
            self.lane_length_m,
            self.lane_spacing_m,
            self.current_m_s,
            self.current_towards_deg,
            self.cna,
            self.cna_block,
            self.channel,
            self.filter,
            self.duration_s / 60.0
        )
    }
}

/// One generated mission.
#[derive(Debug, Clone)]
pub struct Mission {
    pub facts: Facts,
    pub scenario: Scenario,
}

/// Distance the CNA starts short of its block's first lane, m. Invented.
pub const CNA_LAUNCH_OFFSET_M: f64 = 100.0;

impl Ranges {
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::parse(text, file, Self::validate)
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::load(file, Self::validate)
    }

    /// Every range ordered and within what a scenario allows; every list non-empty; every seed
    /// `seed + i` representable.
    pub fn validate(&self, file: &Path) -> Result<(), ScenarioError> {
        let mut p = Problems::new(file);
        let ordered = |p: &mut Problems, field: &str, r: [f64; 2], lo: f64, hi: f64| {
            if !(r[0].is_finite() && r[1].is_finite() && lo <= r[0] && r[0] <= r[1] && r[1] <= hi) {
                p.push(field, format!("{r:?}"), format!("[lo, hi] with {lo} <= lo <= hi <= {hi}"));
            }
        };
        let whole = |p: &mut Problems, field: &str, r: [usize; 2], lo: usize, hi: usize| {
            if !(lo <= r[0] && r[0] <= r[1] && r[1] <= hi) {
                p.push(field, format!("{r:?}"), format!("[lo, hi] with {lo} <= lo <= hi <= {hi}"));
            }
        };
        whole(&mut p, "n_auvs", self.n_auvs, 1, 8);
        whole(&mut p, "lanes", self.lanes, 1, 40);
        whole(&mut p, "separated_groups", self.separated_groups, 1, 8);
        ordered(&mut p, "lane_heading_deg", self.lane_heading_deg, -360.0, 720.0);
        ordered(&mut p, "lane_length_m", self.lane_length_m, 1.0, 5000.0);
        ordered(&mut p, "lane_spacing_m", self.lane_spacing_m, 1.0, 1000.0);
        ordered(&mut p, "spread_gap_m", self.spread_gap_m, 0.0, 5000.0);
        ordered(&mut p, "separated_gap_m", self.separated_gap_m, 0.0, 5000.0);
        ordered(&mut p, "current_m_s", self.current_m_s, 0.0, 1.0);
        ordered(&mut p, "duration_h", self.duration_h, 0.01, 24.0);
        ordered(&mut p, "depth_m", self.depth_m, 0.0, 99.0);
        if self.missions == 0 {
            p.push("missions", "0", ">= 1");
        }
        if self.seed.checked_add(self.missions as u64).is_none_or(|last| last > i64::MAX as u64) {
            p.push("seed", self.seed.to_string(), "seed + missions within a TOML integer (< 2^63)");
        }
        for (field, empty) in [
            ("layouts", self.layouts.is_empty()),
            ("cna", self.cna.is_empty()),
            ("channel", self.channel.is_empty()),
            ("filter", self.filter.is_empty()),
        ] {
            if empty {
                p.push(field, "[]", "at least one entry");
            }
        }
        for v in &self.filter {
            if let Some(n) = &v.position_noise {
                for (key, value) in [("still_m2_s", n.still_m2_s), ("per_current_s", n.per_current_s)] {
                    if !(value.is_finite() && value >= 0.0) {
                        p.push(format!("filter ({}).position_noise.{key}", v.name), value.to_string(), "finite, >= 0");
                    }
                }
            }
        }
        p.finish()
    }

    /// Mission seeds `seed .. seed + missions`.
    pub fn seeds(&self) -> std::ops::Range<u64> {
        self.seed..self.seed + self.missions as u64
    }

    /// Mission `index` (any index, also past `missions`), validated as `coopnav simulate` would
    /// validate it; `file` names the range file in messages.
    pub fn mission(&self, index: usize, file: &Path) -> Result<Mission, ScenarioError> {
        let seed = self.seed + index as u64;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = rng.gen_range(self.n_auvs[0]..=self.n_auvs[1]);
        let layout = self.layouts[rng.gen_range(0..self.layouts.len())];
        let heading = drawn(&mut rng, self.lane_heading_deg, 0.1).rem_euclid(360.0);
        let length = drawn(&mut rng, self.lane_length_m, 1.0);
        let spacing = drawn(&mut rng, self.lane_spacing_m, 1.0);
        let lanes = rng.gen_range(self.lanes[0]..=self.lanes[1]);
        let spread_gap = drawn(&mut rng, self.spread_gap_m, 1.0);
        let separated_gap = drawn(&mut rng, self.separated_gap_m, 1.0);
        let groups = rng.gen_range(self.separated_groups[0]..=self.separated_groups[1]).min(n);
        let current = drawn(&mut rng, self.current_m_s, 0.001);
        let towards = round_to(rng.gen_range(0.0..360.0), 1.0).rem_euclid(360.0);
        let cna = &self.cna[rng.gen_range(0..self.cna.len())];
        let channel = &self.channel[rng.gen_range(0..self.channel.len())];
        let filter = &self.filter[rng.gen_range(0..self.filter.len())];
        let duration_s = (uniform(&mut rng, self.duration_h) * 60.0).round().max(1.0) * 60.0;
        let depth = drawn(&mut rng, self.depth_m, 1.0);
        let cna_block = rng.gen_range(0..n);

        let name = || PathBuf::from(format!("{} (mission {index}, seed {seed})", file.display()));
        let mut sc = Scenario::example();
        for patch in [&cna.patch, &channel.patch, &filter.patch]
            .into_iter()
            .chain(self.fleet_size.iter().filter(|r| n >= r.min_auvs).map(|r| &r.patch))
        {
            sc = overlay(&sc, toml::Value::Table(patch.clone()))
                .map_err(|message| ScenarioError::Parse { file: name(), message })?;
        }

        let width = (lanes.saturating_sub(1)) as f64 * spacing;
        let gap_m = match layout {
            Layout::Spread => Some(spread_gap),
            Layout::Separated => Some(separated_gap),
            Layout::Adjacent | Layout::Diagonal => None,
        };
        // Each block's first-lane start in the lanes' frame: (along the lanes, to their right).
        let offsets: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let k_f = k as f64;
                match layout {
                    Layout::Adjacent => (0.0, k_f * (width + spacing)),
                    Layout::Spread => (0.0, k_f * (width + spread_gap)),
                    Layout::Diagonal => (k_f * (length + spacing), k_f * (width + spacing)),
                    Layout::Separated => {
                        let group = k * groups / n;
                        (0.0, k_f * (width + spacing) + group as f64 * (separated_gap - spacing))
                    }
                }
            })
            .collect();
        let fold = |pick: fn(&(f64, f64)) -> f64| offsets.iter().map(pick).fold(0.0, f64::max);
        let centre = ((fold(|o| o.0) + length) / 2.0, (fold(|o| o.1) + width) / 2.0);
        let (ux, uy) = Heading::from(CompassDeg(heading)).unit();
        let (rx, ry) = (uy, -ux);
        let world = |(a, c): (f64, f64)| (a * ux + c * rx, a * uy + c * ry);
        let origins: Vec<(f64, f64)> = offsets.iter().map(|&(a, c)| world((a - centre.0, c - centre.1))).collect();
        let centres: Vec<(f64, f64)> =
            offsets.iter().map(|&(a, c)| world((a + length / 2.0 - centre.0, c + width / 2.0 - centre.1))).collect();
        let fleet_span_m =
            centres.iter().flat_map(|a| centres.iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1))).fold(0.0, f64::max);

        let f = &mut sc.fleet;
        f.n_auvs = n;
        f.origin = origins[0];
        f.lane_heading_compass_deg = heading;
        f.lane_length = length;
        f.lane_spacing = spacing;
        f.lanes = lanes;
        f.block_offset = width + spacing;
        f.depth = coopnav_core::DepthTarget::Depth { depth };
        let (sin, cos) = towards.to_radians().sin_cos();
        f.current = (current * sin, current * cos);
        f.lawnmowers = origins
            .iter()
            .map(|&origin| MowerSpec { origin, lane_heading_compass_deg: heading, turn: Turn::Right })
            .collect();
        let start = origins[cna_block];
        sc.cna.x = start.0 - CNA_LAUNCH_OFFSET_M * ux;
        sc.cna.y = start.1 - CNA_LAUNCH_OFFSET_M * uy;
        sc.cna.heading_compass_deg = heading;
        sc.seed = seed;
        sc.duration_s = duration_s;
        sc.cna.adcp_current = [sc.fleet.current.0, sc.fleet.current.1];
        if let Some(noise) = &filter.position_noise {
            let q = noise.per_step(current, sc.filter.params.step_s);
            sc.filter.params.q[0] = q;
            sc.filter.params.q[1] = q;
        }
        sc.policy = Policies::default();
        sc.validate(&name())?;

        let facts = Facts {
            index,
            seed,
            n_auvs: n,
            layout,
            gap_m,
            groups,
            lane_heading_deg: heading,
            lane_length_m: length,
            lane_spacing_m: spacing,
            lanes,
            current_m_s: current,
            current_towards_deg: towards,
            cna: cna.name.clone(),
            channel: channel.name.clone(),
            filter: filter.name.clone(),
            duration_s,
            depth_m: depth,
            cna_block,
            fleet_span_m,
        };
        Ok(Mission { facts, scenario: sc })
    }

    /// Missions `0 .. missions`.
    pub fn generate(&self, file: &Path) -> Result<Vec<Mission>, ScenarioError> {
        (0..self.missions).map(|i| self.mission(i, file)).collect()
    }
}

/// A uniform draw from `r` to the nearest multiple of `step` (as a team would state the fact),
/// kept within `r`.
fn drawn(rng: &mut ChaCha8Rng, r: [f64; 2], step: f64) -> f64 {
    ((uniform(rng, r) / step).round() * step).clamp(r[0], r[1])
}

/// `v` to the nearest multiple of `step`.
fn round_to(v: f64, step: f64) -> f64 {
    (v / step).round() * step
}

fn uniform(rng: &mut ChaCha8Rng, r: [f64; 2]) -> f64 {
    if r[0] == r[1] {
        r[0]
    } else {
        rng.gen_range(r[0]..=r[1])
    }
}

impl Mission {
    /// The file name `coopnav generate` writes it under.
    pub fn file_name(&self) -> String {
        format!("mission-{:03}.toml", self.facts.index)
    }

    /// The mission as a scenario file: a comment naming its facts, then every table but
    /// `[policy]` (which a mission does not state). `coopnav simulate` reads it back to the same
    /// scenario.
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        let mut value = toml::Value::try_from(&self.scenario)?;
        if let toml::Value::Table(t) = &mut value {
            t.remove("policy");
        }
        let mut out = String::new();
        let _ =
            writeln!(out, "# Generated mission {} (seed {}): {}", self.facts.index, self.facts.seed, self.facts.line());
        out.push_str("# No [policy] table: the policies a file without one gets.\n");
        out.push_str(&toml::to_string(&value)?);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GENERALIZATION: &str = include_str!("../../../../scenarios/generators/generalization.toml");

    fn ranges() -> Ranges {
        Ranges::parse(GENERALIZATION, Path::new("generalization.toml")).unwrap()
    }

    #[test]
    fn a_written_mission_reads_back_to_the_same_scenario() {
        let r = ranges();
        for i in 0..12 {
            let m = r.mission(i, Path::new("generalization.toml")).unwrap();
            let text = m.to_toml().unwrap();
            let table: toml::Table = toml::from_str(&text).unwrap();
            assert!(!table.contains_key("policy"), "mission {i} states policy keys");
            let back = Scenario::parse(&text, Path::new("mission.toml")).unwrap();
            assert_eq!(back, m.scenario, "mission {i}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_mission_and_another_seed_another() {
        let r = ranges();
        let f = Path::new("g.toml");
        let a = r.mission(3, f).unwrap();
        assert_eq!(a.scenario, r.mission(3, f).unwrap().scenario);
        assert_eq!(a.facts.seed, r.seed + 3);
        let other = Ranges { seed: r.seed + 1, ..r.clone() };
        // Index 2 of the next seed is index 3 of this one: the mission is its seed's.
        assert_eq!(other.mission(2, f).unwrap().scenario, a.scenario);
        assert_ne!(r.mission(4, f).unwrap().scenario, a.scenario);
    }

    #[test]
    fn separated_groups_lie_more_than_the_drawn_gap_apart_and_adjacent_blocks_touch() {
        let base = ranges();
        let f = Path::new("g.toml");
        let only = |layout| Ranges { layouts: vec![layout], n_auvs: [4, 4], separated_groups: [2, 2], ..base.clone() };
        for i in 0..6 {
            let m = only(Layout::Separated).mission(i, f).unwrap();
            let gap = m.facts.gap_m.unwrap();
            assert!(gap > 1000.0, "{gap}");
            // Blocks 1 and 2 are in different groups: the second's first lane lies `gap` to the
            // right of the first block's last lane.
            let sc = &m.scenario;
            let (a, b) = (sc.lawnmower(1).waypoints(), sc.lawnmower(2).waypoints());
            let nearest = a
                .iter()
                .flat_map(|p| b.iter().map(move |q| (p.0 - q.0).hypot(p.1 - q.1)))
                .fold(f64::INFINITY, f64::min);
            assert!((nearest - gap).abs() < 1e-6, "mission {i}: nearest waypoints {nearest} m, gap {gap} m");
            let adjacent = only(Layout::Adjacent).mission(i, f).unwrap();
            let sc = &adjacent.scenario;
            let (a, b) = (sc.lawnmower(0).waypoints(), sc.lawnmower(1).waypoints());
            let nearest = a
                .iter()
                .flat_map(|p| b.iter().map(move |q| (p.0 - q.0).hypot(p.1 - q.1)))
                .fold(f64::INFINITY, f64::min);
            assert!((nearest - adjacent.facts.lane_spacing_m).abs() < 1e-6, "adjacent: {nearest} m");
        }
    }

    #[test]
    fn the_missions_cover_every_range_of_the_file() {
        let r = ranges();
        let missions = r.generate(Path::new("g.toml")).unwrap();
        assert_eq!(missions.len(), r.missions);
        let facts: Vec<&Facts> = missions.iter().map(|m| &m.facts).collect();
        for n in r.n_auvs[0]..=r.n_auvs[1] {
            assert!(facts.iter().any(|f| f.n_auvs == n), "no mission with {n} AUVs");
        }
        for layout in &r.layouts {
            assert!(facts.iter().any(|f| f.layout == *layout && f.n_auvs > 1), "no {layout:?}");
        }
        for v in r.cna.iter().chain(&r.channel).chain(&r.filter) {
            assert!(facts.iter().any(|f| [&f.cna, &f.channel, &f.filter].contains(&&v.name)), "no {}", v.name);
        }
        let most = |g: &dyn Fn(&Facts) -> f64| facts.iter().map(|f| g(f)).fold(f64::NEG_INFINITY, f64::max);
        let least = |g: &dyn Fn(&Facts) -> f64| facts.iter().map(|f| g(f)).fold(f64::INFINITY, f64::min);
        assert!(
            most(&|f| f.current_m_s) > 0.9 * r.current_m_s[1] && least(&|f| f.current_m_s) < 0.1 * r.current_m_s[1]
        );
        assert!(most(&|f| f.duration_s) > 0.9 * 3600.0 * r.duration_h[1]);
        assert!(least(&|f| f.duration_s) < 1.1 * 3600.0 * r.duration_h[0]);
        assert!(most(&|f| f.current_towards_deg) > 300.0 && least(&|f| f.current_towards_deg) < 60.0);
        // Each mission's facts are its scenario's.
        for m in &missions {
            let (sc, f) = (&m.scenario, &m.facts);
            assert_eq!(sc.fleet.n_auvs, f.n_auvs);
            assert!((sc.fleet.current.0.hypot(sc.fleet.current.1) - f.current_m_s).abs() < 1e-12);
            assert_eq!(sc.cna.auv.is_some(), f.cna == "auv", "mission {}: {}", f.index, f.cna);
            assert_eq!(sc.duration_s, f.duration_s);
        }
    }

    #[test]
    fn a_bad_range_file_names_every_bad_field() {
        let bad =
            GENERALIZATION.replace("n_auvs = [1, 8]", "n_auvs = [3, 9]").replace("missions = 200", "missions = 0");
        let e = Ranges::parse(&bad, Path::new("g.toml")).unwrap_err().to_string();
        assert!(e.contains("g.toml") && e.contains("n_auvs") && e.contains("missions"), "{e}");
    }

    const AIDING: &str = include_str!("../../../../scenarios/generators/aiding-never-hurts.toml");

    #[test]
    fn a_filter_variant_with_position_noise_sets_its_missions_q_from_their_current() {
        let f = Path::new("aiding-never-hurts.toml");
        let r = Ranges::parse(AIDING, f).unwrap();
        let example = Scenario::example().filter.params.q;
        let (mut five, mut seven) = (0, 0);
        for i in 0..16 {
            let m = r.mission(i, f).unwrap();
            let q = m.scenario.filter.params.q;
            // The other states' noise is the example's.
            assert_eq!(q[2..], example[2..], "mission {i}");
            if m.facts.filter == "5-state" {
                // 0.30 + 84.36 c² m²/s per axis, per 0.1 s step, c the stated speed.
                let c = m.facts.current_m_s;
                let want = (0.30 + 84.36 * c * c) * 0.1;
                assert!((q[0] - want).abs() < 1e-12 && q[1] == q[0], "mission {i}: {q:?} for {c} m/s");
                five += 1;
            } else {
                assert_eq!(q, example, "mission {i}: the 7-state variant has no position_noise");
                seven += 1;
            }
        }
        assert!(five > 0 && seven > 0, "{five} {seven}");
        // At the example's own 0.05 m/s the rule gives back its position noise within 0.01 %.
        let n = PositionNoise { still_m2_s: 0.30, per_current_s: 84.36 };
        assert!((n.per_step(0.05, 0.1) / crate::scenario::world::CLOSED_LOOP_Q_EN - 1.0).abs() < 1e-4);
        // Mistakes are named by the variant and field.
        let bad = AIDING.replace("still_m2_s = 0.30", "still_m2_s = -1.0");
        let e = Ranges::parse(&bad, f).unwrap_err().to_string();
        assert!(e.contains("filter (5-state).position_noise.still_m2_s"), "{e}");
    }
}
