use coopnav_nav::cycle::Configuration;
use coopnav_sim::hbl::{monte_carlo, Scenario};
fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(50);
    for c in [Configuration::Msbl, Configuration::HblOne, Configuration::HblTwo] {
        let mut sc = Scenario::table5(c);
        let step: f64 = std::env::var("STEP").ok().map(|s| s.parse().unwrap()).unwrap_or(0.1);
        sc.filters.auv.step_s = step;
        if let Ok(g) = std::env::var("ST") { sc.filters.auv.range_noise.sigma_time = g.parse().unwrap(); }
        if let Ok(g) = std::env::var("NIS") { sc.filters.auv.range_gate.max_nis = Some(g.parse().unwrap()); }
        if let Ok(g) = std::env::var("RES") { sc.filters.auv.range_gate.max_abs_residual = Some(g.parse().unwrap()); } sc.filters.ship.step_s = step; sc.filters.buoy.step_s = step;
        let t = std::time::Instant::now();
        let r = monte_carlo(&sc, n, 1, &|_| {}).unwrap();
        let s = &r.summary;
        let mut v: Vec<(usize, f64, f64)> = r.runs.iter().enumerate().map(|(i, m)| (i, m.zone_error.unwrap(), m.zone_perpendicular.unwrap())).collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        eprintln!("worst {:?}", &v[..5]);
        eprintln!("{:8} zone {:.3}±{:.3} par {:.3} perp {:.3} buoy {:?} healthy {} upd {} pred {} {:?}", s.configuration, s.zone_error.mean, s.zone_error.sd, s.zone_parallel.mean, s.zone_perpendicular.mean, s.buoy_error.map(|b| b.mean), s.all_healthy, s.filter_updates, s.filter_predicts, t.elapsed());
    }
}
#[allow(dead_code)]
fn worst() {}
