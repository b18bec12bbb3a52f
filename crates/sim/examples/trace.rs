use coopnav_core::run_seed;
use coopnav_nav::cycle::Configuration;
use coopnav_sim::hbl::{run, Scenario};
fn main() {
    let i: u64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let sc = Scenario::table5(Configuration::HblTwo);
    let (m, tr) = run(&sc, &sc.resolved_cycle().unwrap(), run_seed(1, i), true);
    eprintln!("{m:?}");
    for r in tr.unwrap().rows.iter().step_by(20) {
        eprintln!("t {:6.1} xrel {:7.1} auv ({:7.1},{:6.1}) est ({:7.1},{:6.1}) ship ({:6.1},{:5.1}) est ({:6.1},{:5.1}) buoy {:?} {:?} err {:.2}", r.t, r.x_rel, r.auv_true[0], r.auv_true[1], r.auv_est[0], r.auv_est[1], r.ship_true[0], r.ship_true[1], r.ship_est[0], r.ship_est[1], r.buoy_true.map(|b| [b[0].round(), b[1].round()]), r.buoy_est.map(|b| [b[0].round(), b[1].round()]), r.error);
    }
}
