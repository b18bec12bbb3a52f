use super::*;

#[test]
#[ignore]
fn explore() {
    let sc = Scenario::example();
    for name in POLICY_NAMES {
        let mut p = PolicySpec::new(name, &sc).unwrap().build(&sc).unwrap();
        let r = run(&sc, &mut p, 1, false, &Faults::default());
        eprintln!("{name:10} mean {:.2} rms {:.2} max {:.2} modelled {:?} healthy {} timing {:?} planner {:?}", r.fleet.error.mean, r.fleet.error.rms, r.fleet.error.max, r.fleet.modelled_mean, r.fleet.healthy, r.timing, r.planner);
        for a in &r.auvs { eprintln!("   {} {:?} down {:?} up {:?} dist {:.0}", a.name, a.error, a.downlink, a.uplink, a.distance_mean); }
    }
}
