//! `coopnav sweep` on a real Slurm cluster: a two-node cluster on this host (MUNGE, slurmctld and
//! two slurmd, `tests/slurm/cluster.sh`) inside a private network namespace the test makes
//! (`unshare -n`, loopback only), the plan's shards submitted with the `sbatch --array` script
//! `coopnav sweep slurm` writes, the merge as the job that depends on them. Checked: every shard
//! ran, both nodes ran shards, and the shard results and merged files are byte-identical to the
//! same plan run in one process (`sweep run --all`). Every wait is bounded (the script's own, and
//! this test's backstop).

mod common;

use common::copy_dir;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const COOPNAV: &str = env!("CARGO_BIN_EXE_coopnav");

fn coopnav(args: &[&str]) -> String {
    let out = Command::new(COOPNAV).args(args).output().expect("coopnav runs");
    assert!(out.status.success(), "coopnav {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Every file under `dir` but the manifests (they name the command and the directory).
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().unwrap() != "manifest.json" {
                out.push((p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[cfg(all(slurm_installed, private_netns))]
fn unshare() -> (&'static str, &'static str) {
    (env!("COOPNAV_UNSHARE_FOUND"), env!("COOPNAV_UNSHARE_FLAGS"))
}
#[cfg(not(all(slurm_installed, private_netns)))]
fn unshare() -> (&'static str, &'static str) {
    unreachable!("the test is ignored without Slurm and a private namespace")
}

#[test]
#[cfg_attr(
    not(all(slurm_installed, private_netns)),
    ignore = "needs Slurm and MUNGE (scripts/install-slurm.sh) and `unshare -n` for a private network namespace"
)]
fn a_sweep_runs_as_a_slurm_array_on_two_nodes_and_merges_to_the_one_process_bytes() {
    let tmp = tempfile::Builder::new().prefix("cn-slurm").tempdir_in("/tmp").unwrap();
    let t = tmp.path();
    let sweep = t.join("s.toml");
    std::fs::write(
        &sweep,
        "scenarios = [\"default\"]\npolicies = [\"zigzag\", \"racetrack\"]\nruns = 3\n\
         [[axis]]\npath = \"fleet.n_auvs\"\nvalues = [2, 3]\n",
    )
    .unwrap();
    let (cluster, local) = (t.join("cluster"), t.join("local"));
    coopnav(&["sweep", "plan", sweep.to_str().unwrap(), "--shards", "4", "-o", cluster.to_str().unwrap()]);
    copy_dir(&cluster, &local);
    coopnav(&["sweep", "run", local.to_str().unwrap(), "--all"]);
    coopnav(&["sweep", "merge", local.to_str().unwrap()]);
    coopnav(&["sweep", "slurm", cluster.to_str().unwrap()]);

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/cluster.sh");
    let submit = cluster.join("slurm/submit.sh");
    let (program, flags) = unshare();
    let mut child = Command::new(program)
        .arg(flags)
        .arg("bash")
        .arg(&script)
        .arg(t.join("slurm-state"))
        .arg("bash")
        .arg(&submit)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("unshare runs the cluster script");
    // Backstop above the script's own bounds (60 s to start, 300 s to drain the queue): SIGTERM
    // first, so its trap stops the daemons.
    let deadline = Instant::now() + Duration::from_secs(420);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            // SAFETY: signalling the child this test started, by its pid.
            unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
            std::thread::sleep(Duration::from_secs(10));
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("the cluster did not finish within 420 s:\n{}", String::from_utf8_lossy(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    let out = child.wait_with_output().unwrap();
    let log = |name: &str| std::fs::read_to_string(t.join("slurm-state/log").join(name)).unwrap_or_default();
    assert!(
        out.status.success(),
        "the cluster script failed:\n{}\n{}\nslurmctld: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
        log("slurmctld.log")
    );

    let mut nodes = std::collections::BTreeSet::new();
    for s in 0..4 {
        let text = std::fs::read_to_string(cluster.join(format!("slurm/logs/shard-{s}.out"))).unwrap();
        let node = text
            .lines()
            .find_map(|l| l.strip_prefix(&format!("coopnav sweep: shard {s} on node ")))
            .unwrap_or_else(|| panic!("shard {s}'s log names no node:\n{text}"));
        nodes.insert(node.to_string());
        assert!(cluster.join(format!("results/shard-00{s}.cbor")).is_file(), "shard {s} has no results");
    }
    assert_eq!(nodes.into_iter().collect::<Vec<_>>(), ["node1", "node2"], "both nodes ran shards");
    let merged = std::fs::read_to_string(cluster.join("slurm/logs/merge.out")).unwrap();
    assert!(merged.contains("coopnav sweep: merge on node") && merged.contains("wrote "), "{merged}");
    for part in ["results", "merged"] {
        let (a, b) = (files(&cluster.join(part)), files(&local.join(part)));
        assert!(!a.is_empty());
        assert_eq!(
            a.iter().map(|f| &f.0).collect::<Vec<_>>(),
            b.iter().map(|f| &f.0).collect::<Vec<_>>(),
            "{part}: the same files"
        );
        assert!(a == b, "{part}: the cluster's bytes differ from the one-process run's");
    }
}
