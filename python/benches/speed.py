"""The Python package's speed targets, measured against the Rust side in one run (interleaved
repetitions, medians), printed as JSON:

* one planner decision, N = 5, A = 7, L = 5 (estimator-aware cost, branch-and-bound on one
  thread): ``Planner.decide`` against ``coopnav bench planner``'s ``bnb_1_thread`` time for the
  same workload (target: at most 1.5x);
* the default closed-loop mission: ``coopnav.simulate`` against ``coopnav simulate`` (the whole
  command, process start and run directory included; target: at most 1.1x).

    python python/benches/speed.py --cli target/release/coopnav --runs 5
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import coopnav

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_plan import workload  # noqa: E402  (the bench workload, rebuilt from its geometry)


def timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cli", default="target/release/coopnav")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()

    planner, inputs = workload({"kind": "estimator"})
    rust_decision, python_decision, rust_sim, python_sim = [], [], [], []
    scenario = coopnav.Scenario.example()
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.runs):
            bench = json.loads(subprocess.run([args.cli, "bench", "planner", "--runs", "5", "--brute-max-leaves", "0"],
                                              capture_output=True, text=True, check=True).stdout)
            row = next(r for r in bench["results"]
                       if (r["workload"]["n"], r["workload"]["a"], r["workload"]["l"]) == (5, 7, 5)
                       and r["workload"]["cost"]["kind"] == "estimator")
            rust_decision.append(row["bnb_1_thread"]["seconds"])
            python_decision.append(statistics.median(timed(lambda: planner.decide(*inputs)) for _ in range(5)))
            out = Path(tmp) / f"sim{rep}"
            rust_sim.append(timed(lambda: subprocess.run([args.cli, "simulate", "-o", str(out)],
                                                         capture_output=True, check=True)))
            python_sim.append(timed(lambda: coopnav.simulate(scenario)))
    med = statistics.median
    print(json.dumps({
        "runs": args.runs,
        "decision_N5_A7_L5_estimator": {
            "rust_bench_s": med(rust_decision), "python_s": med(python_decision),
            "ratio": med(python_decision) / med(rust_decision), "target": 1.5,
        },
        "simulate_default_mission": {
            "cli_s": med(rust_sim), "python_s": med(python_sim),
            "ratio": med(python_sim) / med(rust_sim), "target": 1.1,
        },
    }, indent=2))


if __name__ == "__main__":
    main()
