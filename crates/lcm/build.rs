//! Tells the tests which optional tools are here, so a test needing an absent one is reported as
//! ignored with its reason rather than passing:
//! - cfg `lcm_python`: a Python that imports the official `lcm` package (scripts/install-lcm.sh)
//!   with its `lcm-gen` beside it or on PATH: `$COOPNAV_LCM_PYTHON`, else tools/lcm/bin/python
//!   at the repository root, else `python3` on PATH. Handed to the tests as
//!   `COOPNAV_LCM_PYTHON_FOUND` and `COOPNAV_LCM_GEN_FOUND`;
//! - cfg `lcm_logger`: that package's `lcm-logger` too, the native program the wheel ships rather
//!   than its Python wrapper (`COOPNAV_LCM_LOGGER_FOUND`);
//! - cfg `private_netns`: `unshare -n` (else `unshare -rn`, unprivileged) works and `ip` can bring
//!   up the new namespace's loopback (the transport tests run only inside such a namespace);
//!   handed over as `COOPNAV_UNSHARE_FOUND` and `COOPNAV_UNSHARE_FLAGS`.
//!
//! What it watches, so installing a tool later re-runs it: when a tool is found, the files found;
//! when not, `PATH` and every directory on it, the Python's scripts directory (where pip puts
//! `lcm-gen`) and tools/lcm or tools/ at the root, the place of the install script's fallback
//! virtual environment.

use std::path::{Path, PathBuf};
use std::process::Command;

fn path_dirs() -> Vec<PathBuf> {
    std::env::var_os("PATH").map(|p| std::env::split_paths(&p).collect()).unwrap_or_default()
}

fn which(name: &str) -> Option<PathBuf> {
    path_dirs().into_iter().map(|d| d.join(name)).find(|p| p.is_file())
}

fn watch(path: &Path) {
    println!("cargo:rerun-if-changed={}", path.display());
}

/// What a Python reports of itself: its executable and scripts directory, and whether `lcm`
/// imports (with where).
struct PythonProbe {
    executable: PathBuf,
    scripts: PathBuf,
    lcm_init: Option<PathBuf>,
    /// Where the wheel keeps its native programs (its `lcm-logger` on PATH is a Python wrapper
    /// that SIGKILLs the real one on SIGINT, losing the unflushed end of the log).
    native_bin: Option<PathBuf>,
}

fn probe_python(python: &Path) -> Option<PythonProbe> {
    let script = "import sys, sysconfig\n\
                  print(sys.executable)\n\
                  print(sysconfig.get_paths()['scripts'])\n\
                  try:\n    import lcm\n    print(lcm.__file__)\n\
                  \x20   print(getattr(lcm, 'LCM_BIN_DIR', ''))\n\
                  except Exception:\n    print('')\n";
    let out = Command::new(python).args(["-c", script]).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    let mut lines = text.lines();
    let executable = PathBuf::from(lines.next()?);
    let scripts = PathBuf::from(lines.next()?);
    let lcm_init = lines.next().filter(|l| !l.is_empty()).map(PathBuf::from);
    let native_bin = lines.next().filter(|l| !l.is_empty()).map(PathBuf::from);
    Some(PythonProbe { executable, scripts, lcm_init, native_bin })
}

fn main() {
    let manifest_dir = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest_dir).join("../..");
    for cfg in ["lcm_python", "lcm_logger", "private_netns"] {
        println!("cargo::rustc-check-cfg=cfg({cfg})");
    }
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=PATH");
    println!("cargo:rerun-if-env-changed=COOPNAV_LCM_PYTHON");

    let venv_python = root.join("tools/lcm/bin/python");
    let candidates: Vec<PathBuf> = match std::env::var_os("COOPNAV_LCM_PYTHON") {
        Some(p) => vec![PathBuf::from(p)],
        None => [Some(venv_python.clone()), which("python3")].into_iter().flatten().collect(),
    };
    let mut found_python = false;
    let mut found_logger = false;
    let mut scripts_dirs = Vec::new();
    for python in &candidates {
        let Some(probe) = probe_python(python) else { continue };
        scripts_dirs.push(probe.scripts.clone());
        let Some(init) = probe.lcm_init else { continue };
        let tool = |name: &str| Some(probe.scripts.join(name)).filter(|p| p.is_file()).or_else(|| which(name));
        let Some(gen) = tool("lcm-gen") else { continue };
        watch(python);
        watch(&probe.executable);
        watch(&init);
        watch(&gen);
        println!("cargo:rustc-cfg=lcm_python");
        println!("cargo:rustc-env=COOPNAV_LCM_PYTHON_FOUND={}", probe.executable.display());
        println!("cargo:rustc-env=COOPNAV_LCM_GEN_FOUND={}", gen.display());
        found_python = true;
        let native_logger = probe.native_bin.as_ref().map(|d| d.join("lcm-logger")).filter(|p| p.is_file());
        if let Some(logger) = native_logger.or_else(|| tool("lcm-logger")) {
            watch(&logger);
            println!("cargo:rustc-cfg=lcm_logger");
            println!("cargo:rustc-env=COOPNAV_LCM_LOGGER_FOUND={}", logger.display());
            found_logger = true;
        }
        break;
    }

    // `unshare -n` as root; `unshare -rn` (a user namespace too) where unprivileged ones are allowed.
    let unshare = which("unshare");
    let ip = which("ip");
    let mut netns = false;
    if let (Some(unshare), Some(ip)) = (&unshare, &ip) {
        for flags in ["-n", "-rn"] {
            let works = Command::new(unshare)
                .args([flags, &ip.display().to_string(), "link", "set", "lo", "up"])
                .output()
                .is_ok_and(|o| o.status.success());
            if works {
                watch(unshare);
                watch(ip);
                println!("cargo:rustc-cfg=private_netns");
                println!("cargo:rustc-env=COOPNAV_UNSHARE_FOUND={}", unshare.display());
                println!("cargo:rustc-env=COOPNAV_UNSHARE_FLAGS={flags}");
                netns = true;
                break;
            }
        }
    }

    if !(found_python && found_logger && netns) {
        // Something is missing: watch where installing it would show.
        let mut dirs: Vec<&PathBuf> = Vec::new();
        let path = path_dirs();
        for dir in path.iter().chain(&scripts_dirs).filter(|d| d.is_dir()) {
            if !dirs.contains(&dir) {
                dirs.push(dir);
                watch(dir);
            }
        }
        let tools = root.join("tools");
        if tools.join("lcm").is_dir() {
            watch(&tools.join("lcm"));
        } else if tools.is_dir() {
            watch(&tools);
        }
    }
}
