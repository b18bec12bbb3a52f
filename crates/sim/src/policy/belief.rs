//! What the CNA knows of the survey AUVs, built the same way wherever the CNA runs (the engine's
//! CNA and `coopnav live cna`): one underway predictor per AUV, started from the AUV's mission
//! plan when the operator gave it (`policy.before_first_report = "mission_plan"`), and what a
//! received status message (Appendix C node report with the covariance trailer) tells it.

use crate::policy::ReportedCov;
use crate::scenario::start::auv_launch;
use crate::scenario::world::{BeforeFirstReport, Scenario};
use coopnav_acomms::codec::DecodeError;
use coopnav_acomms::node_report::NodeReport;
use coopnav_acomms::status::{CovTrailer, CovarianceReport};
use coopnav_core::{Bathymetry, Heading, Vec3};
use coopnav_plan::predict::{StatusReport, UnderwayPredictor};

/// The CNA's predictor of survey AUV `k` (over `bathy`, the scenario's bathymetry), knowing its
/// mission plan when the scenario says the operator gave it: launch point and time, planned
/// speed and every planned waypoint, as the fleet configuration defines them.
pub fn predictor(sc: &Scenario, k: usize, bathy: &Bathymetry) -> UnderwayPredictor {
    let predictor = UnderwayPredictor::new(sc.predictor_config());
    if sc.policy.before_first_report == BeforeFirstReport::Ignore {
        return predictor;
    }
    let launch = auv_launch(sc, k, bathy);
    predictor.with_plan(StatusReport {
        t: 0.0,
        pos: launch.pos,
        speed: sc.fleet.speed,
        heading: Heading::from_radians(launch.heading),
        waypoints: launch.waypoints,
    })
}

/// What the CNA reads of a node-report status sent at `t_tx` (s): the report its predictor
/// takes and the AUV's covariance from the trailer (None: not decodable).
pub fn read_node_status(bytes: &[u8], t_tx: f64) -> Option<(StatusReport, ReportedCov)> {
    let (m, cov) = split_status(bytes).ok()?;
    let t = resolve_time(m.time_of_day, t_tx);
    let pos = Vec3::new(m.x, m.y, m.depth);
    let report = StatusReport { t, pos, speed: m.speed, heading: m.heading, waypoints: m.waypoints };
    Some((report, ReportedCov { t, cov: cov.to_cov() }))
}

/// Splits a received status into its node report and covariance trailer and decodes both.
fn split_status(bytes: &[u8]) -> Result<(NodeReport, CovarianceReport), DecodeError> {
    let split = bytes.len().saturating_sub(CovTrailer::BYTES);
    Ok((NodeReport::decode(&bytes[..split])?, CovTrailer::decode(&bytes[split..])?))
}

/// Resolves a time of day (s) to the absolute time nearest `t_now`.
fn resolve_time(time_of_day: u32, t_now: f64) -> f64 {
    let day = 86_400.0;
    let base = (t_now / day).floor() * day + time_of_day as f64;
    [base - day, base, base + day]
        .into_iter()
        .min_by(|a, b| (a - t_now).abs().total_cmp(&(b - t_now).abs()))
        .unwrap_or(base)
}
