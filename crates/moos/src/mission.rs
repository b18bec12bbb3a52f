//! MOOS-IvP mission files for a planned CNA path: a `.moos` (the community's global settings and
//! the usual ProcessConfig blocks: uSimMarine, pHelmIvP, pMarinePIDV22, pNodeReporter, pLogger,
//! and pMarineViewer to watch it, launched by pAntler) and a `.bhv` whose BHV_Waypoint behaviours fly the CNA's waypoints at the
//! planned speed, with every leg's timing as comments.
//!
//! An ASC CNA gets one BHV_Waypoint with all the points. An AUV CNA changes depth along its plan:
//! the waypoints are cut into runs of equal depth, and run k is one BHV_Waypoint and one
//! BHV_ConstantDepth, both active while `LEG = k`; reaching the run's last point posts
//! `LEG = k+1`, which hands over to the next run.

use std::fmt::Write as _;

use coopnav_core::LatLon;

/// LatOrigin / LongOrigin when the caller has none: the origin of MOOS-IvP's example missions (MIT
/// sailing pavilion, Charles River). Invented for coopnav: a plan's local frame has no geodetic
/// anchor.
pub const EXAMPLE_ORIGIN_DEG: (f64, f64) = (42.358456, -71.087589);

/// Depths closer than this fly as one run, m.
const DEPTH_RESOLUTION_M: f64 = 0.1;

/// One planned waypoint: reached at `t` (s from the start of the plan), compass heading of the leg
/// that ends there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waypoint {
    pub t: f64,
    pub x: f64,
    pub y: f64,
    pub depth: f64,
    pub heading_compass_deg: f64,
}

/// What the mission files say.
#[derive(Debug, Clone)]
pub struct MissionSpec {
    /// The MOOS community (vehicle) name.
    pub community: String,
    pub server_port: u16,
    /// LatOrigin / LongOrigin of the local frame.
    pub origin: LatLon,
    /// Transit speed, m/s.
    pub speed: f64,
    /// An AUV CNA (depth control, per-run depths) instead of an ASC.
    pub auv: bool,
    /// Where the CNA starts.
    pub start: Waypoint,
    pub waypoints: Vec<Waypoint>,
    /// BHV_Waypoint capture radius, m. Invented (MOOS-IvP's example missions use 5 m).
    pub capture_radius_m: f64,
}

/// The two files, named after the community.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionFiles {
    pub moos_name: String,
    pub moos: String,
    pub bhv_name: String,
    pub bhv: String,
}

/// Writes both files.
pub fn mission_files(spec: &MissionSpec) -> MissionFiles {
    let bhv_name = format!("{}.bhv", spec.community);
    MissionFiles {
        moos_name: format!("{}.moos", spec.community),
        moos: moos_file(spec, &bhv_name),
        bhv_name,
        bhv: bhv_file(spec),
    }
}

fn moos_file(spec: &MissionSpec, bhv_name: &str) -> String {
    let s = &spec.start;
    let mut f = String::new();
    let _ = writeln!(f, "// coopnav plan: MOOS community of the CNA; its path is in {bhv_name}.");
    let _ = writeln!(f, "// Launch with: pAntler {}.moos", spec.community);
    let _ = writeln!(f, "ServerHost   = localhost");
    let _ = writeln!(f, "ServerPort   = {}", spec.server_port);
    let _ = writeln!(f, "Community    = {}", spec.community);
    let _ = writeln!(f, "MOOSTimeWarp = 1");
    let _ = writeln!(f, "LatOrigin    = {:.8}", spec.origin.lat_deg());
    let _ = writeln!(f, "LongOrigin   = {:.8}", spec.origin.lon_deg());
    block(
        &mut f,
        "ANTLER",
        &[
            "MSBetweenLaunches = 200",
            "Run = MOOSDB @ NewConsole = false",
            "Run = uSimMarine @ NewConsole = false",
            "Run = pHelmIvP @ NewConsole = false",
            "Run = pMarinePIDV22 @ NewConsole = false",
            "Run = pNodeReporter @ NewConsole = false",
            "Run = pLogger @ NewConsole = false",
            "Run = pMarineViewer @ NewConsole = false",
        ],
    );
    let start = format!(
        "start_pos = x={:.2},y={:.2},heading={:.1},speed=0,depth={:.2}",
        s.x, s.y, s.heading_compass_deg, s.depth
    );
    block(&mut f, "uSimMarine", &["AppTick = 4", "CommsTick = 4", &start, "prefix = NAV"]);
    let behaviours = format!("behaviors = {bhv_name}");
    let mut helm =
        vec!["AppTick = 4", "CommsTick = 4", &behaviours, "domain = course:0:359:360", "domain = speed:0:4:41"];
    if spec.auv {
        helm.push("domain = depth:0:500:501");
    }
    block(&mut f, "pHelmIvP", &helm);
    // Gains as in MOOS-IvP's example missions (invented for coopnav: tune them for the craft).
    let mut pid = vec![
        "AppTick = 10",
        "CommsTick = 10",
        "verbose = terse",
        "active_start = true",
        "yaw_pid_kp = 1.2",
        "yaw_pid_kd = 0.0",
        "yaw_pid_ki = 0.3",
        "yaw_pid_integral_limit = 0.07",
        "speed_pid_kp = 1.0",
        "speed_pid_kd = 0.0",
        "speed_pid_ki = 0.0",
        "speed_pid_integral_limit = 0.07",
        "maxrudder = 100",
        "maxthrust = 100",
        "speed_factor = 20",
    ];
    if spec.auv {
        pid.extend([
            "depth_control = true",
            "pitch_pid_kp = 1.5",
            "pitch_pid_kd = 0.3",
            "pitch_pid_ki = 0.004",
            "pitch_pid_integral_limit = 0",
            "z_to_pitch_pid_kp = 0.12",
            "z_to_pitch_pid_kd = 0",
            "z_to_pitch_pid_ki = 0.004",
            "z_to_pitch_pid_integral_limit = 0.05",
            "maxpitch = 15",
            "maxelevator = 13",
        ]);
    } else {
        pid.push("depth_control = false");
    }
    block(&mut f, "pMarinePIDV22", &pid);
    let platform = format!("platform_type = {}", if spec.auv { "UUV" } else { "SHIP" });
    block(&mut f, "pNodeReporter", &["AppTick = 2", "CommsTick = 2", &platform, "platform_color = orange"]);
    let file = format!("File = LOG_{}", spec.community.to_uppercase());
    block(
        &mut f,
        "pLogger",
        &["AppTick = 8", "CommsTick = 8", "AsyncLog = true", &file, "PATH = ./", "WildCardLogging = true"],
    );
    // The operator's view: the CNA's node reports and its path as the helm posts it.
    block(
        &mut f,
        "pMarineViewer",
        &[
            "AppTick = 4",
            "CommsTick = 4",
            "tiff_viewable = false",
            "hash_viewable = true",
            "vehicle_shape_scale = 1.5",
            "seglist_viewable_all = true",
            "point_viewable_labels = false",
        ],
    );
    f
}

fn block(f: &mut String, process: &str, lines: &[&str]) {
    let _ = writeln!(f, "\nProcessConfig = {process}\n{{");
    for line in lines {
        let _ = writeln!(f, "  {line}");
    }
    let _ = writeln!(f, "}}");
}

fn bhv_file(spec: &MissionSpec) -> String {
    let mut f = String::new();
    let _ = writeln!(f, "// coopnav plan: the CNA's planned path for pHelmIvP, at {} m/s.", spec.speed);
    let _ = writeln!(
        f,
        "// Times are seconds from the start of the plan; headings compass degrees (0 = north, clockwise)."
    );
    let _ = writeln!(
        f,
        "// start: t = {:.1}, ({:.2}, {:.2}), depth {:.2} m, heading {:.1}",
        spec.start.t, spec.start.x, spec.start.y, spec.start.depth, spec.start.heading_compass_deg
    );
    let mut from = spec.start.t;
    for (i, w) in spec.waypoints.iter().enumerate() {
        let _ = writeln!(
            f,
            "// leg {}: t = {:.1} .. {:.1}, to ({:.2}, {:.2}), depth {:.2} m, heading {:.1}",
            i + 1,
            from,
            w.t,
            w.x,
            w.y,
            w.depth,
            w.heading_compass_deg
        );
        from = w.t;
    }
    let _ = writeln!(f, "\ninitialize DEPLOY = true");
    let runs = depth_runs(spec);
    if spec.auv {
        let _ = writeln!(f, "initialize LEG = 1");
    }
    for (k, run) in runs.iter().enumerate() {
        let pts: Vec<String> = run.iter().map(|w| format!("{:.2},{:.2}", w.x, w.y)).collect();
        let _ = writeln!(f, "\nBehavior = BHV_Waypoint\n{{");
        let _ = writeln!(f, "  name           = cna_path_{}", k + 1);
        let _ = writeln!(f, "  pwt            = 100");
        let _ = writeln!(f, "  condition      = DEPLOY = true");
        if spec.auv {
            let _ = writeln!(f, "  condition      = LEG = {}", k + 1);
            let _ = writeln!(f, "  endflag        = LEG = {}", k + 2);
        }
        let _ = writeln!(f, "  speed          = {}", spec.speed);
        let _ = writeln!(f, "  capture_radius = {}", spec.capture_radius_m);
        let _ = writeln!(f, "  slip_radius    = {}", 3.0 * spec.capture_radius_m);
        let _ = writeln!(f, "  points         = {}", pts.join(":"));
        let _ = writeln!(f, "}}");
        if spec.auv {
            let _ = writeln!(f, "\nBehavior = BHV_ConstantDepth\n{{");
            let _ = writeln!(f, "  name      = cna_depth_{}", k + 1);
            let _ = writeln!(f, "  pwt       = 100");
            let _ = writeln!(f, "  condition = DEPLOY = true");
            let _ = writeln!(f, "  condition = LEG = {}", k + 1);
            let _ = writeln!(f, "  depth     = {:.2}", run[0].depth);
            let _ = writeln!(f, "}}");
        }
    }
    f
}

/// The waypoints cut into runs of one depth (all of them in one run for an ASC).
fn depth_runs(spec: &MissionSpec) -> Vec<&[Waypoint]> {
    if !spec.auv {
        return vec![&spec.waypoints];
    }
    spec.waypoints.chunk_by(|a, b| (a.depth - b.depth).abs() < DEPTH_RESOLUTION_M).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn waypoint(t: f64, x: f64, depth: f64) -> Waypoint {
        Waypoint { t, x, y: 0.0 - x, depth, heading_compass_deg: 135.0 }
    }

    fn spec(auv: bool) -> MissionSpec {
        let depth = |d: f64| if auv { d } else { 0.0 };
        MissionSpec {
            community: "cna".into(),
            server_port: 9000,
            origin: LatLon::new(42.358456, -71.087589).unwrap(),
            speed: 1.5,
            auv,
            start: waypoint(0.0, 0.0, depth(0.0)),
            waypoints: vec![
                waypoint(10.0, 10.0, depth(5.0)),
                waypoint(20.0, 20.0, depth(5.04)),
                waypoint(30.0, 30.0, depth(12.0)),
            ],
            capture_radius_m: 5.0,
        }
    }

    #[test]
    fn an_asc_flies_every_point_in_one_behaviour_without_depth_control() {
        let files = mission_files(&spec(false));
        assert_eq!((files.moos_name.as_str(), files.bhv_name.as_str()), ("cna.moos", "cna.bhv"));
        assert_eq!(files.bhv.matches("Behavior = BHV_Waypoint").count(), 1);
        assert!(files.bhv.contains("  points         = 10.00,-10.00:20.00,-20.00:30.00,-30.00\n"));
        assert!(!files.bhv.contains("BHV_ConstantDepth") && !files.bhv.contains("LEG"));
        assert!(files.moos.contains("depth_control = false") && !files.moos.contains("domain = depth"));
        assert!(files.bhv.contains("// leg 2: t = 10.0 .. 20.0, to (20.00, -20.00), depth 0.00 m, heading 135.0\n"));
    }

    #[test]
    fn an_auv_changes_depth_run_by_run() {
        let files = mission_files(&spec(true));
        assert_eq!(files.bhv.matches("Behavior = BHV_Waypoint").count(), 2, "5 m and 5.04 m are one run");
        assert!(files.bhv.contains("  condition      = LEG = 1\n  endflag        = LEG = 2\n"));
        assert!(files.bhv.contains("  points         = 10.00,-10.00:20.00,-20.00\n"));
        assert!(files.bhv.contains("  condition = LEG = 2\n  depth     = 12.00\n"));
        assert!(files.moos.contains("depth_control = true") && files.moos.contains("domain = depth:0:500:501"));
        assert!(files.moos.contains("start_pos = x=0.00,y=0.00,heading=135.0,speed=0,depth=0.00"));
    }
}
