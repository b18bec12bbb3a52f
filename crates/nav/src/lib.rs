//! coopnav-nav: survey-AUV navigation with one-way-travel-time (OWTT) ranges, after Gill (2013).
//!
//! It owns the generic EKF, the AUV and surface-vehicle filters, the OWTT range model, the
//! mini-packet codec, the ranging cycles, the RTS smoother and the post-processing of logs.

pub mod auv;
pub mod codec;
pub mod consistency;
pub mod cycle;
pub mod ekf;
pub mod fieldlog;
pub mod post;
pub mod post_quality;
pub mod post_reference;
pub mod post_tune;
pub mod range;
pub mod smoother;
pub mod surface;
pub mod synthetic;

pub use auv::{
    AuvEkf, AuvFilter, AuvModel, AuvParams, CurrentParams, GateRecovery, IteratedRange, OutlierUpdate, ParamError,
    RangeLinearisation, RangeOutliers, Recoveries,
};
pub use ekf::{Ekf, Gate, UpdateOutcome};
pub use range::{RangeMeasurement, RangeNoise};
pub use surface::{Outriggers, Side, StateKind, SurfaceEkf, SurfaceParams};
