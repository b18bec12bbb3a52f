//! Reading an input file (scenario, config, spec) whose size is checked first: a file above
//! [`MAX_INPUT_FILE_BYTES`] is read only with `--allow-large`, so a mistaken multi-gigabyte
//! file is refused before it fills memory.

use anyhow::{Context, Result};
use coopnav_core::limits::{self, Estimate, MAX_INPUT_FILE_BYTES};
use std::path::Path;

/// The text of `path`, after its size is checked.
pub fn read(path: &Path, allow_large: bool) -> Result<String> {
    let bytes = std::fs::metadata(path).with_context(|| format!("cannot read {}", path.display()))?.len();
    let size = Estimate::new("input file (bytes)", path.display().to_string(), bytes as f64, MAX_INPUT_FILE_BYTES);
    limits::check([size], allow_large)?;
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}
