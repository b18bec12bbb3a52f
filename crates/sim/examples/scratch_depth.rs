use coopnav_core::run_seed;
use coopnav_sim::closed_loop::PolicySpec;
use coopnav_sim::engine::{run, Faults, Observer};
use coopnav_sim::experiments::closed_loop::{setup, TUNING_SEED};
use coopnav_sim::experiments::{ReproOptions, Size};
use rayon::prelude::*;

/// Per AUV: sum distance, count, count within 1000 m; CNA x per quarter; error per quarter.
struct Obs {
    n: usize,
    dur: f64,
    dist: Vec<f64>,
    cnt: Vec<f64>,
    near: Vec<f64>,
    qx: [f64; 4],
    qc: [f64; 4],
    qe: [f64; 4],
    qn: [f64; 4],
}
impl Observer for Obs {
    fn on_sample(&mut self, t: f64, cna: coopnav_core::geometry::Vec3, rows: &[coopnav_sim::engine::TraceRow]) {
        let q = ((t / self.dur * 4.0) as usize).min(3);
        self.qx[q] += cna.z;
        self.qc[q] += 1.0;
        for r in rows {
            self.dist[r.auv] += r.distance;
            self.cnt[r.auv] += 1.0;
            if r.distance < 1000.0 {
                self.near[r.auv] += 1.0;
            }
            self.qe[q] += r.error;
            self.qn[q] += 1.0;
        }
        let _ = self.n;
    }
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let (runs, scen, n): (u64, &str, usize) = (a[0].parse().unwrap(), &a[1], a[2].parse().unwrap());
    let (settings, _, _) = setup(&ReproOptions { size: Size::Full, seed: TUNING_SEED + 1 }).unwrap();
    let s = settings.iter().find(|s| s.name == scen).unwrap();
    let sc = s.scenario(n, TUNING_SEED, None);
    for policy in a[3].split(',') {
        let spec = PolicySpec::new(policy, &sc).unwrap();
        let per: Vec<Vec<f64>> = (0..runs)
            .into_par_iter()
            .map(|i| {
                let mut p = spec.build(&sc).unwrap();
                let mut o = Obs {
                    n,
                    dur: sc.duration_s,
                    dist: vec![0.0; n],
                    cnt: vec![0.0; n],
                    near: vec![0.0; n],
                    qx: [0.0; 4],
                    qc: [0.0; 4],
                    qe: [0.0; 4],
                    qn: [0.0; 4],
                };
                let r = run(&sc, &mut p, run_seed(sc.seed, i), &Faults::default(), &mut o);
                let mut v: Vec<f64> = r.auvs.iter().map(|m| m.error.mean).collect();
                v.extend((0..n).map(|k| o.dist[k] / o.cnt[k]));
                v.extend((0..n).map(|k| o.near[k] / o.cnt[k]));
                v.extend((0..4).map(|q| o.qx[q] / o.qc[q]));
                v.extend((0..4).map(|q| o.qe[q] / o.qn[q]));
                v
            })
            .collect();
        let col = |k: usize| per.iter().map(|v| v[k]).sum::<f64>() / runs as f64;
        let f =
            |r: std::ops::Range<usize>, p: usize| r.map(|k| format!("{:6.*}", p, col(k))).collect::<Vec<_>>().join("");
        println!("{policy:18} err {}", f(0..n, 2));
        println!("{:18} dist{}", "", f(n..2 * n, 0));
        println!("{:18} <1km{}", "", f(2 * n..3 * n, 2));
        println!(
            "{:18} cna z by quarter {}   err by quarter {}",
            "",
            f(3 * n..3 * n + 4, 1),
            f(3 * n + 4..3 * n + 8, 2)
        );
    }
}
