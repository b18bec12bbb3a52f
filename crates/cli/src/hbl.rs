//! `coopnav hbl simulate|montecarlo|grid|tune|postprocess`: the Gill hybrid-baseline tools.

use crate::alog_import;
use crate::input::{self, Format};
use crate::run_dir::given_or_fresh;
use anyhow::{Context, Result};
use coopnav_core::limits;
use coopnav_nav::cycle::Configuration;
use coopnav_nav::fieldlog::{BeaconId, FieldLog, TimeBase};
use coopnav_nav::post::{self, PostConfig, PostSample, RangeResidual};
use coopnav_nav::post_quality::Quality;
use coopnav_nav::post_tune::{self, Scored, TuneOptions, TuneReport};
use coopnav_sim::batch::grid::{self, GridSpec};
use coopnav_sim::batch::tune::{tune, Coefficient, Objective, TuneSpec};
use coopnav_sim::batch::work;
use coopnav_sim::observe::zone::{zone_monte_carlo_with_progress, RunCounts, ZoneMetrics, ZoneSpec};
use coopnav_sim::output::hbl_plot as plot;
use coopnav_sim::output::log_format::LogFormat;
use coopnav_sim::output::record::record_pass;
use coopnav_sim::output::{Manifest, RunDir};
use coopnav_sim::scenario::hbl as hbl_scenario;
use coopnav_sim::scenario::hbl::{table5_file, table5_scenario};
use coopnav_sim::scenario::Scenario;

/// x_rel bin of the Monte Carlo error profile (m).
const PROFILE_BIN_M: f64 = 5.0;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(clap::Subcommand)]
pub enum Command {
    /// One run on the mission engine: tracks and errors once a second (trace.csv), the
    /// post-processing log (log.csv: dead reckoning every filter step, ship fixes every truth step,
    /// buoy fixes and ranges as they happen), summary.json, SVG plots, MOOS files.
    Simulate {
        #[command(flatten)]
        common: Common,
        /// Replay run I of a Monte Carlo with the same --seed (its runs are 0 … runs − 1).
        #[arg(long, default_value_t = 0)]
        run: u64,
        /// How log.csv is written (TOML: geodetic_origin, buoy_fix_storage; `hbl example
        /// log-format`); metres by default.
        #[arg(long)]
        log_format: Option<PathBuf>,
    },
    /// A Monte Carlo of one scenario: per-run CSV, summary.json, and the mean error profile
    /// against x_rel (profile.csv, profile.svg: total, along- and across-path).
    Montecarlo {
        #[command(flatten)]
        common: Common,
        #[arg(long, default_value_t = 250)]
        runs: usize,
    },
    /// The buoy-location grid: CSV plus an SVG heat map. Each run ends once the AUV is past the
    /// zone; the scenario's duration_s and lane are raised to at least 400 s and 360 m first, so an
    /// AUV that a buoy on its path pulls off course still reaches the zone.
    Grid {
        #[command(flatten)]
        common: Common,
        /// Grid TOML (x, y, spacing, runs_per_cell); defaults to the thesis grid.
        #[arg(long)]
        grid: Option<PathBuf>,
    },
    /// Bounded Nelder–Mead tuning of filter coefficients on a fixed-seed Monte Carlo.
    Tune {
        #[command(flatten)]
        common: Common,
        /// Tuning TOML (coefficients, objective, runs, max_iters, seed; `hbl example tune`).
        #[arg(long, required_unless_present = "example")]
        spec: Option<PathBuf>,
    },
    /// Print a documented starting file: the Table 5 scenario (an engine scenario file), a grid, a
    /// tuning spec, a log format or a post-processing config (edit and pass it back: the scenario
    /// as the positional file, the others with --grid, --spec, --log-format or --config).
    Example {
        #[arg(value_enum, default_value_t = ExampleKind::Scenario)]
        kind: ExampleKind,
    },
    /// Post-process a CSV log: EKF then RTS smoother.
    Postprocess {
        /// The log (format in coopnav_nav::post), or a MOOS `.alog` (by its extension).
        #[arg(required_unless_present = "example")]
        log: Option<PathBuf>,
        /// For an `.alog`: TOML mapping MOOS variables to log rows (`hbl example alog-map`).
        #[arg(long)]
        alog_map: Option<PathBuf>,
        /// Post-processing TOML (auv coefficients, acoustic_time_offset_s, slant_range, ...).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output directory (default: a fresh runs/hbl-postprocess).
        #[arg(short, long = "output", alias = "out")]
        out: Option<PathBuf>,
        /// Print the default post-processing config (`--config`) as TOML and exit.
        #[arg(long)]
        example: bool,
        /// Replace the output directory if it exists.
        #[arg(long)]
        force: bool,
        /// Refuse the log (exit non-zero, write nothing) when the log itself leaves a row unusable as
        /// logged: rows before `init`, a second `init`, ranges without a fresh transponder fix, long
        /// silences, ranges without usable geometry. Ranges the innovation gate rejects (acoustic
        /// outliers) are warned about, not refused: the gate catching one is the filter working.
        #[arg(long)]
        strict: bool,
        /// Run even when the estimated work or memory is above coopnav's limits (coopnav_core::limits).
        #[arg(long)]
        allow_large: bool,
        /// Tune range σ, E/N process noise, speed scale, compass bias and initial E/N variance from
        /// the log itself (how well the track smoothed without each range predicts it,
        /// cross-validated, Nelder–Mead), print before/after, write tune.json and
        /// tuned_config.toml, and post-process with the tuned values — or keep the starting ones,
        /// with a warning, when the result is not better on the held-out ranges.
        #[arg(long)]
        tune: bool,
        /// Folds of the cross-validation over ranges (every k-th range held out, each phase in
        /// turn) whose held-out residuals summary.json reports and --tune scores (0: none).
        #[arg(long, default_value_t = TuneOptions::default().hold_out_every)]
        hold_out_every: usize,
        /// With --tune: Nelder–Mead iterations at most.
        #[arg(long, default_value_t = TuneOptions::default().max_iters)]
        tune_iters: u64,
        /// With --tune: the search averages the dead-reckoning rows over blocks of this many
        /// seconds and predicts in steps of that length (0: full rate); before/after are full rate.
        #[arg(long, default_value_t = TuneOptions::default().dead_reckoning_block_s)]
        tune_block_s: f64,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ExampleKind {
    /// The scenario file of simulate, montecarlo, grid and tune.
    Scenario,
    /// `grid --grid`.
    Grid,
    /// `tune --spec`.
    Tune,
    /// `simulate --log-format`.
    LogFormat,
    /// `postprocess --config`.
    Post,
    /// `postprocess --alog-map`.
    AlogMap,
}

#[derive(clap::Args)]
pub struct Common {
    /// Engine scenario TOML (as `coopnav simulate` reads; `--example` prints one); defaults to
    /// Gill's Table 5 HBL Two set-up (scenarios/gill-table5-hbl-two.toml). Survey AUV 0 meets
    /// `ships[0]`; `buoys[0]` is the HBL buoy; the zone lies along the survey lane.
    scenario: Option<PathBuf>,
    /// The measurement zone's near edge: x_rel = (AUV − ship) along the survey lane, m (default
    /// −30, Gill's Table 5; below --zone-max-m).
    #[arg(long, allow_negative_numbers = true)]
    zone_min_m: Option<f64>,
    /// The measurement zone's far edge, m (default 75, Gill's Table 5).
    #[arg(long, allow_negative_numbers = true)]
    zone_max_m: Option<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory (default: a fresh runs/hbl-<command>).
    #[arg(short, long = "output", alias = "out")]
    out: Option<PathBuf>,
    /// Replace the output directory if it exists.
    #[arg(long)]
    force: bool,
    /// Run even when the estimated work or memory is above coopnav's limits (coopnav_core::limits).
    #[arg(long)]
    allow_large: bool,
    /// Print the default scenario (Gill's Table 5, HBL Two) as TOML and exit.
    #[arg(long)]
    example: bool,
}

impl Common {
    /// The files the command reads: the scenario, when given, and `more`.
    fn inputs<'a>(&'a self, more: &[Option<&'a Path>]) -> Vec<&'a Path> {
        self.scenario.as_deref().into_iter().chain(more.iter().flatten().copied()).collect()
    }

    /// The run directory of `hbl COMMAND`: the one `-o` names (refused when it holds anything but
    /// a run of coopnav's, or one of `inputs`), else a fresh `runs/hbl-COMMAND`.
    fn run_dir(&self, command: &str, inputs: &[&Path]) -> Result<RunDir> {
        given_or_fresh(self.out.as_deref(), self.force, inputs, &format!("hbl-{command}"))
    }
}

fn scenario(c: &Common) -> Result<Scenario> {
    match &c.scenario {
        Some(p) => {
            let text = input::read(p, c.allow_large)?;
            input::parsed_as(hbl_scenario::parse(&text, p), &text, p, Format::Mission)
        }
        None => Ok(table5_scenario(Configuration::HblTwo)?),
    }
}

impl Common {
    /// The run's inputs, with the zone's edges when they were given (absent: Table 5's).
    fn with_zone(&self, mut inputs: serde_json::Value) -> serde_json::Value {
        if self.zone_min_m.is_some() || self.zone_max_m.is_some() {
            inputs["zone"] = json!({ "zone_min_m": self.zone_min_m, "zone_max_m": self.zone_max_m });
        }
        inputs
    }
}

fn bar(n: u64) -> ProgressBar {
    let pb = ProgressBar::new(n);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed}").unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

fn manifest(dir: &RunDir, command: &str, seed: u64, inputs: serde_json::Value) -> Result<()> {
    Ok(dir.write_json("manifest.json", &Manifest::new(command, Some(seed), inputs))?)
}

pub fn run_command(cmd: Command) -> Result<()> {
    if let Command::Simulate { common, .. }
    | Command::Montecarlo { common, .. }
    | Command::Grid { common, .. }
    | Command::Tune { common, .. } = &cmd
    {
        if common.example {
            return example(ExampleKind::Scenario);
        }
    }
    match cmd {
        Command::Simulate { common, run, log_format } => simulate(&common, run, log_format.as_deref()),
        Command::Montecarlo { common, runs } => montecarlo(&common, runs),
        Command::Grid { common, grid } => grid_cmd(&common, grid.as_deref()),
        Command::Tune { common, spec } => {
            tune_cmd(&common, &spec.ok_or_else(|| anyhow::anyhow!("hbl tune needs --spec FILE (`hbl example tune`)"))?)
        }
        Command::Postprocess {
            log,
            alog_map,
            config,
            out,
            example: print_example,
            force,
            strict,
            allow_large,
            tune,
            hold_out_every,
            tune_iters,
            tune_block_s,
        } => {
            let tune = tune.then_some(TuneOptions {
                hold_out_every,
                max_iters: tune_iters,
                dead_reckoning_block_s: tune_block_s,
            });
            let Some(log) = log.filter(|_| !print_example) else { return example(ExampleKind::Post) };
            let files =
                PostFiles { log: &log, alog_map: alog_map.as_deref(), config: config.as_deref(), out: out.as_deref() };
            postprocess(files, force, strict, allow_large, hold_out_every, tune)
        }
        Command::Example { kind } => example(kind),
    }
}

/// The optional geodetic origin (absent by default) for lat/lon (`_ll`) log rows.
const ORIGIN_HINT: &str =
    "# origin = { lat_deg = 47.97, lon_deg = -116.5, height_m = 630.0 }  # WGS-84 origin of lat/lon (_ll) log rows";

/// The example file of `kind`, without the header `hbl example` prints above it.
pub(crate) fn example_text(kind: ExampleKind) -> Result<String> {
    Ok(match kind {
        ExampleKind::Scenario => table5_file(Configuration::HblTwo).1.to_string(),
        // Absent options don't serialise: show the geodetic one.
        ExampleKind::LogFormat => format!(
            "{}\n{}",
            ORIGIN_HINT.replacen("origin", "geodetic_origin", 1),
            toml::to_string_pretty(&LogFormat::default())?
        ),
        ExampleKind::Grid => toml::to_string_pretty(&GridSpec::default())?,
        ExampleKind::Tune => toml::to_string_pretty(&TuneSpec {
            coefficients: vec![Coefficient::AuvQEn, Coefficient::BuoyQEn],
            objective: Objective::AuvZone,
            runs: 50,
            max_iters: 40,
            seed: 1,
        })?,
        ExampleKind::Post => format!("{ORIGIN_HINT}\n{}", toml::to_string_pretty(&PostConfig::default())?),
        ExampleKind::AlogMap => toml::to_string_pretty(&crate::alog_import::AlogMapping::default())?,
    })
}

fn example(kind: ExampleKind) -> Result<()> {
    let text = example_text(kind)?;
    let what = match kind {
        ExampleKind::Scenario => {
            "HBL scenario (Gill 2013 Table 5, HBL Two; an engine scenario file) for `hbl simulate|montecarlo|grid|tune FILE`"
        }
        ExampleKind::LogFormat => "log format for `hbl simulate --log-format`",
        ExampleKind::Grid => "buoy-location grid for `hbl grid --grid`",
        ExampleKind::Tune => "tuning spec for `hbl tune --spec`",
        ExampleKind::Post => "post-processing config for `hbl postprocess --config`",
        ExampleKind::AlogMap => "MOOS variable mapping for `hbl postprocess X.alog --alog-map`",
    };
    println!("# coopnav {what}.");
    if let ExampleKind::Scenario = kind {
        println!("# The file `coopnav reproduce gill-table-5` runs; the scenario format is in scenarios/README.md.");
    } else {
        println!("# Every field is at its default and optional: keep only what you change. Units and the");
        println!(
            "# thesis source of each field: the rustdoc of coopnav_sim::scenario::hbl and coopnav_nav (`cargo doc --open`)."
        );
    }
    print!("{text}");
    Ok(())
}

/// The zone of a pass in `sc`: along the survey lane's direction, between the edges given (by
/// default Gill's Table 5 zone).
fn zone_spec(sc: &Scenario, c: &Common) -> Result<ZoneSpec> {
    let table5 = ZoneSpec::table5();
    let (zone_min, zone_max) = (c.zone_min_m.unwrap_or(table5.zone_min), c.zone_max_m.unwrap_or(table5.zone_max));
    if !(zone_min.is_finite() && zone_max.is_finite() && zone_min < zone_max) {
        anyhow::bail!(
            "--zone-min-m {zone_min} and --zone-max-m {zone_max}: the measurement zone needs finite edges, the near \
             one below the far one (x_rel = AUV − ship along the lane, m; Gill's Table 5 zone is {} … {})",
            table5.zone_min,
            table5.zone_max
        );
    }
    Ok(ZoneSpec { path_compass_deg: sc.fleet.lane_heading_compass_deg, zone_min, zone_max, ..table5 })
}

/// The name a summary line gives the scenario: its file, or the default's.
fn scenario_name(c: &Common) -> String {
    c.scenario.as_ref().map_or(table5_file(Configuration::HblTwo).0.to_string(), |p| p.display().to_string())
}

fn log_format(path: Option<&Path>, allow_large: bool) -> Result<LogFormat> {
    let format: LogFormat = match path {
        Some(p) => input::read_as(p, allow_large, Format::HblLogFormat, toml::from_str)?,
        None => LogFormat::default(),
    };
    format.validate().with_context(|| path.map_or(String::new(), |p| format!("in {}", p.display())))?;
    Ok(format)
}

/// `hbl simulate`'s summary: the zone figures and the run's counts.
#[derive(Serialize)]
struct PassSummary {
    #[serde(flatten)]
    zone: ZoneMetrics,
    #[serde(flatten)]
    counts: RunCounts,
}

fn simulate(c: &Common, index: u64, log_path: Option<&Path>) -> Result<()> {
    let sc = scenario(c)?;
    let format = log_format(log_path, c.allow_large)?;
    limits::check(work::hbl_runs(&sc, 1.0, "one run", true), c.allow_large)?;
    let zone = zone_spec(&sc, c)?;
    let (pass, result) = record_pass(&sc, zone, format.clone(), coopnav_core::run_seed(c.seed, index))?;
    let summary = PassSummary { zone: pass.zone.metrics(), counts: RunCounts::of(&result, 0) };
    let dir = c.run_dir("simulate", &c.inputs(&[log_path]))?;
    manifest(&dir, "hbl simulate", c.seed, c.with_zone(json!({ "scenario": sc, "run": index, "log_format": format })))?;
    let mut csv = String::from("t,x_rel,auv_e,auv_n,est_e,est_n,sd_e,sd_n,ship_e,ship_n,ship_est_e,ship_est_n,buoy_e,buoy_n,buoy_est_e,buoy_est_n,error\n");
    for r in &pass.rows {
        let o = |v: Option<[f64; 2]>, i: usize| v.map_or(String::new(), |p| p[i].to_string());
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.t,
            r.x_rel,
            r.auv_true[0],
            r.auv_true[1],
            r.auv_est[0],
            r.auv_est[1],
            r.auv_sd[0],
            r.auv_sd[1],
            r.ship_true[0],
            r.ship_true[1],
            r.ship_est[0],
            r.ship_est[1],
            o(r.buoy_true, 0),
            o(r.buoy_true, 1),
            o(r.buoy_est, 0),
            o(r.buoy_est, 1),
            r.error
        ));
    }
    dir.write_bytes("trace.csv", csv)?;
    let mut log = Vec::new();
    post::write_log(&mut log, &pass.sorted_log(), format.frame().as_ref())?;
    dir.write_bytes("log.csv", log)?;
    dir.write_bytes("tracks.svg", plot::tracks(&pass.rows)?)?;
    dir.write_bytes("error_vs_xrel.svg", plot::error_vs_xrel(&pass.rows, (zone.zone_min, zone.zone_max))?)?;
    dir.write_json("summary.json", &summary)?;
    coopnav_sim::output::moos_export::write_moos_files(
        &dir,
        &coopnav_sim::output::moos_export::hbl_run(&pass.rows, format.frame()),
    )?;
    let out = dir.finish()?;
    println!("zone error {:.3} m; wrote {}", summary.zone.zone_error.unwrap_or(f64::NAN), out.display());
    Ok(())
}

fn montecarlo(c: &Common, runs: usize) -> Result<()> {
    let sc = scenario(c)?;
    if runs < 2 {
        anyhow::bail!("--runs {runs}: a Monte Carlo needs at least 2 runs");
    }
    limits::check(work::hbl_runs(&sc, runs as f64, "--runs", false), c.allow_large)?;
    let zone = ZoneSpec { profile_bin_m: PROFILE_BIN_M, ..zone_spec(&sc, c)? };
    let pb = bar(runs as u64);
    let r = zone_monte_carlo_with_progress(&sc, zone, runs, c.seed, &|n| pb.set_position(n))?;
    pb.finish_and_clear();
    let summary = r.summary(c.seed)?;
    let dir = c.run_dir("montecarlo", &c.inputs(&[]))?;
    manifest(&dir, "hbl montecarlo", c.seed, c.with_zone(json!({ "scenario": sc, "runs": runs })))?;
    let mut csv = String::from("run,zone_error,zone_parallel,zone_perpendicular,approach_perpendicular,buoy_error,saturation_error,ranges_received,ranges_applied,healthy\n");
    for (i, (m, n)) in r.runs.iter().zip(&r.counts).enumerate() {
        let o = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        csv.push_str(&format!(
            "{i},{},{},{},{},{},{},{},{},{}\n",
            o(m.zone_error),
            o(m.zone_parallel),
            o(m.zone_perpendicular),
            o(m.approach_perpendicular),
            o(m.buoy_error),
            o(m.saturation_error),
            n.ranges_received,
            n.ranges_applied,
            n.healthy
        ));
    }
    dir.write_bytes("runs.csv", csv)?;
    let mut profile = String::from("x_rel,samples,error,parallel,perpendicular\n");
    for b in &r.profile {
        profile.push_str(&format!("{},{},{},{},{}\n", b.x_rel, b.samples, b.error, b.parallel, b.perpendicular));
    }
    dir.write_bytes("profile.csv", profile)?;
    dir.write_bytes("profile.svg", plot::profile(&r.profile, (zone.zone_min, zone.zone_max))?)?;
    dir.write_json("summary.json", &json!({ "runs": runs, "base_seed": c.seed, "summary": summary }))?;
    let out = dir.finish()?;
    let z = summary.zone_error;
    println!(
        "{}: zone error {:.3} ± {:.3} m (SE {:.3}, {} runs); wrote {}",
        scenario_name(c),
        z.mean,
        z.sd,
        z.se,
        z.n,
        out.display()
    );
    Ok(())
}

fn grid_cmd(c: &Common, grid_path: Option<&Path>) -> Result<()> {
    let mut sc = scenario(c)?;
    let spec: GridSpec = match grid_path {
        Some(p) => input::read_as(p, c.allow_large, Format::HblGrid, toml::from_str)?,
        None => GridSpec::default(),
    };
    spec.validate()
        .with_context(|| grid_path.map_or("the default grid spec".into(), |p| format!("in {}", p.display())))?;
    grid::lengthen_for_grid(&mut sc);
    sc.validate(Path::new(&scenario_name(c)))?;
    limits::check(work::hbl_grid(&sc, &spec), c.allow_large)?;
    let pb = bar(spec.cells().len() as u64);
    let zone = ZoneSpec { stop_past_zone: true, ..zone_spec(&sc, c)? };
    let cell = grid::engine_cell(&sc, zone, spec.runs_per_cell, c.seed)?;
    let cells = grid::buoy_grid(&spec, &|n| pb.set_position(n), &cell)?;
    pb.finish_and_clear();
    let dir = c.run_dir("grid", &c.inputs(&[grid_path]))?;
    manifest(&dir, "hbl grid", c.seed, c.with_zone(json!({ "scenario": sc, "grid": spec })))?;
    let mut buf = Vec::new();
    grid::write_csv(&mut buf, &cells)?;
    dir.write_bytes("grid.csv", buf)?;
    dir.write_bytes("heat_map.svg", plot::heat_map(&cells, spec.spacing)?)?;
    let best = grid::optimal_region(&cells, 0.10);
    dir.write_json("summary.json", &json!({ "cells": cells.len(), "optimal_region_within_10pct": best }))?;
    let out = dir.finish()?;
    println!("{} cells, {} in the optimal region; wrote {}", cells.len(), best.len(), out.display());
    Ok(())
}

fn tune_cmd(c: &Common, spec_path: &Path) -> Result<()> {
    let sc = scenario(c)?;
    let spec: TuneSpec = input::read_as(spec_path, c.allow_large, Format::HblTune, toml::from_str)?;
    spec.validate().with_context(|| format!("in {}", spec_path.display()))?;
    limits::check(work::hbl_tune(&sc, &spec), c.allow_large)?;
    let r = tune(&sc, zone_spec(&sc, c)?, &spec)?;
    let dir = c.run_dir("tune", &c.inputs(&[Some(spec_path)]))?;
    manifest(&dir, "hbl tune", spec.seed, c.with_zone(json!({ "scenario": sc, "spec": spec })))?;
    dir.write_json("summary.json", &r)?;
    let out = dir.finish()?;
    println!(
        "cost {:.4} → {:.4} after {} iterations; wrote {}",
        r.start_cost,
        r.best_cost,
        r.iterations,
        out.display()
    );
    println!("{:<24} {:>12}", "coefficient", "tuned value");
    for (coefficient, value) in &r.coefficients {
        // The name as the spec file spells it (serde's snake_case), not the Rust variant.
        let name = serde_json::to_value(coefficient)?;
        println!("{:<24} {:>12}", name.as_str().unwrap_or_default(), significant(*value, 4));
    }
    Ok(())
}

/// `value` to `digits` significant digits: fixed-point between 10⁻³ and 10⁶, scientific outside,
/// so that a coefficient of 3·10⁻⁹ prints as `3.000e-9`, not as `0.000000`.
fn significant(value: f64, digits: usize) -> String {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    if !(1e-3..1e6).contains(&magnitude) {
        return format!("{value:.*e}", digits.saturating_sub(1));
    }
    let decimals = (digits as i32 - 1 - magnitude.log10().floor() as i32).max(0) as usize;
    format!("{value:.decimals$}")
}

/// The paths `hbl postprocess` reads and writes.
struct PostFiles<'a> {
    log: &'a Path,
    alog_map: Option<&'a Path>,
    config: Option<&'a Path>,
    out: Option<&'a Path>,
}

/// summary.json of `hbl postprocess`: the run's counts and truth figures, what it says about its
/// own accuracy without truth, and the tuning's choice.
#[derive(Serialize)]
struct PostprocessSummary<'a> {
    #[serde(flatten)]
    summary: &'a post::PostSummary,
    quality: &'a Quality,
    #[serde(skip_serializing_if = "Option::is_none")]
    tuning: Option<TuningSummary<'a>>,
}

/// The tuning's outcome in summary.json (the full before/after is tune.json).
#[derive(Serialize)]
struct TuningSummary<'a> {
    guard: &'a post_tune::Guard,
    chosen: &'a post_tune::Tuned,
    searched: &'a post_tune::Tuned,
    sd: &'a post_tune::TunedSd,
    held_out_before: &'a post_tune::CrossValidation,
    held_out_after: &'a post_tune::CrossValidation,
    /// The held-out figures of the kept values (the start's, the search's result's or another
    /// candidate's).
    held_out_kept: &'a post_tune::CrossValidation,
}

fn postprocess(
    files: PostFiles,
    force: bool,
    strict: bool,
    allow_large: bool,
    hold_out_every: usize,
    tune_options: Option<TuneOptions>,
) -> Result<()> {
    let PostFiles { log, alog_map, config, out } = files;
    let mut cfg = match config {
        Some(p) => input::read_as(p, allow_large, Format::HblPost, PostConfig::from_toml)?,
        None => PostConfig::default(),
    };
    let bytes =
        limits::read_bounded(log, "post-processing log (bytes)", work::max_postprocess_log_bytes(), allow_large)?;
    limits::check([work::postprocess_log(&log.display().to_string(), bytes.len() as u64)], allow_large)?;
    let field_log = if log.extension().is_some_and(|e| e == "alog") {
        let alog = coopnav_moos::read_alog(&bytes[..]).with_context(|| format!("in {}", log.display()))?;
        let rows = alog_import::rows(&alog, &alog_import::mapping(alog_map)?, cfg.buoy_depth, cfg.frame().as_ref())
            .with_context(|| format!("in {}", log.display()))?;
        FieldLog { time: TimeBase::Relative, rows }
    } else {
        if let Some(m) = alog_map {
            anyhow::bail!("--alog-map {} is for an .alog log; {} is not one", m.display(), log.display());
        }
        post::read_any_log(&bytes[..], &cfg).with_context(|| format!("in {}", log.display()))?
    };
    let rows = &field_log.rows;
    limits::check(work::postprocess(rows, &cfg), allow_large)?;
    let tuned = match tune_options {
        Some(opts) => {
            let report = post_tune::tune(rows, &cfg, &opts)?;
            print_tuning(&report);
            if let Some(w) = &report.guard.warning {
                eprintln!("warning: {}: {w}", log.display());
            }
            cfg = report.config.clone();
            Some(report)
        }
        None => None,
    };
    // The cross-validation's runs come first, so that only one run's history is held at a time.
    limits::check(work::postprocess_folds(rows, &cfg, hold_out_every), allow_large)?;
    let held_out = match (hold_out_every, &tuned) {
        (0, _) => None,
        (_, Some(t)) if t.guard.kept == post_tune::Kept::Start => Some(t.before.cross_validation),
        (k, _) => Some(post_tune::cross_validate(rows, &cfg, k)?),
    };
    let result = post::postprocess_rows(rows, &cfg)?;
    let faults = result.summary.log_faults();
    if strict && !faults.is_empty() {
        anyhow::bail!("{} (--strict): {}", log.display(), faults.join("; "));
    }
    let quality = Quality::of(&result, held_out);
    for w in result.summary.warnings().into_iter().chain(quality.warnings()) {
        eprintln!("warning: {}: {w}", log.display());
    }
    let inputs: Vec<&Path> = [Some(log), alog_map, config].into_iter().flatten().collect();
    let dir = given_or_fresh(out, force, &inputs, "hbl-postprocess")?;
    let time_origin_unix = match field_log.time {
        TimeBase::Unix { origin } => Some(origin),
        TimeBase::Relative => None,
    };
    // Output times are seconds since the log's origin; a Unix log's origin is recorded here.
    manifest(&dir, "hbl postprocess", 0, json!({ "log": log, "config": cfg, "time_origin_unix": time_origin_unix }))?;
    // Streamed row by row: a day's log has about a million steps (150 MB of CSV).
    dir.write_csv("estimates.csv", result.samples.iter().map(EstimateRow::of))?;
    dir.write_csv("residuals.csv", result.residuals.iter().map(ResidualRow::of))?;
    if let Some(frame) = cfg.frame() {
        let mut unplaceable = None;
        let rows = result.samples.iter().map_while(|s| match frame.from_plane(s.smoothed[0], s.smoothed[1]) {
            Ok(p) => Some(LatLonRow { t: s.t, smooth_lat_deg: p.lat_deg(), smooth_lon_deg: p.lon_deg() }),
            Err(e) => {
                unplaceable = Some((s.t, e));
                None
            }
        });
        dir.write_csv("smoothed_ll.csv", rows)?;
        if let Some((t, e)) = unplaceable {
            return Err(e).with_context(|| format!("smoothed position at t = {t} s has no latitude/longitude"));
        }
    }
    let tuning = tuned.as_ref().map(|t| TuningSummary {
        guard: &t.guard,
        chosen: &t.chosen,
        searched: &t.after.values,
        sd: &t.sd,
        held_out_before: &t.before.cross_validation,
        held_out_after: &t.after.cross_validation,
        held_out_kept: &t.kept.cross_validation,
    });
    let summary = PostprocessSummary { summary: &result.summary, quality: &quality, tuning };
    dir.write_json("summary.json", &summary)?;
    if let Some(report) = &tuned {
        dir.write_json("tune.json", report)?;
        dir.write_bytes("tuned_config.toml", toml::to_string_pretty(&cfg)?)?;
    }
    dir.write_bytes("report.html", crate::post_report::render(rows, &result, &quality, tuned.as_ref())?)?;
    let out = dir.finish()?;
    println!("{}\nwrote {}", serde_json::to_string_pretty(&summary)?, out.display());
    Ok(())
}

/// One line of `estimates.csv`: filtered and smoothed position with their SDs, the truth where
/// logged, the smoothed compass bias and current.
#[derive(Serialize)]
struct EstimateRow {
    t: f64,
    filt_e: f64,
    filt_n: f64,
    filt_sd_e: f64,
    filt_sd_n: f64,
    smooth_e: f64,
    smooth_n: f64,
    smooth_sd_e: f64,
    smooth_sd_n: f64,
    true_e: Option<f64>,
    true_n: Option<f64>,
    smooth_heading_bias_deg: f64,
    smooth_current_e: Option<f64>,
    smooth_current_n: Option<f64>,
}

impl EstimateRow {
    fn of(s: &PostSample) -> Self {
        EstimateRow {
            t: s.t,
            filt_e: s.filtered[0],
            filt_n: s.filtered[1],
            filt_sd_e: s.filtered_sd[0],
            filt_sd_n: s.filtered_sd[1],
            smooth_e: s.smoothed[0],
            smooth_n: s.smoothed[1],
            smooth_sd_e: s.smoothed_sd[0],
            smooth_sd_n: s.smoothed_sd[1],
            true_e: s.truth.map(|p| p[0]),
            true_n: s.truth.map(|p| p[1]),
            smooth_heading_bias_deg: s.smoothed_heading_bias.to_degrees(),
            smooth_current_e: s.smoothed_current.map(|c| c[0]),
            smooth_current_n: s.smoothed_current.map(|c| c[1]),
        }
    }
}

/// One line of `residuals.csv`.
#[derive(Serialize)]
struct ResidualRow {
    t: f64,
    beacon: BeaconId,
    applied: bool,
    innovation_m: f64,
    innovation_sd_m: f64,
    smoothed_residual_m: f64,
    smoothed_residual_sd_m: f64,
    held_out: bool,
    nis: f64,
}

impl ResidualRow {
    fn of(r: &RangeResidual) -> Self {
        ResidualRow {
            t: r.t,
            beacon: r.beacon,
            applied: r.applied,
            innovation_m: r.innovation,
            innovation_sd_m: r.innovation_sd,
            smoothed_residual_m: r.smoothed,
            smoothed_residual_sd_m: r.smoothed_sd,
            held_out: r.held_out,
            nis: r.nis,
        }
    }
}

/// One line of `smoothed_ll.csv`.
#[derive(Serialize)]
struct LatLonRow {
    t: f64,
    smooth_lat_deg: f64,
    smooth_lon_deg: f64,
}

/// The tuning's before/after table: values, the held-out ranges' log predictive density, the
/// in-sample and held-out residual RMS; then the SDs and the guard's choice.
fn print_tuning(r: &TuneReport) {
    let o = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.3}"));
    let line = |name: &str, s: &Scored| {
        let v = &s.values;
        println!(
            "{name:<7} {:>10.3} {:>10.3e} {:>8.4} {:>9.3} {:>9.2} {:>12.2} {:>10} {:>10} {:>10} {:>10}",
            v.range_sd_m,
            v.q_en,
            v.speed_scale,
            v.heading_bias_deg,
            v.p0_en,
            s.held_out_log_predictive,
            o(s.in_sample_rms_filter_m),
            o(s.in_sample_rms_smoothed_m),
            o(s.held_out_rms_filter_m),
            o(s.held_out_rms_smoothed_m)
        )
    };
    println!(
        "tuning: {} iterations, {} evaluations of {} folds (every {}th range held out in turn)",
        r.iterations, r.evaluations, r.hold_out_every, r.hold_out_every
    );
    println!(
        "{:<7} {:>10} {:>10} {:>8} {:>9} {:>9} {:>12} {:>10} {:>10} {:>10} {:>10}",
        "",
        "range_sd",
        "q_en",
        "speed_k",
        "bias_deg",
        "p0_en",
        "heldout_lp",
        "in_filt_m",
        "in_smth_m",
        "out_filt_m",
        "out_smth_m"
    );
    line("before", &r.before);
    line("after", &r.after);
    let sd = &r.sd;
    println!(
        "{:<7} {:>10} {:>10} {:>8} {:>9} {:>9}",
        "± sd",
        o(sd.range_sd_m),
        sd.q_en.map_or("–".into(), |x| format!("{x:.3e}")),
        sd.speed_scale.map_or("–".into(), |x| format!("{x:.4}")),
        o(sd.heading_bias_deg),
        o(sd.p0_en)
    );
    let kept = match r.guard.kept {
        post_tune::Kept::Tuned => "the tuned values",
        post_tune::Kept::BestCandidate => "the search's best valid candidate",
        post_tune::Kept::Start => "the starting values",
    };
    println!("kept {kept}");
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn coefficients_print_at_their_precision() {
        assert_eq!(significant(3e-9, 4), "3.000e-9");
        assert_eq!(significant(-2.5e-7, 3), "-2.50e-7");
        assert_eq!(significant(0.0123456, 4), "0.01235");
        assert_eq!(significant(1.5, 4), "1.500");
        assert_eq!(significant(1234.5678, 4), "1235");
        assert_eq!(significant(2.0e7, 2), "2.0e7");
        assert_eq!(significant(0.0, 4), "0");
    }
}
