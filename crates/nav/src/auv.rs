//! The survey AUV's EKF (digest §3.2): the thesis's 5 states [E, N, S, ψ, b] (`AuvEkf`, the
//! default), or 7 with a water current [.., c_E, c_N] (`AuvEkf<7>`, field logs); heading-rate
//! input, speed and compass updates, and OWTT range updates from *any* transponder whose position
//! at transmit time the caller supplies (ship outrigger, buoy, or a CNA that carries its position
//! in its message), optionally with that position's own uncertainty.
//!
//! ψ is the direction the vehicle moves through the water and b the compass's offset from it, so
//! b is the heading-bias (crab-angle) state: a vehicle that crabs 8° needs a prior `p0[4]` wide
//! enough to reach 8°. Headings inside are math convention (0 = east, counter-clockwise), so E
//! advances with cos ψ and N with sin ψ; the thesis writes the same model clockwise from north.

use crate::ekf::{propagate_covariance, wrap_angle, Ekf, Gate, SparseRows, UpdateOutcome};
use crate::range::{RangeMeasurement, RangeNoise};
use coopnav_core::validation::{CheckFields, InvalidFields, Problems};
use coopnav_core::Vec3;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

pub type AuvState = SVector<f64, 5>;
pub const E: usize = 0;
pub const N: usize = 1;
pub const S: usize = 2;
pub const PSI: usize = 3;
pub const BIAS: usize = 4;
/// Water current east and north (m/s), in the 7-state filter only.
pub const CURRENT_E: usize = 5;
pub const CURRENT_N: usize = 6;

/// The current states of the 7-state filter: a random walk (constant when `q` = 0). Invented
/// parameters (the thesis has no current state, digest §3.2; issue 12 field logs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurrentParams {
    /// Initial variance of each current component ((m/s)²); default (0.3 m/s)².
    pub p0: f64,
    /// Per-step process noise of each component ((m/s)² per `step_s`); default (0.3 m/s per hour)².
    pub q: f64,
}

impl Default for CurrentParams {
    fn default() -> Self {
        CurrentParams { p0: 0.09, q: 0.09 / 36_000.0 }
    }
}

impl CheckFields for CurrentParams {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.positive(&format!("{prefix}p0"), self.p0);
        p.non_negative(&format!("{prefix}q"), self.q);
    }
}

/// The AUV filter's state vector: `{ kind = "thesis" }` (5 states) or `{ kind = "current", p0, q }`
/// (7, with a water current).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AuvModel {
    /// [E, N, S, ψ, b]: the thesis's filter (digest §3.2).
    #[default]
    Thesis,
    /// [E, N, S, ψ, b, c_E, c_N]: with a water current (issue 12, field logs).
    Current(CurrentParams),
}

impl CheckFields for AuvModel {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        if let AuvModel::Current(c) = self {
            c.check_fields(prefix, p);
        }
    }
}

/// Coefficients of the AUV filter. Variances are per *nominal step* `step_s` (digest §3.1: Q is
/// added once per predict); a prediction over h seconds adds Q·h/step_s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuvParams {
    /// Nominal filter step Δt (s) the Q values refer to. Reconstructed: digest §10 A1 (0.1 s).
    pub step_s: f64,
    /// Initial variances [E m², N m², S (m/s)², ψ rad², b rad²]. Reconstructed: digest §10 A2.
    pub p0: [f64; 5],
    /// Per-step process noise. Q_E = Q_N = 0.255448 is Table 3; S, ψ, b: digest §10 A2.
    pub q: [f64; 5],
    /// Speed-measurement SD (m/s). Digest §10 A2.
    pub sigma_speed: f64,
    /// Compass SD (rad). Digest §10 A2 (0.5°).
    pub sigma_heading: f64,
    pub range_noise: RangeNoise,
    pub range_gate: Gate,
}

impl Default for AuvParams {
    fn default() -> Self {
        let deg = std::f64::consts::PI / 180.0;
        AuvParams {
            step_s: 0.1,
            p0: [16.0, 16.0, 0.0025, 0.01, (0.5 * deg).powi(2)],
            q: [0.255448, 0.255448, 1e-4, (0.2 * deg).powi(2), (0.01 * deg).powi(2)],
            sigma_speed: 0.05,
            sigma_heading: 0.5 * deg,
            range_noise: RangeNoise::default(),
            range_gate: Gate::OFF,
        }
    }
}

/// Bad filter coefficients: every bad field, named with its prefix.
pub type ParamError = InvalidFields;

/// Checks every coefficient; each problem names the field (prefixed by `prefix`).
impl CheckFields for AuvParams {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.positive(&format!("{prefix}step_s"), self.step_s);
        for (i, v) in self.p0.iter().enumerate() {
            p.positive(&format!("{prefix}p0[{i}]"), *v);
        }
        for (i, v) in self.q.iter().enumerate() {
            p.non_negative(&format!("{prefix}q[{i}]"), *v);
        }
        p.positive(&format!("{prefix}sigma_speed"), self.sigma_speed);
        p.positive(&format!("{prefix}sigma_heading"), self.sigma_heading);
        self.range_noise.check_fields(&format!("{prefix}range_noise."), p);
        self.range_gate.check_fields(&format!("{prefix}range_gate."), p);
    }
}

/// Dead reckoning over `h` seconds with the heading changing by `turn` rad (eq. 7, Euler step),
/// plus the drift of the current states when there are 7: the mean map the EKF linearises and the
/// unscented smoother pushes sigma points through.
pub fn transition<const M: usize>(x: &SVector<f64, M>, h: f64, turn: f64) -> SVector<f64, M> {
    transition_at(x, h, turn, x[PSI].sin_cos())
}

/// [`transition`] with (sin ψ, cos ψ) of `x` already computed (the filter's step shares them
/// with its Jacobian).
fn transition_at<const M: usize>(x: &SVector<f64, M>, h: f64, turn: f64, (sin, cos): (f64, f64)) -> SVector<f64, M> {
    let mut next = *x;
    next[E] += h * x[S] * cos;
    next[N] += h * x[S] * sin;
    if M > CURRENT_N {
        next[E] += h * x[CURRENT_E];
        next[N] += h * x[CURRENT_N];
    }
    next[PSI] = wrap_angle(x[PSI] + turn);
    next
}

/// ∂transition/∂x at `x` (digest §3.2, F^A).
pub fn transition_jacobian<const M: usize>(x: &SVector<f64, M>, h: f64) -> SMatrix<f64, M, M> {
    let mut f = SMatrix::<f64, M, M>::identity();
    for (i, entries) in transition_jacobian_entries(x, h, x[PSI].sin_cos()) {
        entries.iter().for_each(|&(j, v)| f[(i, j)] += v);
    }
    f
}

/// The non-identity entries of [`transition_jacobian`], by row: E and N, each with its entries
/// (column, value) at S and ψ, and at its current state when there are 7 (zero-valued at itself
/// when `M` = 5, so the rows have one length); (sin ψ, cos ψ) of `x` given.
fn transition_jacobian_entries<const M: usize>(
    x: &SVector<f64, M>,
    h: f64,
    (sin, cos): (f64, f64),
) -> SparseRows<2, 3> {
    let drift = if M > CURRENT_N { h } else { 0.0 };
    let (ce, cn) = if M > CURRENT_N { (CURRENT_E, CURRENT_N) } else { (E, N) };
    [(E, [(S, h * cos), (PSI, -h * x[S] * sin), (ce, drift)]), (N, [(S, h * sin), (PSI, h * x[S] * cos), (cn, drift)])]
}

/// The frame of a logged velocity over ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityFrame {
    /// (forward, starboard) in the vehicle's frame.
    Body,
    /// (east, north).
    Earth,
}

/// A range update's outcome with its innovation (m) and innovation variance S (m²), the terms
/// of the innovation likelihood.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeUpdate {
    pub outcome: UpdateOutcome,
    pub innovation: f64,
    pub variance: f64,
}

/// The AUV navigation filter with `M` = 5 (thesis) or 7 (with current) states.
#[derive(Debug, Clone)]
pub struct AuvEkf<const M: usize = 5> {
    ekf: Ekf<M>,
    params: AuvParams,
    /// Per-step process noise of the states after the thesis's five (none when `M` = 5).
    extra_q: f64,
}

impl AuvEkf<5> {
    /// Starts at time `t0` from position (e, n), speed, math heading ψ and zero compass bias.
    pub fn new(t0: f64, e: f64, n: f64, speed: f64, psi: f64, params: AuvParams) -> Self {
        let x0 = AuvState::from([e, n, speed, psi, 0.0]);
        let p0 = SMatrix::<f64, 5, 5>::from_diagonal(&SVector::from(params.p0));
        AuvEkf { ekf: Ekf::new(t0, x0, p0, [false, false, false, true, true]), params, extra_q: 0.0 }
    }
}

impl AuvEkf<7> {
    /// The 7-state filter: as [`AuvEkf::new`], with zero current of prior variance `current.p0`.
    pub fn with_current(
        t0: f64,
        e: f64,
        n: f64,
        speed: f64,
        psi: f64,
        params: AuvParams,
        current: CurrentParams,
    ) -> Self {
        let x0 = SVector::<f64, 7>::from([e, n, speed, psi, 0.0, 0.0, 0.0]);
        let [pe, pn, ps, ppsi, pb] = params.p0;
        let p0 = SMatrix::<f64, 7, 7>::from_diagonal(&SVector::from([pe, pn, ps, ppsi, pb, current.p0, current.p0]));
        let angles = [false, false, false, true, true, false, false];
        AuvEkf { ekf: Ekf::new(t0, x0, p0, angles), params, extra_q: current.q }
    }
}

impl<const M: usize> AuvEkf<M> {
    pub fn ekf(&self) -> &Ekf<M> {
        &self.ekf
    }
    pub fn ekf_mut(&mut self) -> &mut Ekf<M> {
        &mut self.ekf
    }
    pub fn params(&self) -> &AuvParams {
        &self.params
    }
    pub fn state(&self) -> &SVector<f64, M> {
        self.ekf.x()
    }
    pub fn position(&self) -> (f64, f64) {
        (self.ekf.x()[E], self.ekf.x()[N])
    }

    /// Dead-reckons to time `t` with the measured heading rate `yaw_rate` (rad/s, math sense)
    /// held over the interval (eq. 7). Does nothing if `t` is not after the filter time.
    pub fn predict_to(&mut self, t: f64, yaw_rate: f64) -> bool {
        let h = t - self.ekf.t();
        if !(h > 0.0) {
            return false;
        }
        let x = *self.ekf.x();
        let sin_cos = x[PSI].sin_cos();
        let x_new = transition_at(&x, h, h * yaw_rate, sin_cos);
        let q = self.step_q(h);
        self.ekf.predict_sparse(t, x_new, &transition_jacobian_entries(&x, h, sin_cos), &q)
    }

    /// The prediction from `x` over `h` seconds at heading rate `yaw_rate`: the propagated mean,
    /// the Jacobian F and the process noise Q, as the forward pass uses them (its covariance step
    /// is [`Self::prior_covariance`]).
    pub fn prediction(
        &self,
        x: &SVector<f64, M>,
        h: f64,
        yaw_rate: f64,
    ) -> (SVector<f64, M>, SMatrix<f64, M, M>, SMatrix<f64, M, M>) {
        let q = SMatrix::<f64, M, M>::from_diagonal(&self.step_q(h));
        (transition(x, h, h * yaw_rate), transition_jacobian(x, h), q)
    }

    /// The prior covariance of the step from the filtered (`x`, `p`) over `h` seconds: the same
    /// sparse arithmetic as [`Self::predict_to`], so a smoother that stores only filtered states
    /// recomputes each prior bit for bit.
    pub fn prior_covariance(&self, x: &SVector<f64, M>, p: &SMatrix<f64, M, M>, h: f64) -> SMatrix<f64, M, M> {
        let mut p = *p;
        propagate_covariance(&mut p, &transition_jacobian_entries(x, h, x[PSI].sin_cos()), &self.step_q(h));
        p
    }

    /// The process noise of an `h`-second step, per state (Q is given per nominal step).
    fn step_q(&self, h: f64) -> SVector<f64, M> {
        let scale = h / self.params.step_s;
        SVector::<f64, M>::from_fn(|i, _| self.params.q.get(i).copied().unwrap_or(self.extra_q) * scale)
    }

    /// Speed-sensor update (m/s).
    pub fn update_speed(&mut self, measured: f64) -> UpdateOutcome {
        self.update_speed_sd(measured, self.params.sigma_speed)
    }

    /// Speed update with its own SD (m/s), e.g. from a log row.
    pub fn update_speed_sd(&mut self, measured: f64, sd: f64) -> UpdateOutcome {
        let y = measured - self.ekf.x()[S];
        self.ekf.update_units(y, [S], sd.powi(2), &Gate::OFF)
    }

    /// Compass update: the compass reads ψ + b (math convention, rad).
    pub fn update_heading(&mut self, measured: f64) -> UpdateOutcome {
        self.update_heading_sd(measured, self.params.sigma_heading)
    }

    /// Compass update with its own SD (rad).
    pub fn update_heading_sd(&mut self, measured: f64, sd: f64) -> UpdateOutcome {
        let y = wrap_angle(measured - self.ekf.x()[PSI] - self.ekf.x()[BIAS]);
        self.ekf.update_units(y, [PSI, BIAS], sd.powi(2), &Gate::OFF)
    }

    /// Position fix of the vehicle itself (GPS at the surface), SD `sd` m on each axis.
    pub fn update_position(&mut self, e: f64, n: f64, sd: f64) -> UpdateOutcome {
        let mut h = SMatrix::<f64, 2, M>::zeros();
        h[(0, E)] = 1.0;
        h[(1, N)] = 1.0;
        let x = self.ekf.x();
        let y = nalgebra::Vector2::new(e - x[E], n - x[N]);
        self.ekf.update(y, h, nalgebra::Matrix2::identity() * (sd * sd), &Gate::OFF)
    }

    /// Velocity over ground (a DVL in bottom lock), SD `sd` m/s per component. Over ground the
    /// vehicle moves at S(cos ψ, sin ψ) through the water plus the current (7 states); the body
    /// frame turns that by the compass heading θ = ψ + b: forward = v·(cos θ, sin θ), starboard =
    /// v·(sin θ, −cos θ) (math convention, starboard is to the right).
    pub fn update_velocity(&mut self, frame: VelocityFrame, measured: [f64; 2], sd: f64) -> UpdateOutcome {
        let x = self.ekf.x();
        let (sin, cos) = x[PSI].sin_cos();
        // Earth-frame velocity and its Jacobian rows.
        let mut ve = x[S] * cos;
        let mut vn = x[S] * sin;
        let (mut je, mut jn) = (SMatrix::<f64, 1, M>::zeros(), SMatrix::<f64, 1, M>::zeros());
        (je[S], je[PSI], jn[S], jn[PSI]) = (cos, -x[S] * sin, sin, x[S] * cos);
        if M > CURRENT_N {
            ve += x[CURRENT_E];
            vn += x[CURRENT_N];
            (je[CURRENT_E], jn[CURRENT_N]) = (1.0, 1.0);
        }
        let (predicted, h) = match frame {
            VelocityFrame::Earth => ([ve, vn], [je, jn]),
            VelocityFrame::Body => {
                let (st, ct) = (x[PSI] + x[BIAS]).sin_cos();
                let (fwd, stbd) = (ve * ct + vn * st, ve * st - vn * ct);
                let (mut jf, mut js) = (je * ct + jn * st, je * st - jn * ct);
                // Both rotate with θ = ψ + b.
                for i in [PSI, BIAS] {
                    jf[i] += -ve * st + vn * ct;
                    js[i] += ve * ct + vn * st;
                }
                ([fwd, stbd], [jf, js])
            }
        };
        let mut hm = SMatrix::<f64, 2, M>::zeros();
        hm.set_row(0, &h[0]);
        hm.set_row(1, &h[1]);
        let y = nalgebra::Vector2::new(measured[0] - predicted[0], measured[1] - predicted[1]);
        self.ekf.update(y, hm, nalgebra::Matrix2::identity() * (sd * sd), &Gate::OFF)
    }

    /// OWTT range update (eq. 9). `auv_depth` = Some(z) uses the 3-D slant range to the
    /// transponder's depth (field mode); None the horizontal range (simulation mode, digest A4).
    pub fn update_range(&mut self, m: &RangeMeasurement, auv_depth: Option<f64>) -> UpdateOutcome {
        self.update_range_from_uncertain(m, auv_depth, 0.0)
    }

    /// As [`Self::update_range`], with the transponder's horizontal position uncertain by
    /// `transponder_sd` (m, each axis): its variance along the line of sight is added to the range
    /// noise (the position error projects onto the range through the same unit vector).
    pub fn update_range_from_uncertain(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        transponder_sd: f64,
    ) -> UpdateOutcome {
        let range_variance = self.params.range_noise.variance(m.travel_time);
        let gate = self.params.range_gate;
        self.update_range_with(m, auv_depth, range_variance, transponder_sd, &gate).outcome
    }

    /// The range update with the range variance (m²), the transponder's horizontal SD (m, each
    /// axis) and the gate given by the caller (a log row with its own σ, a tuned noise).
    pub fn update_range_with(
        &mut self,
        m: &RangeMeasurement,
        auv_depth: Option<f64>,
        range_variance: f64,
        transponder_sd: f64,
        gate: &Gate,
    ) -> RangeUpdate {
        let Some((predicted, h)) = self.range_jacobian(&m.transponder, auv_depth) else {
            return RangeUpdate { outcome: UpdateOutcome::Unusable, innovation: f64::NAN, variance: f64::NAN };
        };
        let mut r = range_variance;
        if transponder_sd > 0.0 {
            r += transponder_sd.powi(2) * (h[E] * h[E] + h[N] * h[N]);
        }
        let innovation = m.range - predicted;
        let variance = (h * self.ekf.p() * h.transpose())[(0, 0)] + r;
        RangeUpdate { outcome: self.ekf.update_scalar(innovation, h, r, gate), innovation, variance }
    }

    /// The predicted range to a transponder and its Jacobian row; None directly overhead in 2-D,
    /// where the range has no gradient (no information, no update).
    pub fn range_jacobian(&self, transponder: &Vec3, auv_depth: Option<f64>) -> Option<(f64, SMatrix<f64, 1, M>)> {
        let x = self.ekf.x();
        let de = x[E] - transponder.x;
        let dn = x[N] - transponder.y;
        let dz = auv_depth.map_or(0.0, |z| z - transponder.z);
        let predicted = (de * de + dn * dn + dz * dz).sqrt();
        if !(predicted > 1e-6) {
            return None;
        }
        let mut h = SMatrix::<f64, 1, M>::zeros();
        h[E] = de / predicted;
        h[N] = dn / predicted;
        Some((predicted, h))
    }

    /// Predicted range from the current estimate to a transponder (for residual bookkeeping).
    pub fn predicted_range(&self, transponder: &Vec3, auv_depth: Option<f64>) -> f64 {
        let x = self.ekf.x();
        let dz = auv_depth.map_or(0.0, |z| z - transponder.z);
        ((x[E] - transponder.x).powi(2) + (x[N] - transponder.y).powi(2) + dz * dz).sqrt()
    }
}

/// An AUV filter of either state vector, chosen at run time by an [`AuvModel`]: what a
/// simulator holds for each vehicle. The engine reads the navigation states (E, N, S, ψ), the
/// horizontal covariance block and the current estimate, whichever the model.
#[derive(Debug, Clone)]
pub enum AuvFilter {
    Thesis(AuvEkf<5>),
    Current(AuvEkf<7>),
}

/// Calls `$body` with `$f` bound to the filter, whichever its state vector.
macro_rules! each_model {
    ($self:expr, $f:ident => $body:expr) => {
        match $self {
            AuvFilter::Thesis($f) => $body,
            AuvFilter::Current($f) => $body,
        }
    };
}

impl AuvFilter {
    /// As [`AuvEkf::new`], with the state vector of `model`.
    pub fn new(model: &AuvModel, t0: f64, e: f64, n: f64, speed: f64, psi: f64, params: AuvParams) -> Self {
        match model {
            AuvModel::Thesis => AuvFilter::Thesis(AuvEkf::new(t0, e, n, speed, psi, params)),
            AuvModel::Current(c) => AuvFilter::Current(AuvEkf::with_current(t0, e, n, speed, psi, params, *c)),
        }
    }

    pub fn position(&self) -> (f64, f64) {
        each_model!(self, f => f.position())
    }
    /// Estimated speed through the water (m/s) and math heading ψ (rad).
    pub fn speed_heading(&self) -> (f64, f64) {
        each_model!(self, f => (f.state()[S], f.state()[PSI]))
    }
    /// Estimated water current (east, north) m/s: zero for the thesis model.
    pub fn current(&self) -> (f64, f64) {
        match self {
            AuvFilter::Thesis(_) => (0.0, 0.0),
            AuvFilter::Current(f) => (f.state()[CURRENT_E], f.state()[CURRENT_N]),
        }
    }
    /// The horizontal covariance block [P_EE, P_EN, P_NN].
    pub fn position_cov(&self) -> [f64; 3] {
        each_model!(self, f => {
            let p = f.ekf().p();
            [p[(E, E)], p[(E, N)], p[(N, N)]]
        })
    }
    pub fn is_finite(&self) -> bool {
        each_model!(self, f => f.state().iter().chain(f.ekf().p().iter()).all(|v| v.is_finite()))
    }
    pub fn predict_to(&mut self, t: f64, yaw_rate: f64) -> bool {
        each_model!(self, f => f.predict_to(t, yaw_rate))
    }
    pub fn update_speed(&mut self, measured: f64) -> UpdateOutcome {
        each_model!(self, f => f.update_speed(measured))
    }
    pub fn update_heading(&mut self, measured: f64) -> UpdateOutcome {
        each_model!(self, f => f.update_heading(measured))
    }
    pub fn update_range(&mut self, m: &RangeMeasurement, auv_depth: Option<f64>) -> UpdateOutcome {
        each_model!(self, f => f.update_range(m, auv_depth))
    }
    /// A horizontal position fix (e, n) with σ `sd` per axis (GPS at the surface): two scalar
    /// updates, exact for the diagonal noise.
    pub fn update_position_fix(&mut self, fix: (f64, f64), sd: f64) -> [UpdateOutcome; 2] {
        each_model!(self, f => [
            f.update_axis(E, fix.0, sd * sd),
            f.update_axis(N, fix.1, sd * sd),
        ])
    }
}

impl<const M: usize> AuvEkf<M> {
    /// A direct measurement of state `i` with variance `r`.
    fn update_axis(&mut self, i: usize, measured: f64, r: f64) -> UpdateOutcome {
        let y = measured - self.ekf.x()[i];
        self.ekf.update_units(y, [i], r, &Gate::OFF)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::is_positive_definite;
    use coopnav_core::wrap_pi;

    fn meas(range: f64, at: Vec3) -> RangeMeasurement {
        RangeMeasurement { range, travel_time: range / 1500.0, transponder: at }
    }

    #[test]
    fn dead_reckoning_follows_heading_and_rate() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 1.0, 0.0, AuvParams::default());
        for k in 1..=10 {
            f.predict_to(k as f64 * 0.1, 0.0);
        }
        assert!((f.position().0 - 1.0).abs() < 1e-12 && f.position().1.abs() < 1e-12);
        f.predict_to(2.0, std::f64::consts::FRAC_PI_2 / 1.0);
        assert!(f.state()[PSI] > 1.0, "heading integrates the rate input");
    }

    #[test]
    fn range_update_pulls_towards_the_measured_circle() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams::default());
        let out = f.update_range(&meas(95.0, Vec3::new(100.0, 0.0, 0.0)), None);
        assert!(out.applied());
        assert!(f.position().0 > 3.0, "moved towards the transponder: {:?}", f.position());
        assert!(f.position().1.abs() < 1e-9, "no information across the line of sight");
        assert!(f.ekf().p()[(E, E)] < 16.0 && (f.ekf().p()[(N, N)] - 16.0).abs() < 1e-9);
    }

    #[test]
    fn transponder_uncertainty_adds_its_line_of_sight_variance() {
        // Line of sight along E: the posterior E variance is P·R/(P + R) with R = σ_r² + σ_b².
        let at = Vec3::new(100.0, 0.0, 0.0);
        let r0 = AuvParams::default().range_noise.variance(95.0 / 1500.0);
        for sd in [0.0, 3.0] {
            let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, 0.0, AuvParams::default());
            assert!(f.update_range_from_uncertain(&meas(95.0, at), None, sd).applied());
            let r = r0 + sd * sd;
            assert!((f.ekf().p()[(E, E)] - 16.0 * r / (16.0 + r)).abs() < 1e-9, "sd {sd}: {}", f.ekf().p()[(E, E)]);
        }
    }

    #[test]
    fn current_states_carry_the_vehicle_and_start_still() {
        let mut f = AuvEkf::with_current(0.0, 0.0, 0.0, 1.0, 0.0, AuvParams::default(), CurrentParams::default());
        f.ekf_mut().predict(
            1.0,
            SVector::from([0.0, 0.0, 1.0, 0.0, 0.0, 0.2, -0.1]),
            SMatrix::identity(),
            SMatrix::zeros(),
        );
        f.predict_to(11.0, 0.0);
        // 10 s at 1 m/s east through the water plus (0.2, −0.1) m/s of current.
        assert!((f.position().0 - 12.0).abs() < 1e-9 && (f.position().1 + 1.0).abs() < 1e-9, "{:?}", f.position());
        assert!(f.ekf().p()[(E, CURRENT_E)] > 0.0, "position and current are correlated by the drift");
    }

    #[test]
    fn overhead_transponder_is_harmless() {
        let mut f = AuvEkf::new(0.0, 5.0, 5.0, 0.0, 0.0, AuvParams::default());
        assert_eq!(f.update_range(&meas(0.0, Vec3::new(5.0, 5.0, 1.5)), None), UpdateOutcome::Unusable);
        let out = f.update_range(&meas(8.5, Vec3::new(5.0, 5.0, 1.5)), Some(10.0));
        assert!(out.applied());
        assert!(f.state().iter().all(|v| v.is_finite()));
        assert!(is_positive_definite(f.ekf().p()));
    }

    #[test]
    fn compass_update_splits_heading_and_bias_and_wraps() {
        let mut f = AuvEkf::new(0.0, 0.0, 0.0, 0.0, std::f64::consts::PI - 0.01, AuvParams::default());
        f.update_heading(-std::f64::consts::PI + 0.01);
        // The innovation is +0.02 rad across the ±π seam, not −6.26.
        let est = f.state()[PSI] + f.state()[BIAS];
        assert!(wrap_pi(est - (std::f64::consts::PI - 0.01)) > 0.0);
        assert!(wrap_pi(est - (std::f64::consts::PI - 0.01)) < 0.021);
    }

    #[test]
    fn bad_params_name_the_field() {
        let mut p = AuvParams::default();
        p.q[2] = -1.0;
        p.sigma_speed = f64::NAN;
        assert_eq!(
            p.validate("auv.").unwrap_err().to_string(),
            "2 bad fields:\n  field auv.q[2] = -1: allowed a finite number >= 0\n  field auv.sigma_speed = NaN: allowed a finite number > 0"
        );
    }
}
