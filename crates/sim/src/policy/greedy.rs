//! The greedy one-step Fisher-information baseline (the approach of open
//! USV–AUV cooperative-localisation work): every τ the CNA goes to the reachable point whose next
//! ping adds the most range information to the fleet, with no look-ahead and no model of the
//! filters' covariances.
//!
//! Per AUV k the information of a ping from p is J = p_s(r)·hhᵀ/R(r), h the horizontal part of
//! the unit line of sight (as the EKF's range Jacobian), p_s the link's success probability and R
//! the range noise. A single range is rank one, so the score joins it with the information of
//! the previous ping the CNA sent that AUV, and a weak prior keeps the determinant defined:
//! score = Σ_k ln det(J_prev,k + J_k + I/σ_prior²). The point maximising it is chosen among the
//! current position and `candidates` points one τ of travel away (`[policy.greedy-fisher]`, with
//! σ_prior; both invented, docs/models.md#baselines).

use super::{CnaCommand, CnaPolicy, PolicyContext};
use coopnav_core::Vec3;
use coopnav_plan::{LinkTable, RangeNoise};

/// Greedy one-step Fisher-information placement.
#[derive(Debug, Clone)]
pub struct GreedyFisher {
    link: LinkTable,
    noise: RangeNoise,
    /// Information [J_ee, J_en, J_nn] of the previous ping, per AUV.
    previous: Vec<[f64; 3]>,
    /// Reachable points tried per decision, evenly spread in heading.
    candidates: usize,
    /// σ_prior, m: the prior that keeps a rank-one information matrix invertible.
    sigma_prior_m: f64,
}

impl GreedyFisher {
    pub fn new(n_auvs: usize, link: LinkTable, noise: RangeNoise, candidates: usize, sigma_prior_m: f64) -> Self {
        GreedyFisher { link, noise, previous: vec![[0.0; 3]; n_auvs], candidates, sigma_prior_m }
    }

    /// Expected information of one ping from `cna` to the AUV at `auv`.
    fn information(&self, cna: &Vec3, auv: &Vec3) -> [f64; 3] {
        let d = auv - cna;
        let r = d.norm();
        if r < 1e-9 {
            return [0.0; 3];
        }
        let (h0, h1) = (d.x / r, d.y / r);
        let w = self.link.success(r) / self.noise.variance(r);
        [w * h0 * h0, w * h0 * h1, w * h1 * h1]
    }

    fn score(&self, cna: &Vec3, auvs: &[(usize, Vec3)]) -> f64 {
        let prior = 1.0 / (self.sigma_prior_m * self.sigma_prior_m);
        auvs.iter()
            .map(|(k, p)| {
                let [a, b, c] = self.information(cna, p);
                let [pa, pb, pc] = self.previous[*k];
                let (a, b, c) = (a + pa + prior, b + pb, c + pc + prior);
                (a * c - b * b).max(f64::MIN_POSITIVE).ln()
            })
            .sum()
    }
}

impl CnaPolicy for GreedyFisher {
    fn name(&self) -> &'static str {
        "greedy-fisher"
    }

    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let here = ctx.cna.pos;
        // This period's ping is sent from here now: it becomes each known AUV's previous ping.
        for k in 0..self.previous.len() {
            if let Some(p) = ctx.fleet.position(k, ctx.t) {
                self.previous[k] = self.information(&here, &p);
            }
        }
        let t_next = ctx.t + ctx.tau;
        let auvs: Vec<(usize, Vec3)> =
            (0..self.previous.len()).filter_map(|k| ctx.fleet.position(k, t_next).map(|p| (k, p))).collect();
        if auvs.is_empty() {
            return CnaCommand::Hold;
        }
        let step = ctx.speed * ctx.tau;
        let ring = (0..self.candidates).map(|i| {
            let a = std::f64::consts::TAU * i as f64 / self.candidates as f64;
            Vec3::new(here.x + step * a.cos(), here.y + step * a.sin(), here.z)
        });
        let mut best = (self.score(&here, &auvs), here);
        for p in ring {
            let s = self.score(&p, &auvs);
            // Strictly better only: ties keep the earlier candidate (staying first).
            if s > best.0 {
                best = (s, p);
            }
        }
        CnaCommand::GoTo(best.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::Heading;
    use coopnav_plan::{CnaPose, FnForecast};

    fn ctx<'a>(cna: (f64, f64), fleet: &'a FnForecast<impl Fn(usize, f64) -> Option<Vec3>>) -> PolicyContext<'a> {
        PolicyContext {
            t: 0.0,
            tau: 30.0,
            cna: CnaPose { pos: Vec3::new(cna.0, cna.1, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 },
            speed: 2.0,
            fleet,
            reported: &[],
            cna_variance: 1.0,
        }
    }

    #[test]
    fn it_moves_to_turn_the_line_of_sight_after_a_ping_along_it() {
        // One still AUV 300 m east: the ping sent now is along x, so the next one should come
        // from a point that turns the line of sight (north or south), not from further along x.
        let fleet = FnForecast { n: 1, f: |_: usize, _: f64| Some(Vec3::new(300.0, 0.0, 20.0)) };
        let mut g = GreedyFisher::new(1, LinkTable::perfect(), RangeNoise::default(), 16, 100.0);
        let CnaCommand::GoTo(p) = g.decide(&ctx((0.0, 0.0), &fleet)) else { panic!("expected a target") };
        assert!(p.y.abs() > 50.0, "{p:?}");
        assert!((p.x.hypot(p.y) - 60.0).abs() < 1e-9);
    }

    #[test]
    fn a_ping_carries_information_and_nothing_known_holds() {
        let g = GreedyFisher::new(1, LinkTable::perfect(), RangeNoise::default(), 16, 100.0);
        assert!(g.information(&Vec3::zeros(), &Vec3::new(100.0, 0.0, 0.0))[0] > 0.0);
        let none = FnForecast { n: 1, f: |_: usize, _: f64| None };
        let mut g = GreedyFisher::new(1, LinkTable::perfect(), RangeNoise::default(), 16, 100.0);
        assert_eq!(g.decide(&ctx((0.0, 0.0), &none)), CnaCommand::Hold);
    }
}
