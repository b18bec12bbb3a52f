"""Compare CNA policies over seeds on the default closed-loop mission and plot the distributions
of the survey AUVs' true navigation error.

    python examples/compare_policies.py --runs 20 --policies planner-estimator,centroid,zigzag --out errors.png

Every policy flies the same seeded runs (run i of each shares its sensor noise and channel draws),
so differences come from the policy. matplotlib is optional: without it the script prints the
table only.
"""

import argparse

import numpy as np

import coopnav


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="seeded runs per policy")
    parser.add_argument("--policies", default="planner-estimator,planner,centroid,zigzag,none")
    parser.add_argument("--duration", type=float, default=1800.0, help="mission length, s")
    parser.add_argument("--out", default="policy_errors.png", help="plot file (needs matplotlib)")
    args = parser.parse_args()

    data = coopnav.Scenario.example().to_dict()
    data["duration_s"] = args.duration
    scenario = coopnav.Scenario.from_dict(data)
    policies = args.policies.split(",")

    comparison = coopnav.monte_carlo(scenario, policies, args.runs)
    print(comparison["table"], end="")
    per_run = {p["policy"]: np.array(p["runs"]) for p in comparison["policies"]}

    # One mission in full: the error of every AUV over time, from simulate's time series.
    first = coopnav.simulate(scenario, policy=policies[0])["timeseries"]

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot (pip install matplotlib)")
        return
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    left.boxplot(list(per_run.values()), showmeans=True)
    left.set_xticks(range(1, len(per_run) + 1), list(per_run))
    left.set_ylabel("fleet mean true error per run (m)")
    left.set_title(f"{args.runs} seeded runs per policy")
    for k in np.unique(first["auv"]):
        rows = first["auv"] == k
        right.plot(first["t"][rows], first["error"][rows], label=f"auv{k}")
    right.set_xlabel("time (s)")
    right.set_ylabel("true error (m)")
    right.set_title(f"policy {policies[0]}, seed {data['seed']}")
    right.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
