use coopnav_nav::cycle::Configuration;
use coopnav_sim::hbl::{monte_carlo, Scenario};
fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(50);
    for c in [Configuration::Msbl, Configuration::HblOne, Configuration::HblTwo] {
        let sc = Scenario::table5(c);
        let t = std::time::Instant::now();
        let r = monte_carlo(&sc, n, 1, &|_| {}).unwrap();
        let s = &r.summary;
        eprintln!("{:8} zone {:.3}±{:.3} par {:.3} perp {:.3} buoy {:?} healthy {} upd {} pred {} {:?}", s.configuration, s.zone_error.mean, s.zone_error.sd, s.zone_parallel.mean, s.zone_perpendicular.mean, s.buoy_error.map(|b| b.mean), s.all_healthy, s.filter_updates, s.filter_predicts, t.elapsed());
    }
}
