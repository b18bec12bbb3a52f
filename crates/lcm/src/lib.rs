//! LCM (Lightweight Communications and Marshalling) for coopnav: the wire format field AUV
//! backseats such as MBARI's LRAUV speak.
//!
//! What this crate owns:
//! - [`schema`]: coopnav's message types as `.lcm` files (`crates/lcm/lcm/*.lcm`, package
//!   `coopnav`, the single source of truth), a parser for them, and lcm-gen's type fingerprints;
//! - [`codec`]: LCM's binary encoding of a [`value::Record`] and its refusal of malformed input;
//! - [`udpm`]: the UDP multicast transport (`udpm://` URLs, the `LC02` short and `LC03` fragment
//!   packets, bounded reassembly, publish and subscribe);
//! - [`logfile`]: lcm-logger's event log format, written and read.
//!
//! The facts each module follows are cited there from lcm-proj/lcm's documentation
//! (`docs/content/lcm-type-ref.md`, `udp-multicast-protocol.md`, `log-file-format.md`) and source
//! (`lcmgen/lcmgen.c`, `lcm/lcm_udpm.c`, `lcm/udpm_util.h`, `lcm/eventlog.c`); the code is coopnav's.
//!
//! # Implemented
//! - structs with every primitive (`int8_t` .. `int64_t`, `float`, `double`, `boolean`, `byte`,
//!   `string`), nested structs, constant and variable dimensions, multi-dimensional arrays,
//!   `const` declarations (also as array sizes), packages; fingerprints equal to lcm-gen's;
//! - exact-name channel subscriptions (plus "every channel"), receive with a timeout;
//! - log files: writer and a reader that resynchronises on the sync word.
//!
//! # Not implemented
//! - LCM `enum` types (deprecated in LCM) and inline nested declarations: refused by the parser;
//! - regular-expression subscriptions, the `mpudpm`, `tcpq`, `file` and `memq` providers;
//! - generated, statically typed Rust structs: messages are dynamic [`value::Record`]s checked
//!   against the schema;
//! - decoding accepts a boolean only as 0 or 1 (lcm's C decoder takes any non-zero byte as true).

pub mod codec;
pub mod error;
pub mod logfile;
pub mod sample;
pub mod schema;
pub mod udpm;
pub mod value;

pub use codec::{decode, encode};
pub use error::{CodecError, LogError, SchemaError, TransportError};
pub use logfile::{Event, LogReader, LogWriter};
pub use schema::Schema;
pub use udpm::Udpm;
pub use value::{Record, Value};
