//! coopnav-acomms: the acoustic link, after Nams (2014).
//!
//! It owns the WHOI Micro-Modem rate table, transmission-loss models (analytic and BELLHOP),
//! packet success, TDMA, the bit-exact message codecs, the packet-success tracker and the
//! adaptive rate selector.

pub mod codec;
pub mod estimator;
pub mod node_report;
pub mod rates;
pub mod selector;
pub mod status;
pub mod success;
pub mod tl;
pub mod tracker;
pub mod workload;

pub use rates::{Rate, RateSpec, Tdma};
pub use success::{Receiver, Reception, SuccessModel};
pub use tl::{TlError, TransmissionLoss};
