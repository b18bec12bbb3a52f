//! Fuzzing of every parser and codec coopnav reads input with: each target feeds
//! bytes to one parser and must get `Ok` or a typed error back, never a panic. Inputs come from a
//! seeded ChaCha generator: arbitrary bytes, and mutations of a valid seed input (bit flips,
//! truncations, splices, numbers replaced by extremes). It lives in the binary crate because the
//! `.alog` import and the Nams experiment file are parsed here.
//!
//! CI runs [`CI_INPUTS`] per target; a longer run takes the count from `COOPNAV_FUZZ_N`:
//! `COOPNAV_FUZZ_N=1000000 cargo test --release -p coopnav-cli --bin coopnav fuzz -- --ignored`.

use crate::{alog_import, nams};
use coopnav_acomms::node_report::{NodeReport, VehicleType};
use coopnav_acomms::status::{CovFrame0, CovStatus, CovarianceReport, Frame0, NextWaypoint, StatusMessage};
use coopnav_acomms::tracker::{HeaderEntry, MaskWidth, TrackingHeader};
use coopnav_core::{Bathymetry, CompassDeg, Heading, Vec3};
use coopnav_nav::codec::{Direction, MiniPacket, Sentence};
use coopnav_nav::cycle::{Configuration, Cycle};
use coopnav_nav::post::{self, PostConfig};
use coopnav_sim::scenario;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// Inputs per target in CI.
const CI_INPUTS: usize = 10_000;
/// Environment variable with the input count of the long (ignored) run.
const COUNT_VAR: &str = "COOPNAV_FUZZ_N";
/// Inputs per target of the long run when the variable is unset.
const LONG_DEFAULT: usize = 1_000_000;
/// Base seed of the generator; each target adds its index.
const SEED: u64 = 0x00C0_0F0F_F022;

/// Replacements for a numeric field: extremes, signed zero, non-finite, beyond every integer type.
const EXTREMES: [&str; 14] = [
    "1e308",
    "-1e308",
    "1e309",
    "-0",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "18446744073709551616",
    "-9223372036854775809",
    "99999999999999999999999999999999",
    "4e-324",
    "0",
    "-1",
];

/// One parser under fuzz: a valid seed input and the call (true when it accepted the input).
struct Target {
    name: &'static str,
    seed: fn() -> Vec<u8>,
    parse: fn(&[u8]) -> bool,
}

/// Every target, in one list.
const TARGETS: &[Target] = &[
    Target { name: "closed-loop scenario", seed: closed_loop_seed, parse: closed_loop_parse },
    Target { name: "closed-loop scenario, shelf", seed: shelf_seed, parse: closed_loop_parse },
    Target { name: "closed-loop scenario, buoys and ships", seed: gill_seed, parse: closed_loop_parse },
    Target { name: "closed-loop scenario, every table", seed: full_stack_seed, parse: closed_loop_parse },
    Target { name: "closed-loop scenario, AUV CNA", seed: auv_cna_seed, parse: closed_loop_parse },
    Target { name: "plan scenario, tracks", seed: plan_tracks_seed, parse: plan_parse },
    Target { name: "plan scenario", seed: plan_seed, parse: plan_parse },
    Target { name: "hbl scenario", seed: hbl_seed, parse: hbl_parse },
    Target { name: "hbl cycle", seed: cycle_seed, parse: cycle_parse },
    Target { name: "post-processing config", seed: post_config_seed, parse: post_config_parse },
    Target { name: "nams experiment", seed: nams_seed, parse: nams_parse },
    Target { name: "track csv", seed: track_seed, parse: track_parse },
    Target { name: "bathymetry ascii grid", seed: ascii_grid_seed, parse: ascii_grid_parse },
    Target { name: "bathymetry csv", seed: bathymetry_csv_seed, parse: bathymetry_csv_parse },
    Target { name: "post-processing log csv", seed: post_log_seed, parse: post_log_parse },
    Target { name: "alog reader", seed: alog_seed, parse: alog_parse },
    Target { name: "post-processing alog import", seed: alog_seed, parse: alog_import_parse },
    Target { name: "node report", seed: node_report_seed, parse: node_report_parse },
    Target { name: "status frame (thesis)", seed: frame0_seed, parse: frame0_parse },
    Target { name: "status frame (covariance)", seed: cov_frame_seed, parse: cov_frame_parse },
    Target { name: "tracking header", seed: header_seed, parse: header_parse },
    Target { name: "mini-packet word", seed: mini_packet_seed, parse: mini_packet_parse },
    Target { name: "nmea sentence", seed: nmea_seed, parse: nmea_parse },
];

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn closed_loop_seed() -> Vec<u8> {
    scenario::EXAMPLE.into()
}
fn closed_loop_parse(b: &[u8]) -> bool {
    scenario::Scenario::parse(&text(b), Path::new("fuzz.toml")).is_ok()
}

/// The example with its sloping shelf switched on.
fn shelf_seed() -> Vec<u8> {
    scenario::EXAMPLE.replacen("# shelf = { shallow", "shelf = { shallow", 1).into()
}
/// Gill's Table 5 set-up: transponder buoys and a ship broadcasting mini-packets.
fn gill_seed() -> Vec<u8> {
    include_str!("../../../scenarios/gill-table5-msbl.toml").into()
}
/// Every optional table at once (drifting buoys, ships, a shelf, finish behaviours), with the
/// analytic transmission loss so that no BELLHOP grid is computed per input.
fn full_stack_seed() -> Vec<u8> {
    let file = include_str!("../../../scenarios/full-stack.toml");
    let line = file.lines().find(|l| l.starts_with("tl = ")).expect("full-stack.toml names its tl");
    file.replacen(line, "tl = { kind = \"analytic\", k = 1.5, freq_hz = 25000.0 }", 1).into()
}
fn auv_cna_seed() -> Vec<u8> {
    include_str!("../../../scenarios/sloping-auv-cna.toml").into()
}
/// The plan example with its survey AUVs given as track files (parsed, not read).
fn plan_tracks_seed() -> Vec<u8> {
    let example = scenario::plan::EXAMPLE;
    let head = &example[..example.find("[[auv]]").expect("the plan example lists its AUVs")];
    format!("{head}[[auv]]\nname = \"auv1\"\ntrack_csv = \"auv1.csv\"\n\n[[auv]]\nname = \"auv2\"\ntrack_csv = \"auv2.csv\"\n")
        .into()
}

fn plan_seed() -> Vec<u8> {
    scenario::plan::EXAMPLE.into()
}
fn plan_parse(b: &[u8]) -> bool {
    scenario::plan::Scenario::parse(&text(b), Path::new("fuzz.toml")).is_ok()
}

fn hbl_seed() -> Vec<u8> {
    scenario::hbl::table5_file(Configuration::HblTwo).1.into()
}
fn hbl_parse(b: &[u8]) -> bool {
    scenario::hbl::parse(&text(b), Path::new("fuzz.toml")).is_ok()
}

fn cycle_seed() -> Vec<u8> {
    toml::to_string_pretty(&Cycle::hbl_short()).expect("the HBL Short cycle serialises").into()
}
fn cycle_parse(b: &[u8]) -> bool {
    Cycle::from_toml(&text(b)).is_ok()
}

fn post_config_seed() -> Vec<u8> {
    toml::to_string_pretty(&PostConfig::default()).expect("the default post config serialises").into()
}
fn post_config_parse(b: &[u8]) -> bool {
    PostConfig::from_toml(&text(b)).is_ok()
}

fn nams_seed() -> Vec<u8> {
    nams::example().expect("the Nams example serialises").into()
}
fn nams_parse(b: &[u8]) -> bool {
    nams::parse_file(&text(b), Path::new("fuzz.toml")).is_ok()
}

fn track_seed() -> Vec<u8> {
    b"t,x,y,z\n0,0,0,5\n1,1.5,2,5\n2,3,4.25,5.5\n3,4.5,6.5,6\n".to_vec()
}
fn track_parse(b: &[u8]) -> bool {
    scenario::tracks::parse_track_csv(&text(b), Path::new("fuzz.csv")).is_ok()
}

fn ascii_grid_seed() -> Vec<u8> {
    b"ncols 3\nnrows 2\nxllcorner 0\nyllcorner -20\ncellsize 10\nNODATA_value -9999\n50 51 52\n53 54 55\n".to_vec()
}
fn ascii_grid_parse(b: &[u8]) -> bool {
    Bathymetry::parse_ascii_grid(&text(b), "fuzz.asc").is_ok()
}

fn bathymetry_csv_seed() -> Vec<u8> {
    b"x,y,depth\n0,0,50\n10,0,51\n0,10,52\n10,10,53\n".to_vec()
}
fn bathymetry_csv_parse(b: &[u8]) -> bool {
    Bathymetry::parse_csv(&text(b), "fuzz.csv").is_ok()
}

fn post_log_seed() -> Vec<u8> {
    b"t,kind,src,v1,v2,v3,v4\n0,init,,0,0,1.5,90\n0.5,yaw_rate,,0.1,,,\n1,speed,,1.5,,,\n1,heading,,90,,,\n\
      1,depth,,5,,,\n2,range,13,0.25,,,\n3,ship_fix,,10,20,45,\n4,buoy_fix,,100,200,,\n5,truth,,1,2,,\n"
        .to_vec()
}
fn post_log_parse(b: &[u8]) -> bool {
    post::read_log(b, None).is_ok()
}

fn alog_seed() -> Vec<u8> {
    b"%% LOG FILE:  fuzz.alog\n%%LOGSTART 1000.5\n0.100 NAV_X pNav 12.5\n0.100 NAV_Y pNav -3.25\n\
      0.100 NAV_SPEED pNav 1.5\n0.100 NAV_HEADING pNav 91\n0.300 NAV_DEPTH pNav 5\n0.300 NAV_YAW_RATE pNav 0.1\n\
      0.400 GPS_X pGPS 12\n0.400 GPS_Y pGPS -3\n1.250 OWTT_RANGE pAcomms id=13,travel_time=0.25\n\
      2.000 BUOY_FIX pAcomms x=100,y=200\n2.500 SHIP_FIX pAcomms x=10,y=20,heading=45\n"
        .to_vec()
}
fn alog_parse(b: &[u8]) -> bool {
    coopnav_moos::alog::read_alog(b).is_ok()
}
fn alog_import_parse(b: &[u8]) -> bool {
    coopnav_moos::alog::read_alog(b).is_ok_and(|log| alog_import::rows(&log, &Default::default(), 1.5, None).is_ok())
}

fn node_report_seed() -> Vec<u8> {
    NodeReport {
        src_id: 3,
        time_of_day: 43_210,
        vehicle: VehicleType::Glider,
        x: -1234.0,
        y: 567.0,
        speed: 1.5,
        heading: Heading::from(CompassDeg(271.0)),
        waypoints: vec![(100.0, -200.0), (300.0, 400.0)],
        front_seat_error: 2,
        front_mode: 1,
        leak: false,
        depth: 12.3,
        altitude: 4.5,
        battery: 87.0,
    }
    .encode()
    .expect("the seed node report encodes")
}
fn node_report_parse(b: &[u8]) -> bool {
    NodeReport::decode(b).is_ok()
}

fn header() -> TrackingHeader {
    TrackingHeader {
        entries: (1..=4).map(|c| HeaderEntry { cycles_ago: c * 2, frames: 1 + u16::from(c) }).collect(),
        truncated: false,
    }
}
fn status() -> StatusMessage {
    StatusMessage {
        pos: Vec3::new(1234.5, -987.6, 33.3),
        heading: Heading::from_radians(0.3),
        speed: 1.54,
        next: NextWaypoint::LatLon { lat: 44.7, lon: -63.6 },
    }
}

fn frame0_seed() -> Vec<u8> {
    Frame0 { header: header(), status: status() }.encode(MaskWidth::Narrow, 256).expect("the seed frame encodes")
}
fn frame0_parse(b: &[u8]) -> bool {
    // Both widths: the same bytes are a valid input to either.
    let narrow = Frame0::decode(b, MaskWidth::Narrow).is_ok();
    Frame0::decode(b, MaskWidth::Wide).is_ok() || narrow
}

fn cov_frame_seed() -> Vec<u8> {
    let cov = CovarianceReport { sigma_major: 12.0, sigma_minor: 3.0, orientation: 0.5 };
    CovFrame0 { header: header(), status: CovStatus { status: status(), cov } }
        .encode(MaskWidth::Wide, 256)
        .expect("the seed covariance frame encodes")
}
fn cov_frame_parse(b: &[u8]) -> bool {
    let narrow = CovFrame0::decode(b, MaskWidth::Narrow).is_ok();
    CovFrame0::decode(b, MaskWidth::Wide).is_ok() || narrow
}

fn header_seed() -> Vec<u8> {
    header().encode(MaskWidth::Narrow).expect("the seed header encodes")
}
fn header_parse(b: &[u8]) -> bool {
    let narrow = TrackingHeader::decode(b, MaskWidth::Narrow).is_ok();
    TrackingHeader::decode(b, MaskWidth::Wide).is_ok() || narrow
}

fn mini_packet_seed() -> Vec<u8> {
    0x1A05u16.to_be_bytes().to_vec()
}
/// Every byte pair as a 13-bit word (the modem hands over 16 bits).
fn mini_packet_parse(b: &[u8]) -> bool {
    b.chunks(2).fold(false, |any, pair| {
        let word = u16::from_be_bytes([pair[0], pair.get(1).copied().unwrap_or(0)]);
        MiniPacket::from_word(word).is_ok() || any
    })
}

fn nmea_seed() -> Vec<u8> {
    let packet = MiniPacket::from_word(0x1A05).expect("0x1A05 is a North packet");
    Sentence { direction: Direction::Received, src: 13, dest: 0, packet }.to_string().into()
}
fn nmea_parse(b: &[u8]) -> bool {
    text(b).parse::<Sentence>().is_ok()
}

/// The byte range of every number-looking token of `seed` (digits with sign, point, exponent).
fn numeric_tokens(seed: &[u8]) -> Vec<(usize, usize)> {
    let numeric = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E');
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < seed.len() {
        if seed[i].is_ascii_digit() {
            let start = (0..i).rev().take_while(|&j| numeric(seed[j])).last().unwrap_or(i);
            let end = (i..seed.len()).find(|&j| !numeric(seed[j])).unwrap_or(seed.len());
            tokens.push((start, end));
            i = end;
        } else {
            i += 1;
        }
    }
    tokens
}

fn flip_bits(rng: &mut ChaCha8Rng, b: &mut [u8]) {
    for _ in 0..rng.gen_range(1..=8) {
        let bit = rng.gen_range(0..b.len() * 8);
        b[bit / 8] ^= 1 << (bit % 8);
    }
}

/// Replaces a number by an extreme (text), or a byte by 0x00/0xFF (binary, no numbers).
fn replace_number(rng: &mut ChaCha8Rng, b: &mut Vec<u8>) {
    let tokens = numeric_tokens(b);
    if tokens.is_empty() {
        let at = rng.gen_range(0..b.len());
        b[at] = if rng.gen() { 0xFF } else { 0x00 };
        return;
    }
    let (start, end) = tokens[rng.gen_range(0..tokens.len())];
    let extreme = EXTREMES[rng.gen_range(0..EXTREMES.len())];
    b.splice(start..end, extreme.bytes());
}

/// Joins two random pieces of the input, or inserts a random piece of it elsewhere.
fn splice(rng: &mut ChaCha8Rng, b: &mut Vec<u8>) {
    let (a, c) = (rng.gen_range(0..=b.len()), rng.gen_range(0..=b.len()));
    let (lo, hi) = (a.min(c), a.max(c));
    if rng.gen() {
        b.drain(lo..hi);
    } else {
        let piece = b[lo..hi].to_vec();
        let at = rng.gen_range(0..=b.len());
        b.splice(at..at, piece);
    }
}

fn arbitrary_bytes(rng: &mut ChaCha8Rng, typical_len: usize) -> Vec<u8> {
    let len = rng.gen_range(0..=2 * typical_len + 16);
    (0..len).map(|_| rng.gen()).collect()
}

/// One input: a quarter arbitrary bytes, the rest 1–4 mutations of the seed.
fn input(rng: &mut ChaCha8Rng, seed: &[u8]) -> Vec<u8> {
    if rng.gen_ratio(1, 4) {
        return arbitrary_bytes(rng, seed.len());
    }
    let mut b = seed.to_vec();
    for _ in 0..rng.gen_range(1..=4) {
        if b.is_empty() {
            break;
        }
        match rng.gen_range(0..4) {
            0 => flip_bits(rng, &mut b),
            1 => b.truncate(rng.gen_range(0..b.len())),
            2 => splice(rng, &mut b),
            _ => replace_number(rng, &mut b),
        }
    }
    b
}

/// What parsing and validating `bytes` may allocate at its peak: a fixed allowance, a few
/// copies of the input (its text, the TOML tree, the parsed rows) and the grid a closed-loop
/// scenario's sloping shelf asks for, as the work limits estimate it. An input within it cannot
/// abort on an allocation before the limits are checked.
fn parse_budget(bytes: &[u8]) -> f64 {
    const ALLOWANCE: f64 = 1e6;
    const COPIES: f64 = 32.0;
    let grid = toml::from_str::<scenario::Scenario>(&text(bytes))
        .ok()
        .and_then(|sc| coopnav_sim::batch::work::shelf(sc.fleet.shelf.as_ref(), "fleet.shelf"))
        .map_or(0.0, |e| {
            if e.value.is_nan() {
                0.0
            } else {
                e.value.clamp(0.0, coopnav_core::bathymetry::MAX_GRID_NODES) * 8.0
            }
        });
    ALLOWANCE + COPIES * bytes.len() as f64 + grid
}

/// The bytes one thread holds allocated, and its peak, counted by the test build's allocator so
/// that a fuzz target's parse is measured apart from the tests running beside it.
#[cfg(test)]
mod meter {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        static HELD: Cell<usize> = const { Cell::new(0) };
        static PEAK: Cell<usize> = const { Cell::new(0) };
    }

    struct Meter;

    #[global_allocator]
    static METER: Meter = Meter;

    fn change(grow: usize, shrink: usize) {
        let _ = HELD.try_with(|held| {
            let now = (held.get() + grow).saturating_sub(shrink);
            held.set(now);
            let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
        });
    }

    // SAFETY: every call is forwarded to the system allocator unchanged; the counters are
    // thread-local cells that never allocate.
    unsafe impl GlobalAlloc for Meter {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            let p = unsafe { System.alloc(layout) };
            if !p.is_null() {
                change(layout.size(), 0);
            }
            p
        }
        unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
            unsafe { System.dealloc(p, layout) };
            change(0, layout.size());
        }
        unsafe fn realloc(&self, p: *mut u8, layout: Layout, size: usize) -> *mut u8 {
            let q = unsafe { System.realloc(p, layout, size) };
            if !q.is_null() {
                change(size, layout.size());
            }
            q
        }
    }

    /// `f`'s result and the most bytes it held allocated at once, on this thread.
    pub fn measure<R>(f: impl FnOnce() -> R) -> (R, usize) {
        let start = HELD.with(Cell::get);
        PEAK.with(|p| p.set(start));
        let r = f();
        (r, PEAK.with(Cell::get) - start)
    }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// Runs `count` inputs into `target`; returns how many it accepted, or the first panicking input.
fn fuzz(index: usize, target: &Target, count: usize) -> Result<usize, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED + index as u64);
    let seed = (target.seed)();
    assert!((target.parse)(&seed), "{}: the seed input must parse", target.name);
    let mut accepted = 0;
    let mut most = 0;
    for n in 0..count {
        let bytes = input(&mut rng, &seed);
        match catch_unwind(AssertUnwindSafe(|| meter::measure(|| (target.parse)(&bytes)))) {
            Ok((ok, peak)) => {
                accepted += usize::from(ok);
                most = most.max(peak);
                let budget = parse_budget(&bytes);
                if peak as f64 > budget {
                    return Err(format!(
                        "{}: input {n} ({}) allocated {peak} bytes parsing, over its budget of {budget:.0}; hex {}",
                        target.name,
                        if ok { "accepted" } else { "refused" },
                        hex(&bytes)
                    ));
                }
            }
            Err(_) => return Err(format!("{}: input {n} panicked; hex {}", target.name, hex(&bytes))),
        }
    }
    eprintln!("fuzz {}: at most {most} bytes held while parsing one input", target.name);
    Ok(accepted)
}

fn fuzz_all(count: usize) {
    let mut panics = Vec::new();
    for (index, target) in TARGETS.iter().enumerate() {
        match fuzz(index, target, count) {
            Ok(accepted) => eprintln!("fuzz {}: {count} inputs, {accepted} accepted, 0 panics", target.name),
            Err(e) => panics.push(e),
        }
    }
    assert!(panics.is_empty(), "parsers panicked:\n{}", panics.join("\n"));
}

/// Found by the ascii-grid target: `nrows 1e308` reserved a row vector of that size and aborted.
#[test]
fn ascii_grid_with_absurd_nrows_is_an_error() {
    let text = "ncols 3\nnrows 1e308\nxllcorner 0\nyllcorner -20\ncellsize 10\n50 51 52\n";
    assert!(Bathymetry::parse_ascii_grid(text, "huge.asc").is_err());
}

#[test]
fn every_parser_survives_ci_inputs() {
    fuzz_all(CI_INPUTS);
}

#[test]
#[ignore = "long run: COOPNAV_FUZZ_N inputs per target, in release mode"]
fn every_parser_survives_long_run() {
    let count = std::env::var(COUNT_VAR).map_or(LONG_DEFAULT, |v| {
        v.parse().unwrap_or_else(|_| panic!("{COUNT_VAR}={v:?} must be a whole number of inputs"))
    });
    fuzz_all(count);
}
