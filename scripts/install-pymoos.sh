#!/usr/bin/env bash
# Installs pymoos2 (the pure-Python MOOS framework, from PyPI) into a virtual environment under
# tools/pymoos/ at the repository root. coopnav's mission-file test parses the generated .moos
# with its MissionReader, a parser that is not coopnav's own. Idempotent: does nothing when the
# venv already imports it. coopnav finds the interpreter through $COOPNAV_PYMOOS_PYTHON, else
# tools/pymoos/bin/python.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/tools/pymoos"
python="$venv/bin/python"
if [ -x "$python" ] && "$python" -c "import pymoos2.core.MissionReader" 2>/dev/null; then
  echo "pymoos2 already installed in $venv"
  exit 0
fi
python3 -m venv "$venv"
"$python" -m pip install --quiet --disable-pip-version-check "pymoos2==0.1.0"
"$python" -c "import pymoos2.core.MissionReader; print('pymoos2 installed in $venv')"
