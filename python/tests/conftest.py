"""Shared fixtures: the real `coopnav` CLI binary, run in a scratch directory, whose results
every test compares with the Python API's on the same inputs and seed."""

import csv
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _find_cli():
    given = os.environ.get("COOPNAV_CLI")
    if given:
        return given
    for profile in ("release", "debug"):
        candidate = ROOT / "target" / profile / "coopnav"
        if candidate.is_file():
            return str(candidate)
    return shutil.which("coopnav")


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI with arguments, returns its stdout; fails the test with its stderr."""
    exe = _find_cli()
    if exe is None:
        pytest.skip("the coopnav CLI binary is not built (set COOPNAV_CLI or run cargo build --release)")

    def run(*args, cwd=None):
        done = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, cwd=cwd)
        if done.returncode != 0:
            raise AssertionError(f"coopnav {' '.join(map(str, args))} failed:\n{done.stderr}")
        return done.stdout

    run.exe = exe
    return run


def read_csv(path):
    """A CSV file as columns of strings."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [r[k] for r in rows] for k in rows[0]}


def floats(values):
    """CSV fields as floats; an empty field is NaN (how the Python API writes a missing value)."""
    return [float(v) if v != "" else float("nan") for v in values]


def read_json(path):
    with open(path) as f:
        return json.load(f)
