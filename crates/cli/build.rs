//! Tells the tests which optional external programs are installed, so a test that needs an absent
//! one is reported as ignored, with its reason, instead of passing:
//! - cfg `chromium_installed`: `$COOPNAV_CHROMIUM`, else /usr/bin/chromium, else `chromium` or
//!   `chromium-browser` on PATH, runs `--version` (scripts/install-chromium.sh);
//! - cfg `pymoos_installed`: `$COOPNAV_PYMOOS_PYTHON`, else tools/pymoos/bin/python, imports
//!   pymoos2 (scripts/install-pymoos.sh);
//! - cfg `python_package_installed`: `$COOPNAV_PYENV_PYTHON`, else tools/pyenv/bin/python, imports
//!   coopnav's own Python package and pytest (scripts/install-python.sh);
//! - cfg `bellhop_installed`: the rule of `crates/acomms/bellhop_cfg.rs` (the Python package's
//!   BELLHOP test needs it).
//!
//! - cfg `slurm_installed`: slurmctld, slurmd, sbatch, squeue, sinfo and munged on PATH or in
//!   /usr/sbin, and `slurmd -V` runs (scripts/install-slurm.sh; the sweep's Slurm test also
//!   needs `private_netns`);
//! - cfg `private_netns`: `unshare -n` (else `unshare -rn`, unprivileged) runs `ip link set lo
//!   up` in a new network namespace, as crates/lcm/build.rs probes it (the `live auv` end-to-end
//!   test runs its multicast only inside such a namespace); the program and flags are handed over
//!   as `COOPNAV_UNSHARE_FOUND` and `COOPNAV_UNSHARE_FLAGS`.
//!
//! The program found is handed to the tests as `COOPNAV_CHROMIUM_FOUND` / `COOPNAV_PYMOOS_FOUND` /
//! `COOPNAV_PYENV_FOUND`, so they run exactly what was detected.
//!
//! What it watches, so installing or removing a tool after a build re-runs it without a clean
//! build: the program found (and the package's install stamp); for one not found, `PATH` and the
//! directories it would appear in (the nearest existing one above its default place, every
//! directory on PATH for Chromium, tools/ at the root for the virtual environments).

include!("../acomms/bellhop_cfg.rs");

use std::path::{Path, PathBuf};
use std::process::Command;

/// An optional program: its cfg, the variable naming it, where it may be by default (the first
/// that runs is taken), and the arguments of a quick run that succeeds only when it is usable.
struct Optional {
    cfg: &'static str,
    env: &'static str,
    found_env: &'static str,
    defaults: Vec<PathBuf>,
    probe: &'static [&'static str],
}

fn path_dirs() -> Vec<PathBuf> {
    std::env::var_os("PATH").map(|p| std::env::split_paths(&p).collect()).unwrap_or_default()
}

fn main() {
    // Read when the script runs, not baked in when it is compiled: one compiled build script serves
    // every checkout that shares a target directory, and must probe the checkout being built.
    let manifest_dir = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR for build scripts");
    let root = Path::new(&manifest_dir).join("../..");
    let root = root.canonicalize().unwrap_or(root);
    let on_path = |name: &'static str| path_dirs().into_iter().map(move |d| d.join(name));
    let optionals = [
        Optional {
            cfg: "chromium_installed",
            env: "COOPNAV_CHROMIUM",
            found_env: "COOPNAV_CHROMIUM_FOUND",
            defaults: std::iter::once(PathBuf::from("/usr/bin/chromium"))
                .chain(on_path("chromium"))
                .chain(on_path("chromium-browser"))
                .collect(),
            probe: &["--version"],
        },
        Optional {
            cfg: "pymoos_installed",
            env: "COOPNAV_PYMOOS_PYTHON",
            found_env: "COOPNAV_PYMOOS_FOUND",
            defaults: vec![root.join("tools/pymoos/bin/python")],
            probe: &["-c", "import pymoos2.core.MissionReader"],
        },
        Optional {
            cfg: "python_package_installed",
            env: "COOPNAV_PYENV_PYTHON",
            found_env: "COOPNAV_PYENV_FOUND",
            defaults: vec![root.join("tools/pyenv/bin/python")],
            probe: &["-c", "import coopnav, pytest"],
        },
    ];
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../acomms/bellhop_cfg.rs");
    println!("cargo:rerun-if-env-changed=PATH");
    // Reinstalling the package rewrites this stamp (the venv's python itself does not change).
    let stamp = root.join("tools/pyenv/coopnav-installed");
    if stamp.is_file() {
        println!("cargo:rerun-if-changed={}", stamp.display());
    }
    for o in &optionals {
        detect(o, &root);
    }
    detect_bellhop(&manifest_dir);
    detect_netns();
    detect_slurm();
}

/// The Slurm and MUNGE programs the two-node cluster of `tests/sweep_slurm.rs` runs.
fn detect_slurm() {
    println!("cargo::rustc-check-cfg=cfg(slurm_installed)");
    let find = |name: &str| which(name).or_else(|| Some(Path::new("/usr/sbin").join(name)).filter(|p| p.is_file()));
    let programs = ["slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "munged"];
    let found: Vec<Option<PathBuf>> = programs.iter().map(|p| find(p)).collect();
    if found.iter().all(Option::is_some) {
        let slurmd = found[1].as_ref().expect("all found");
        if Command::new(slurmd).arg("-V").output().is_ok_and(|o| o.status.success()) {
            println!("cargo:rerun-if-changed={}", slurmd.display());
            println!("cargo:rustc-cfg=slurm_installed");
            return;
        }
    }
    println!("cargo:rerun-if-changed=/usr/sbin");
}

fn which(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file())
}

/// `unshare -n` as root, `unshare -rn` where unprivileged user namespaces are allowed.
fn detect_netns() {
    println!("cargo::rustc-check-cfg=cfg(private_netns)");
    println!("cargo:rerun-if-env-changed=PATH");
    let (Some(unshare), Some(ip)) = (which("unshare"), which("ip")) else { return };
    for flags in ["-n", "-rn"] {
        let works = Command::new(&unshare)
            .args([flags, &ip.display().to_string(), "link", "set", "lo", "up"])
            .output()
            .is_ok_and(|o| o.status.success());
        if works {
            println!("cargo:rerun-if-changed={}", unshare.display());
            println!("cargo:rustc-cfg=private_netns");
            println!("cargo:rustc-env=COOPNAV_UNSHARE_FOUND={}", unshare.display());
            println!("cargo:rustc-env=COOPNAV_UNSHARE_FLAGS={flags}");
            return;
        }
    }
}

fn detect(o: &Optional, root: &Path) {
    println!("cargo::rustc-check-cfg=cfg({})", o.cfg);
    println!("cargo:rerun-if-env-changed={}", o.env);
    let candidates = std::env::var_os(o.env).map_or_else(|| o.defaults.clone(), |p| vec![PathBuf::from(p)]);
    let runs = |program: &PathBuf| Command::new(program).args(o.probe).output().is_ok_and(|out| out.status.success());
    if let Some(program) = candidates.iter().find(|p| runs(p)) {
        println!("cargo:rerun-if-changed={}", program.display());
        println!("cargo:rustc-cfg={}", o.cfg);
        println!("cargo:rustc-env={}={}", o.found_env, program.display());
        return;
    }
    // Not usable: watch where installing it would show. A directory is watched with everything
    // below it, so neither the repository's root (its target/ changes with every build) nor the
    // file system's root; tools/ is in the repository, so there is always a place to watch.
    let tools = root.join("tools");
    let mut watched: Vec<PathBuf> = Vec::new();
    for program in &candidates {
        let dir = program.ancestors().skip(1).find(|d| d.is_dir()).map(|d| d.canonicalize().unwrap_or(d.to_path_buf()));
        let dir = match dir {
            // A virtual environment's python exists before the package is installed in it: watch
            // the environment, where pip writes.
            Some(d) if d.starts_with(&tools) && d != tools => {
                d.strip_prefix(&tools).ok().and_then(|r| r.components().next()).map_or(d.clone(), |c| tools.join(c))
            }
            Some(d) if d != root && d.parent().is_some() => d,
            _ => tools.clone(),
        };
        if !watched.contains(&dir) {
            println!("cargo:rerun-if-changed={}", dir.display());
            watched.push(dir);
        }
    }
}
