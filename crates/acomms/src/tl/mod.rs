//! Transmission loss between two points, behind one trait with three implementations:
//! [`analytic::Thorp`] (spreading + Thorp absorption), [`bellhop::Bellhop`] (the real BELLHOP
//! program) and [`cached::CachedGrid`] (a precomputed range × depth field, interpolated, so Monte
//! Carlo loops never call BELLHOP).

pub mod analytic;
pub mod bellhop;
pub mod cached;

use coopnav_core::Vec3;
use thiserror::Error;

pub use bellhop::BellhopError;

/// Largest TL any provider reports, dB: a zero pressure (no beam reached the receiver) maps here.
pub const TL_CEILING: f64 = 200.0;

#[derive(Debug, Error)]
pub enum TlError {
    #[error(transparent)]
    Bellhop(#[from] BellhopError),
    #[error("transmission loss: {0}")]
    Invalid(String),
}

/// A transmission-loss model, dB re 1 m.
pub trait TransmissionLoss: Send + Sync {
    /// TL from a source at `src` to a receiver at `rx`.
    fn tl(&self, src: &Vec3, rx: &Vec3) -> Result<f64, TlError>;

    /// TL over a grid of horizontal ranges × receiver depths along the radial from `src` at
    /// `bearing` (math convention, rad); row-major by depth. Providers that compute a whole field
    /// at once (BELLHOP) override this.
    fn field(&self, src: &Vec3, bearing: f64, ranges: &[f64], depths: &[f64]) -> Result<Vec<f64>, TlError> {
        let (c, s) = (bearing.cos(), bearing.sin());
        let mut out = Vec::with_capacity(ranges.len() * depths.len());
        for &z in depths {
            for &r in ranges {
                out.push(self.tl(src, &Vec3::new(src.x + r * c, src.y + r * s, z))?);
            }
        }
        Ok(out)
    }
}
