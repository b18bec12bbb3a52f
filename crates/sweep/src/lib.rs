//! Sweeps: a study of many closed-loop missions described by one file and run anywhere.
//!
//! A sweep file ([`file`]) names base scenarios, the CNA policies every cell compares, the runs
//! per policy, axes (any scenario field by its path, or a choice among named overlays), the
//! overlays themselves, overlays applied where a cell's axis values meet a condition, and a
//! reduced form. [`expand`] validates the whole file and expands it into cells in a fixed order
//! (both live in `coopnav_sim::batch::sweep`, re-exported here, so that the reproductions whose
//! cells are a sweep file expand them the same way); [`plan`] writes the plan directory (manifest, one scenario file per cell, shard files)
//! and reads it back, refusing one written by another coopnav version or edited since;
//! [`shard`] runs shards (restartable, one process per shard, results journaled run by run);
//! [`merge`] joins finished shards into the paired comparison `simulate --runs` writes, plus
//! the run and fleet tables ([`table`]); [`status`] says where each shard stands; [`slurm`]
//! writes the `sbatch --array` script that runs the shards on a cluster.

pub mod error;
pub use coopnav_sim::batch::sweep::{expand, file};
pub mod merge;
pub mod plan;
pub mod shard;
pub mod slurm;
pub mod status;
pub mod table;

pub use error::SweepError;
