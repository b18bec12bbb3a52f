//! A run directory: refuses to overwrite without --force, writes into `<dir>.partial` and renames
//! at the end, so a failed run leaves nothing half-written under the requested name.
//! (Stand-in until the lead's shared output writer lands on main.)

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

pub struct RunDir {
    target: PathBuf,
    staging: PathBuf,
}

impl RunDir {
    pub fn create(target: &Path, force: bool) -> Result<Self> {
        if target.exists() && !force {
            bail!("{} already exists; pass --force to overwrite it", target.display());
        }
        let mut staging = target.as_os_str().to_owned();
        staging.push(".partial");
        let staging = PathBuf::from(staging);
        if staging.exists() {
            std::fs::remove_dir_all(&staging).with_context(|| format!("removing stale {}", staging.display()))?;
        }
        std::fs::create_dir_all(&staging).with_context(|| format!("creating {}", staging.display()))?;
        Ok(RunDir { target: target.to_path_buf(), staging })
    }

    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> Result<()> {
        let p = self.staging.join(name);
        std::fs::write(&p, contents).with_context(|| format!("writing {}", p.display()))
    }

    pub fn write_json(&self, name: &str, value: &impl serde::Serialize) -> Result<()> {
        self.write(name, serde_json::to_string_pretty(value)?)
    }

    /// Moves the finished run into place.
    pub fn finish(self) -> Result<PathBuf> {
        if self.target.exists() {
            std::fs::remove_dir_all(&self.target).with_context(|| format!("removing {}", self.target.display()))?;
        }
        std::fs::rename(&self.staging, &self.target).with_context(|| format!("renaming into {}", self.target.display()))?;
        Ok(self.target)
    }
}
