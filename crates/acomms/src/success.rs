//! Packet success: the Nams Table 4 piecewise-linear curves of success likelihood against
//! transmission loss, an ambient-noise offset, and Table 5's partial-frame drops (Nams 2014, §4.3).
//!
//! Engine (reconstructed, docs/models.md#nams-success-model): the packet succeeds (≥ 1 frame) with probability
//! p_r(TL + N); a successful multi-frame packet is partial with the receiver type's Table 5
//! probability, losing a uniformly drawn number 1..n−1 of uniformly chosen frames.

use crate::rates::Rate;
use coopnav_core::validation::{CheckFields, Problems};
use rand::seq::index::sample;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// One Table 4 row: success `p_a` up to `tl_ab` dB, falling linearly to 0 at `tl_bc` dB.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SuccessCurve {
    pub p_a: f64,
    pub tl_ab: f64,
    pub tl_bc: f64,
}

impl SuccessCurve {
    pub fn p(&self, tl: f64) -> f64 {
        if tl <= self.tl_ab {
            self.p_a
        } else if tl >= self.tl_bc {
            0.0
        } else {
            self.p_a * (self.tl_bc - tl) / (self.tl_bc - self.tl_ab)
        }
    }
}

/// Which end of the link receives (Table 5 columns).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Receiver {
    Iver2,
    Barge,
}

/// What arrived of one packet: bit i set = frame i received. Zero = nothing received.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Reception {
    pub frames: u16,
    pub n_frames: u8,
}

impl Reception {
    pub fn received(&self) -> bool {
        self.frames != 0
    }
    pub fn frame0(&self) -> bool {
        self.frames & 1 == 1
    }
    pub fn count(&self) -> u32 {
        self.frames.count_ones()
    }
}

/// The success engine. Defaults are Tables 4 and 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SuccessModel {
    /// Curves for rates 0, 1, 4, 5 (rates 2 and 3 reuse 1 and 4).
    pub curves: [SuccessCurve; 4],
    /// Table 5 partial-drop probability for rates 1, 4, 5: [iver2, barge].
    pub partial: [[f64; 2]; 3],
    /// Extra ambient noise, dB, added to TL (reconstructed: docs/models.md#nams-success-model).
    pub noise_db: f64,
}

impl Default for SuccessModel {
    fn default() -> Self {
        let c = |p_a, tl_ab, tl_bc| SuccessCurve { p_a, tl_ab, tl_bc };
        SuccessModel {
            curves: [c(0.80, 50.0, 80.0), c(0.90, 50.0, 80.0), c(0.80, 40.0, 80.0), c(0.45, 40.0, 60.0)],
            partial: [[0.08, 0.38], [0.04, 0.32], [0.33, 0.38]],
            noise_db: 0.0,
        }
    }
}

impl CheckFields for SuccessModel {
    /// Probabilities in [0, 1], each curve's thresholds finite and in order, the noise ≥ 0 dB.
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        for (i, c) in self.curves.iter().enumerate() {
            let at = format!("{prefix}curves[{i}]");
            p.probability(&format!("{at}.p_a"), c.p_a);
            p.finite(&format!("{at}.tl_ab"), c.tl_ab);
            p.finite(&format!("{at}.tl_bc"), c.tl_bc);
            if c.tl_ab >= c.tl_bc {
                p.push(format!("{at}.tl_bc"), c.tl_bc.to_string(), format!("a loss above tl_ab = {} dB", c.tl_ab));
            }
        }
        for (i, row) in self.partial.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                p.probability(&format!("{prefix}partial[{i}][{j}]"), v);
            }
        }
        p.non_negative(&format!("{prefix}noise_db"), self.noise_db);
    }
}

impl SuccessModel {
    fn curve(&self, rate: Rate) -> &SuccessCurve {
        &self.curves[match rate.index() {
            0 => 0,
            1 | 2 => 1,
            3 | 4 => 2,
            _ => 3,
        }]
    }
    fn partial_p(&self, rate: Rate, rx: Receiver) -> f64 {
        let row = match rate.index() {
            0 => return 0.0,
            1 | 2 => 0,
            3 | 4 => 1,
            _ => 2,
        };
        self.partial[row][matches!(rx, Receiver::Barge) as usize]
    }

    /// Likelihood that a packet at `rate` gets at least one frame through `tl` dB (noise added).
    pub fn p_success(&self, rate: Rate, tl: f64) -> f64 {
        self.curve(rate).p(tl + self.noise_db)
    }

    /// Draws one reception.
    pub fn draw(&self, rate: Rate, tl: f64, rx: Receiver, rng: &mut impl Rng) -> Reception {
        let n = rate.spec().frames;
        let all = ((1u32 << n) - 1) as u16;
        let mut r = Reception { frames: 0, n_frames: n as u8 };
        if !rng.gen_bool(self.p_success(rate, tl).clamp(0.0, 1.0)) {
            return r;
        }
        r.frames = all;
        if n > 1 && rng.gen_bool(self.partial_p(rate, rx)) {
            let lost = rng.gen_range(1..n);
            for i in sample(rng, n, lost) {
                r.frames &= !(1u16 << i);
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::SeedStream;

    #[test]
    fn curves_are_table_4() {
        let m = SuccessModel::default();
        assert_eq!(m.p_success(Rate::R1, 30.0), 0.9);
        assert!((m.p_success(Rate::R1, 65.0) - 0.45).abs() < 1e-12);
        assert_eq!(m.p_success(Rate::R5, 60.0), 0.0);
        assert!((m.p_success(Rate::R4, 60.0) - 0.4).abs() < 1e-12);
        let noisy = SuccessModel { noise_db: 6.0, ..m.clone() };
        assert!((noisy.p_success(Rate::R0, 59.0) - m.p_success(Rate::R0, 65.0)).abs() < 1e-12);
        for r in Rate::usable() {
            let mut last = 1.0;
            for k in 0..100 {
                let p = m.p_success(r, k as f64);
                assert!(p <= last + 1e-15, "non-increasing in TL");
                last = p;
            }
        }
    }

    #[test]
    fn validation_names_the_field() {
        let fields = |m: &SuccessModel| {
            let mut p = Problems::new();
            m.check_fields("success.", &mut p);
            p.finish().err().map(|e| e.0.into_iter().map(|p| p.field).collect::<Vec<_>>()).unwrap_or_default()
        };
        assert!(fields(&SuccessModel::default()).is_empty());
        let mut m = SuccessModel::default();
        m.partial[1][0] = 1.5;
        assert_eq!(fields(&m), ["success.partial[1][0]"]);
        let mut m = SuccessModel::default();
        m.curves[2].tl_bc = 10.0;
        m.noise_db = -1.0;
        assert_eq!(fields(&m), ["success.curves[2].tl_bc", "success.noise_db"]);
    }

    #[test]
    fn draws_match_probabilities_and_partial_rates() {
        let m = SuccessModel::default();
        let mut rng = SeedStream::new(3).rng(0);
        let n = 40_000;
        let (mut ok, mut partial) = (0, 0);
        for _ in 0..n {
            let r = m.draw(Rate::R5, 30.0, Receiver::Iver2, &mut rng);
            assert!(r.frames < 256 && r.n_frames == 8);
            if r.received() {
                ok += 1;
                if r.count() < 8 {
                    partial += 1;
                    assert!(r.count() >= 1);
                }
            }
        }
        let p = ok as f64 / n as f64;
        assert!((p - 0.45).abs() < 4.0 * (0.45f64 * 0.55 / n as f64).sqrt(), "{p}");
        let q = partial as f64 / ok as f64;
        assert!((q - 0.33).abs() < 0.03, "{q}");
        let r0 = m.draw(Rate::R0, 100.0, Receiver::Iver2, &mut rng);
        assert!(!r0.received());
    }
}
