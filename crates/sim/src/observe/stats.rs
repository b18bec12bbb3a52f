//! Across-run statistics shared by the Monte Carlo tools: mean, SD and standard error of a set
//! of runs, and the Welch 95 % confidence interval of a difference of two means (as Gill 2013,
//! §3.1.2 compares the cycles).

use serde::Serialize;

/// Mean, SD (n − 1) and standard error of the mean.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    pub n: usize,
    pub mean: f64,
    pub sd: f64,
    pub se: f64,
}

impl Stats {
    pub fn of(v: &[f64]) -> Stats {
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n.max(1) as f64;
        let var = if n > 1 { v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
        Stats { n, mean, sd: var.sqrt(), se: (var / n.max(1) as f64).sqrt() }
    }
}

/// 95 % Welch confidence interval of mean(a) − mean(b).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WelchCi {
    pub difference: f64,
    pub se: f64,
    pub df: f64,
    pub low: f64,
    pub high: f64,
}

pub fn welch_95(a: &Stats, b: &Stats) -> WelchCi {
    let (va, vb) = (a.sd.powi(2) / a.n as f64, b.sd.powi(2) / b.n as f64);
    let se = (va + vb).sqrt();
    let df = if se > 0.0 {
        (va + vb).powi(2) / (va.powi(2) / (a.n as f64 - 1.0) + vb.powi(2) / (b.n as f64 - 1.0))
    } else {
        f64::INFINITY
    };
    let t = t_975(df);
    let difference = a.mean - b.mean;
    WelchCi { difference, se, df, low: difference - t * se, high: difference + t * se }
}

/// 97.5 % quantile of Student's t with `df` degrees of freedom: Cornish–Fisher expansion about
/// the normal quantile (error < 1e-3 for df ≥ 4; the Monte Carlo df are in the hundreds).
pub fn t_975(df: f64) -> f64 {
    let z: f64 = 1.959_963_984_540_054;
    if !df.is_finite() {
        return z;
    }
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * df)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * df * df)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * df.powi(3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_reproduces_the_thesis_cycle_interval() {
        // Gill 2013, §3.1.2: 1.59 ± 0.95 vs 1.37 ± 0.76, n = 250 each → [0.07, 0.37].
        let long = Stats { n: 250, mean: 1.59, sd: 0.95, se: 0.95 / 250f64.sqrt() };
        let short = Stats { n: 250, mean: 1.37, sd: 0.76, se: 0.76 / 250f64.sqrt() };
        let ci = welch_95(&long, &short);
        assert!((ci.low - 0.069).abs() < 0.003 && (ci.high - 0.371).abs() < 0.003, "{ci:?}");
    }

    #[test]
    fn t_quantiles() {
        assert!((t_975(10.0) - 2.228).abs() < 0.005);
        assert!((t_975(30.0) - 2.042).abs() < 0.002);
        assert!((t_975(f64::INFINITY) - 1.96).abs() < 1e-3);
    }

    #[test]
    fn stats_basics() {
        let s = Stats::of(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - 1.2909944).abs() < 1e-6);
        assert!((s.se - s.sd / 2.0).abs() < 1e-12);
    }
}
