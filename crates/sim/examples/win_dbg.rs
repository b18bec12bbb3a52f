use coopnav_sim::closed_loop::{run, Faults, PolicySpec};
use coopnav_sim::experiments::closed_loop::{setup, TUNING_SEED};
use coopnav_sim::experiments::{ReproOptions, Size};
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (settings, _, _) = setup(&ReproOptions { size: Size::Full, seed: 1 }).unwrap();
    let s = settings.iter().find(|s| s.name == args[0]).unwrap();
    let sc = s.scenario(args[1].parse().unwrap(), TUNING_SEED, Some(args[2].parse().unwrap()));
    let mut p = PolicySpec::new(&args[3], &sc).unwrap().build(&sc).unwrap();
    let r = run(&sc, &mut p, coopnav_core::run_seed(TUNING_SEED, 0), &Faults::default(), &mut ());
    println!("{:?}", r.planner);
    for a in &r.auvs {
        println!("{:?}", a);
    }
}
