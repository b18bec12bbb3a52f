#!/usr/bin/env bash
# Mutation testing of the lines a change touches (docs/testing.md#mutation-testing): diffs the
# Rust sources against the merge base of HEAD and BASE_REF, and runs cargo-mutants with
# `--in-diff` on that diff, each mutant tested by its own crate's tests. Prints the counts
# (caught / missed / unviable / timed out) and every missed mutant.
#
#   bash scripts/mutants-diff.sh [BASE_REF] [--in-place]
#
# BASE_REF defaults to $MUTANTS_BASE_REF, else `origin/main`, else `main`. When no merge base
# other than HEAD itself exists (a clone of main, a detached commit with no main) or the diff
# touches no Rust source, it says so and exits 0 at once.
#
# `--in-place` mutates this tree itself, reusing its warm `target/` (what CI does after its test
# run; the files are restored after each mutant and on Ctrl-C). Without it cargo-mutants copies
# the tree and builds the copy from scratch.
#
# The run is bounded: cargo-mutants is interrupted after $MUTANTS_TIME_LIMIT (default 20m, a
# `timeout` duration) and the counts of the mutants tested so far are printed. Each mutant's test
# run is bounded by $MUTANTS_TEST_TIMEOUT seconds (default 300). Exit status: cargo-mutants' own
# (0 all caught, 2 some missed, 3 some timed out; 124 when the time limit cut the run short), so a
# caller may gate on it; `.ci/run` only reports.
set -euo pipefail
cd "$(dirname "$0")/.."

base_ref="${MUTANTS_BASE_REF:-}"
# --in-place and --jobs exclude each other: one job either way.
place=(--jobs 1)
for arg in "$@"; do
  case "$arg" in
    --in-place) place=(--in-place) ;;
    -*)
      echo "mutants-diff: unknown option $arg (allowed: --in-place)" >&2
      exit 1
      ;;
    *) base_ref="$arg" ;;
  esac
done
if [ -z "$base_ref" ]; then
  for candidate in origin/main main; do
    if git rev-parse --verify --quiet "$candidate^{commit}" >/dev/null; then
      base_ref="$candidate"
      break
    fi
  done
fi
if [ -z "$base_ref" ] || ! git rev-parse --verify --quiet "$base_ref^{commit}" >/dev/null; then
  echo "mutants-diff: skipped: no base branch (${base_ref:-origin/main or main}) to diff against"
  exit 0
fi
head="$(git rev-parse HEAD)"
if ! base="$(git merge-base HEAD "$base_ref")"; then
  echo "mutants-diff: skipped: HEAD and $base_ref have no merge base"
  exit 0
fi
if [ "$base" = "$head" ]; then
  echo "mutants-diff: skipped: the merge base with $base_ref is HEAD itself (no change to test)"
  exit 0
fi

out="${MUTANTS_OUT:-target/mutants-diff}"
mkdir -p "$out"
diff="$out/change.diff"
# Committed changes since the merge base plus any uncommitted ones, Rust sources only.
git diff "$base" -- '*.rs' >"$diff"
if [ ! -s "$diff" ]; then
  echo "mutants-diff: skipped: no Rust source changed since $(git rev-parse --short "$base") ($base_ref)"
  exit 0
fi
echo "mutants-diff: mutating the lines changed since $(git rev-parse --short "$base") ($base_ref):" \
  "$(grep -c "^+++ " "$diff") file(s)"

bash scripts/install-mutants.sh

limit="${MUTANTS_TIME_LIMIT:-20m}"
status=0
# The baseline (the unmutated tests) is skipped: CI ran the same tests just before, and a red
# baseline fails CI on its own. Each mutant is built and tested with the release profile (the
# warm `target/` of the test run) by its crate's unit and integration tests (`--tests`: no
# doctests, which build one program per example).
timeout --signal=INT --kill-after=60 "$limit" \
  nice -n 10 cargo mutants --in-diff "$diff" "${place[@]}" --baseline skip \
  --timeout "${MUTANTS_TEST_TIMEOUT:-300}" --output "$out" --no-shuffle \
  --profile release --cargo-arg=--tests || status=$?

dir="$out/mutants.out"
count() {
  if [ -f "$dir/$1" ]; then grep -c . "$dir/$1" || true; else echo 0; fi
}
echo "== mutants on the changed lines: caught $(count caught.txt), missed $(count missed.txt)," \
  "unviable $(count unviable.txt), timed out $(count timeout.txt)"
if [ "$status" = 124 ]; then
  echo "mutants-diff: stopped after $limit: the counts cover the mutants tested by then"
fi
if [ -s "$dir/missed.txt" ]; then
  echo "missed (no test failed with this change):"
  sed 's/^/  /' "$dir/missed.txt"
fi
exit "$status"
