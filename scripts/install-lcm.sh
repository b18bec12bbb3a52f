#!/usr/bin/env bash
# Installs the official LCM Python package (lcm 1.5.3 from PyPI: the `lcm` module, lcm-gen,
# lcm-logger) that crates/lcm's interoperability tests check coopnav's LCM codec, transport and
# log files against. Idempotent and quiet when a usable install is already there (the same places
# crates/lcm/build.rs probes: $COOPNAV_LCM_PYTHON, tools/lcm/bin/python, python3 on PATH).
# It installs into python3's own environment (where build.rs sees lcm-gen appear and re-runs),
# falling back to a virtual environment at tools/lcm/ when that environment is externally managed.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
version="1.5.3"
usable() {
  "$1" - "$version" <<'PY' 2>/dev/null
import os, sys, sysconfig, shutil
from importlib.metadata import version
import lcm  # noqa: F401
assert version("lcm") == sys.argv[1]
scripts = sysconfig.get_paths()["scripts"]
for tool in ("lcm-gen", "lcm-logger"):
    assert os.path.isfile(os.path.join(scripts, tool)) or shutil.which(tool)
PY
}
for python in ${COOPNAV_LCM_PYTHON:+"$COOPNAV_LCM_PYTHON"} "$root/tools/lcm/bin/python" python3; do
  if command -v "$python" >/dev/null 2>&1 && usable "$python"; then
    exit 0
  fi
done
if python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore "lcm==$version" 2>/dev/null \
  && usable python3; then
  echo "lcm $version installed for $(command -v python3)"
  exit 0
fi
venv="$root/tools/lcm"
# A half-made virtual environment would look installed to the next run's probe: remove it unless
# the install completes.
trap 'rm -rf "$venv"' EXIT
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "lcm==$version"
usable "$venv/bin/python"
trap - EXIT
echo "lcm $version installed in $venv"
