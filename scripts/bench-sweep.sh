#!/usr/bin/env bash
# The sweep's overhead over bare simulation: RUNS one-hour missions of the default scenario (two
# baseline policies, RUNS/2 runs each) through `sweep plan` -> `sweep run --shard 0`, `--shard 1`
# (two shards, one after the other) -> `sweep merge`, against the same missions in one
# `simulate --runs` (the bare Monte Carlo), CPU time (user + system) of each from GNU time. Prints one JSON object. Usage: scripts/bench-sweep.sh [RUNS] (default
# 10000); the coopnav binary is target/release/coopnav (cargo build --release first).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
coopnav="$root/target/release/coopnav"
runs="${1:-10000}"
half=$((runs / 2))
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
printf 'scenarios = ["default"]\npolicies = ["zigzag", "racetrack"]\nruns = %d\n' "$half" >"$work/s.toml"
# CPU seconds (user + system) of one command, from GNU time (/usr/bin/time, Debian's `time`).
step() {
  /usr/bin/time -f "%U %S" -o "$work/time" "$@" >/dev/null
  awk '{ printf "%.3f\n", $1 + $2 }' "$work/time"
}
bare="$(step "$coopnav" simulate --runs "$half" --policy zigzag,racetrack --allow-large)"
plan="$(step "$coopnav" sweep plan "$work/s.toml" --shards 2 -o "$work/plan" --allow-large)"
shard0="$(step "$coopnav" sweep run "$work/plan" --shard 0)"
shard1="$(step "$coopnav" sweep run "$work/plan" --shard 1)"
start="$(date +%s.%N)"
merge="$(step "$coopnav" sweep merge "$work/plan")"
merge_wall="$(echo "$(date +%s.%N) - $start" | bc -l)"
sweep="$(echo "$plan + $shard0 + $shard1 + $merge" | bc -l)"
printf '{"missions": %d, "bare_cpu_s": %.2f, "sweep_cpu_s": %.2f, "plan_cpu_s": %.2f, "shard_cpu_s": [%.2f, %.2f], "merge_cpu_s": %.2f, "merge_wall_s": %.2f, "overhead_percent": %.2f}\n' \
  "$runs" "$bare" "$sweep" "$plan" "$shard0" "$shard1" "$merge" "$merge_wall" "$(echo "100 * ($sweep - $bare) / $bare" | bc -l)"
