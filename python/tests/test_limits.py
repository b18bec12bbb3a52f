"""Python refuses what the CLI refuses, with the same words: the limits and messages live in the
libraries both call."""

import math
import subprocess

import pytest

import coopnav


def cli_error(cli, *args, cwd):
    done = subprocess.run([cli.exe, *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert done.returncode != 0, f"coopnav {args} accepted the input"
    return done.stderr


def test_a_nan_in_a_dict_names_its_field():
    data = coopnav.Scenario.example().to_dict()
    data["fleet"]["current"] = [0.05, math.nan]
    with pytest.raises(ValueError, match=r"field fleet\.current\[1\] = NaN: allowed a finite number"):
        coopnav.Scenario.from_dict(data)


def test_an_endless_scenario_file_is_refused_like_the_cli(cli, tmp_path):
    words = "input file (bytes)"
    assert words in cli_error(cli, "simulate", "/dev/zero", "-o", tmp_path / "out", cwd=tmp_path)
    with pytest.raises(ValueError, match=r"input file \(bytes\).*--allow-large"):
        coopnav.Scenario.load("/dev/zero")


def test_a_log_the_cli_refuses_is_refused_not_an_abort(cli, tmp_path):
    """Rows 500 s apart over 11 days ask for gigabytes of filter history: a ValueError naming
    the limit, as the CLI's message does, instead of an interpreter killed by the allocator."""
    rows = ["# coopnav-log 2 time=relative", "t,kind,src,v1,v2,v3,v4,sigma", "0,init,,0,0,1.5,90,"]
    rows += [f"{500 * i},speed,,1.5,,,," for i in range(1, 2000)]
    log = tmp_path / "log.csv"
    log.write_text("\n".join(rows) + "\n")
    err = cli_error(cli, "hbl", "postprocess", log, "-o", tmp_path / "out", cwd=tmp_path)
    assert "memory of the filter history" in err
    with pytest.raises(ValueError, match="memory of the filter history"):
        coopnav.postprocess(str(log))


def test_a_millimetre_shelf_is_refused_before_its_grid_is_built(cli, tmp_path):
    data = coopnav.Scenario.example().to_dict()
    data["fleet"]["shelf"] = {
        "shallow": 30.0, "deep": 90.0, "x_shallow": 0.0, "x_deep": 1700.0,
        "x_min": -1000.0, "x_max": 3000.0, "y_min": -1000.0, "y_max": 2000.0, "spacing": 1e-3,
    }
    with pytest.raises(ValueError, match=r"bathymetry grid nodes.*fleet\.shelf"):
        coopnav.Scenario.from_dict(data)
