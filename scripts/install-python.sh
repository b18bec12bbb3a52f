#!/usr/bin/env bash
# Builds coopnav's Python package (python/, pyo3 + maturin) into a virtual environment under
# tools/pyenv/ at the repository root, with maturin, numpy, pytest and the DataFrame readers of a
# sweep's Parquet tables (pandas, polars, pyarrow) from PyPI, for the pytest
# suite that crates/cli/tests/python.rs runs. The venv is made once; the package is rebuilt every
# time (cargo only recompiles what changed, in python/target). On success it writes the stamp
# tools/pyenv/coopnav-installed, which crates/cli/build.rs looks for.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
venv="$root/tools/pyenv"
python="$venv/bin/python"
if ! [ -x "$venv/bin/maturin" ] || ! "$python" -c "import numpy, pytest, pandas, polars, pyarrow" 2>/dev/null; then
  python3 -m venv "$venv"
  "$python" -m pip install --quiet --disable-pip-version-check "maturin>=1.9.4,<2" "numpy>=1.21" "pytest>=7" \
    "pandas>=2" "polars>=1" "pyarrow>=14"
fi
rm -f "$venv/coopnav-installed"
# `maturin develop` builds the release extension and installs the package into the venv (editable:
# the compiled module lands in python/coopnav/). pip is not needed again, so this works offline.
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" "$venv/bin/maturin" develop --release --quiet \
  -m "$root/python/Cargo.toml"
"$python" -c "import coopnav; print('coopnav', coopnav.__version__, 'installed in $venv')"
date -u +%FT%TZ > "$venv/coopnav-installed"
