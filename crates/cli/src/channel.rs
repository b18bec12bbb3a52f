//! `coopnav channel`: transmission loss and packet-success likelihood per WHOI rate against
//! range, for one environment: a text table on stdout, and a run directory with CSV and SVG plots.

use anyhow::{Context, Result};
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::{Rate, SuccessModel, TransmissionLoss};
use coopnav_core::limits::{self, Estimate, MAX_POINTS};
use coopnav_core::validation::{InvalidFields, Problems};
use coopnav_core::{Bathymetry, CompassDeg, Heading, Shelf, Vec3};
use coopnav_sim::output::plot::{line_svg, Labels, Series};
use coopnav_sim::output::Manifest;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Clone, Copy, Debug, clap::ValueEnum, Serialize)]
enum Model {
    /// Spreading + Thorp absorption.
    Analytic,
    /// The real BELLHOP program (scripts/install-bellhop.sh).
    Bellhop,
}

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    #[arg(long, value_enum, default_value = "analytic")]
    model: Model,
    /// Spreading factor k of the analytic model (1.5 practical, 2 spherical).
    #[arg(long, default_value_t = 2.0)]
    k: f64,
    /// Extra ambient noise, dB (the thesis compares 0 and 6).
    #[arg(long, default_value_t = 0.0)]
    noise_db: f64,
    /// Source position x, y (m) and depth (m).
    #[arg(long, default_value_t = 0.0)]
    x: f64,
    #[arg(long, default_value_t = 0.0)]
    y: f64,
    #[arg(long, default_value_t = 20.0)]
    source_depth: f64,
    /// Receiver depth, m.
    #[arg(long, default_value_t = 20.0)]
    receiver_depth: f64,
    /// Bearing of the slice from the source, compass degrees (0 = north, clockwise), as every
    /// angle coopnav reads; 90 (east) by default.
    #[arg(long, default_value_t = 90.0)]
    bearing_compass_deg: f64,
    /// Largest range, m, and range step, m.
    #[arg(long, default_value_t = 3000.0)]
    max_range: f64,
    #[arg(long, default_value_t = 100.0)]
    step: f64,
    /// Bathymetry grid (.asc ESRI raster or CSV x,y,depth); default: the synthetic shelf.
    #[arg(long)]
    bathymetry: Option<PathBuf>,
    /// Output directory (default: a fresh runs/channel-N).
    #[arg(short, long = "output", alias = "out")]
    out: Option<PathBuf>,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
    /// Run even when the estimated work or memory is above coopnav's limits (coopnav_core::limits).
    #[arg(long)]
    allow_large: bool,
}

#[derive(Serialize)]
struct Row {
    range_m: f64,
    tl_db: f64,
    p_rate0: f64,
    p_rate1: f64,
    p_rate4: f64,
    p_rate5: f64,
}

impl Args {
    /// Checks every number and reports every bad one at once.
    fn validate(&self) -> Result<(), InvalidFields> {
        let mut p = Problems::new();
        p.check("--k", self.k, |k| k > 0.0 && k <= 4.0, "in (0, 4]");
        p.check("--noise-db", self.noise_db, |v| (0.0..=60.0).contains(&v), "in [0, 60] dB");
        p.finite("--x", self.x);
        p.finite("--y", self.y);
        p.non_negative("--source-depth", self.source_depth);
        p.non_negative("--receiver-depth", self.receiver_depth);
        p.finite("--bearing-compass-deg", self.bearing_compass_deg);
        p.positive("--step", self.step);
        p.require("--max-range", self.max_range, self.max_range >= self.step, "a finite number ≥ --step");
        p.finish()
    }
}

pub fn run(args: Args) -> Result<()> {
    args.validate().context("coopnav channel arguments")?;
    let ranges = Estimate::new("table rows", "--max-range / --step", args.max_range / args.step, MAX_POINTS);
    limits::check([ranges], args.allow_large)?;
    let bathy = match &args.bathymetry {
        Some(p) => Bathymetry::load(p)?,
        None => Bathymetry::shelf(&Shelf::default())?,
    };
    let inputs: Vec<&Path> = args.bathymetry.as_deref().into_iter().collect();
    let run = crate::run_dir::given_or_fresh(args.out.as_deref(), args.force, &inputs, "channel")?;
    let tl: Box<dyn TransmissionLoss> = match args.model {
        Model::Analytic => Box::new(Thorp { k: args.k, ..Thorp::default() }),
        Model::Bellhop => Box::new(Bellhop::new(AcousticEnv::nams(Arc::new(bathy)))?),
    };
    let src = Vec3::new(args.x, args.y, args.source_depth);
    let ranges: Vec<f64> = (1..=(args.max_range / args.step).floor() as usize).map(|i| i as f64 * args.step).collect();
    let field = tl
        .field(&src, Heading::from(CompassDeg(args.bearing_compass_deg)).radians(), &ranges, &[args.receiver_depth])
        .context("computing transmission loss")?;
    let model = SuccessModel { noise_db: args.noise_db, ..SuccessModel::default() };
    let rows: Vec<Row> = ranges
        .iter()
        .zip(&field)
        .map(|(&range_m, &tl_db)| {
            let p = |r: Rate| model.p_success(r, tl_db);
            Row {
                range_m,
                tl_db,
                p_rate0: p(Rate::R0),
                p_rate1: p(Rate::R1),
                p_rate4: p(Rate::R4),
                p_rate5: p(Rate::R5),
            }
        })
        .collect();
    println!("{:>8} {:>8} {:>7} {:>7} {:>7} {:>7}", "range m", "TL dB", "p(r0)", "p(r1)", "p(r4)", "p(r5)");
    for r in &rows {
        println!(
            "{:>8.0} {:>8.1} {:>7.3} {:>7.3} {:>7.3} {:>7.3}",
            r.range_m, r.tl_db, r.p_rate0, r.p_rate1, r.p_rate4, r.p_rate5
        );
    }
    let tl_series = [Series::new("TL", rows.iter().map(|r| (r.range_m, r.tl_db)).collect())];
    let p_series: Vec<Series> = [("rate 0", 0), ("rate 1", 1), ("rate 4", 2), ("rate 5", 3)]
        .iter()
        .map(|&(name, i)| {
            Series::new(
                name,
                rows.iter().map(|r| (r.range_m, [r.p_rate0, r.p_rate1, r.p_rate4, r.p_rate5][i])).collect(),
            )
        })
        .collect();
    let model_name = format!("{:?}", args.model).to_lowercase();
    run.write_text(
        "tl.svg",
        &line_svg(
            Labels { title: &format!("Transmission loss ({model_name})"), x: "range (m)", y: "TL (dB)" },
            &tl_series,
        )?,
    )?;
    run.write_text(
        "success.svg",
        &line_svg(
            Labels { title: &format!("Packet success, noise +{} dB", args.noise_db), x: "range (m)", y: "P(success)" },
            &p_series,
        )?,
    )?;
    run.write_csv("channel.csv", &rows)?;
    run.write_json("manifest.json", &Manifest::new("channel", None, serde_json::to_value(&args)?))?;
    let dir = run.finish()?;
    eprintln!("wrote {}", dir.display());
    Ok(())
}
