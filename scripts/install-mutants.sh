#!/usr/bin/env bash
# Installs cargo-mutants (crates.io), the mutation tester docs/testing.md describes: it changes one
# expression of the code at a time (a `+` to `-`, a function body to a default value...) and runs
# the tests, reporting each change the tests did not catch. Idempotent: does nothing when
# `cargo mutants` already runs. `scripts/mutants-diff.sh` (which CI runs on a change) calls it.
# The version is the one the options of docs/testing.md and mutants-diff.sh were checked with.
set -euo pipefail
if cargo mutants --version >/dev/null 2>&1; then
  exit 0
fi
cargo install --locked cargo-mutants --version 27.1.0
cargo mutants --version
