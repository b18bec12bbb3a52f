//! `coopnav generate`: writes the missions a generator file draws (`scenarios/generators/generalization.toml`
//! and the like), one scenario file each, that `coopnav simulate` runs as they are, with an index
//! of every mission's facts (missions.csv).

use anyhow::{Context, Result};
use coopnav_sim::output::Manifest;
use coopnav_sim::scenario::generate::Ranges;
use serde::Serialize;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The generator file (ranges and seed).
    file: PathBuf,
    /// Seed of mission 0 (default: the file's); mission i's is this + i.
    #[arg(long)]
    seed: Option<u64>,
    /// How many missions (default: the file's).
    #[arg(long)]
    missions: Option<usize>,
    /// Output directory (default: a fresh runs/generate).
    #[arg(short, long = "output", alias = "out")]
    out: Option<PathBuf>,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
}

/// One row of missions.csv.
#[derive(Serialize)]
struct Row<'a> {
    file: String,
    seed: u64,
    n_auvs: usize,
    layout: &'static str,
    gap_m: Option<f64>,
    fleet_span_m: f64,
    lane_heading_deg: f64,
    current_m_s: f64,
    current_towards_deg: f64,
    cna: &'a str,
    channel: &'a str,
    filter: &'a str,
    duration_s: f64,
}

pub fn run(args: Args) -> Result<()> {
    let text = crate::input::read(&args.file, false)?;
    let read = Ranges::parse(&text, &args.file);
    let mut ranges = crate::input::parsed_as(read, &text, &args.file, crate::input::Format::Generator)?;
    ranges.seed = args.seed.unwrap_or(ranges.seed);
    ranges.missions = args.missions.unwrap_or(ranges.missions);
    ranges.validate(&args.file)?;
    let dir = crate::run_dir::given_or_fresh(args.out.as_deref(), args.force, &[&args.file], "generate")?;
    let missions = ranges.generate(&args.file)?;
    let mut rows = Vec::new();
    for m in &missions {
        let text = m.to_toml().with_context(|| format!("writing mission {}", m.facts.index))?;
        dir.write_text(&m.file_name(), &text)?;
        let f = &m.facts;
        rows.push(Row {
            file: m.file_name(),
            seed: f.seed,
            n_auvs: f.n_auvs,
            layout: f.layout.name(),
            gap_m: f.gap_m,
            fleet_span_m: f.fleet_span_m,
            lane_heading_deg: f.lane_heading_deg,
            current_m_s: f.current_m_s,
            current_towards_deg: f.current_towards_deg,
            cna: &f.cna,
            channel: &f.channel,
            filter: &f.filter,
            duration_s: f.duration_s,
        });
    }
    dir.write_csv("missions.csv", rows)?;
    let inputs = serde_json::json!({ "file": args.file, "ranges": ranges });
    dir.write_json("manifest.json", &Manifest::new("generate", Some(ranges.seed), inputs))?;
    eprintln!("wrote {} missions to {}", missions.len(), dir.finish()?.display());
    Ok(())
}
