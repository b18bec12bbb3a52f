//! Reading an input file (scenario, config, spec, mapping) through the libraries' one bounded
//! reader ([`coopnav_core::limits::read_text`]): at most [`MAX_INPUT_FILE_BYTES`] are read
//! without `--allow-large`, whatever the input is (a file, a pipe, a device), so a mistaken
//! multi-gigabyte input is refused before it fills memory.

use anyhow::Result;
use coopnav_core::limits::{self, MAX_INPUT_FILE_BYTES};
use std::path::Path;

/// The text of `path`, read at most to the input limit.
pub fn read(path: &Path, allow_large: bool) -> Result<String> {
    Ok(limits::read_text(path, "input file (bytes)", MAX_INPUT_FILE_BYTES, allow_large)?)
}
