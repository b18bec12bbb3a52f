"""simulate and monte_carlo against `coopnav simulate` on the same scenario and seed."""

import json
import threading
import time

import numpy as np
import pytest

import coopnav
from conftest import floats, read_csv, read_json


def short_scenario(tmp_path, duration_s=600.0, n_auvs=None):
    """The default mission cut short, as a file both the CLI and Python read."""
    d = coopnav.Scenario.example().to_dict()
    d["duration_s"] = duration_s
    if n_auvs is not None:
        d["fleet"]["n_auvs"] = n_auvs
    path = tmp_path / "short.toml"
    path.write_text(coopnav.Scenario.from_dict(d).to_toml())
    return path


@pytest.mark.parametrize("policy, seed", [("planner", 1), ("centroid", 7)])
def test_simulate_matches_the_cli_number_for_number(cli, tmp_path, policy, seed):
    path = short_scenario(tmp_path)
    out = tmp_path / "run"
    cli("simulate", path, "--policy", policy, "--seed", seed, "-o", out)
    got = coopnav.simulate(coopnav.Scenario.load(path), policy=policy, seed=seed)

    assert got["summary"] == read_json(out / "summary.json")
    want = read_csv(out / "timeseries.csv")
    ts = got["timeseries"]
    assert set(ts) == set(want)
    for name, column in ts.items():
        np.testing.assert_array_equal(column, np.array(floats(want[name])), err_msg=name)
    comms = read_csv(out / "comms.csv")
    np.testing.assert_array_equal(got["comms"]["t"], floats(comms["t"]))
    assert got["comms"]["direction"] == comms["direction"]
    assert [str(v).lower() for v in got["comms"]["received"]] == comms["received"]


def test_the_embedded_default_mission_matches_the_cli(cli, tmp_path):
    out = tmp_path / "run"
    cli("simulate", "-o", out)
    got = coopnav.simulate(coopnav.Scenario.example())
    assert got["summary"] == read_json(out / "summary.json")


def test_monte_carlo_matches_the_cli_table_and_json(cli, tmp_path):
    path = short_scenario(tmp_path, duration_s=300.0)
    table = cli("simulate", path, "--runs", 3, "--policy", "planner,zigzag")
    got = coopnav.monte_carlo(coopnav.Scenario.load(path), ["planner", "zigzag"], 3)
    assert got.pop("table") == table
    printed = json.loads(cli("simulate", path, "--runs", 3, "--policy", "planner,zigzag", "--json"))
    assert got == printed


def test_a_long_simulation_releases_the_gil(tmp_path):
    """While simulate runs in one thread, another Python thread keeps counting."""
    # Six hours: long enough to tell even on a quiet machine (the engine does an hour in ~0.05 s).
    scenario = coopnav.Scenario.load(short_scenario(tmp_path, duration_s=6 * 3600.0, n_auvs=5))
    counts = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
            if n % 1000 == 0:
                counts.append(time.perf_counter())
        counts.append(time.perf_counter())

    counter = threading.Thread(target=count)
    counter.start()
    t0 = time.perf_counter()
    coopnav.simulate(scenario)
    t1 = time.perf_counter()
    done.set()
    counter.join()
    during = [c for c in counts if t0 <= c <= t1]
    assert t1 - t0 > 0.2, "the mission is too short to tell"
    # With the GIL held the counter would stall for the whole call: ticks must span it.
    assert len(during) > 10 and during[-1] - during[0] > 0.5 * (t1 - t0)


def test_bad_scenario_fields_raise_value_error_naming_them(cli, tmp_path):
    d = coopnav.Scenario.example().to_dict()
    d["duration_s"] = -5.0
    with pytest.raises(ValueError, match=r"field duration_s = -5: allowed") as err:
        coopnav.Scenario.from_dict(d)
    assert "<dict>" in str(err.value)
    text = coopnav.Scenario.example_toml().replace("duration_s = 3600.0", "duration_s = -5.0")
    assert "duration_s = -5.0" in text
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        coopnav.Scenario.load(path)
    # The same message the CLI prints after "Error: ".
    done = __import__("subprocess").run([cli.exe, "simulate", str(path), "-o", str(tmp_path / "x")],
                                        capture_output=True, text=True)
    assert done.returncode != 0
    assert done.stderr.strip() == f"Error: {err.value}"


def test_unknown_fields_policies_and_kinds_are_named(tmp_path):
    d = coopnav.Scenario.example().to_dict()
    d["fleet"]["n_auvz"] = 3
    with pytest.raises(ValueError, match="n_auvz"):
        coopnav.Scenario.from_dict(d)
    with pytest.raises(ValueError, match="unknown policy 'wander'"):
        coopnav.simulate(coopnav.Scenario.example(), policy="wander")
    with pytest.raises(ValueError, match="unknown scenario kind 'hbl'"):
        coopnav.Scenario.example("hbl")
    with pytest.raises(ValueError, match="runs must be at least 1"):
        coopnav.monte_carlo(coopnav.Scenario.example(), ["planner"], 0)


def test_a_scenario_round_trips_through_dict_and_toml():
    sc = coopnav.Scenario.example()
    again = coopnav.Scenario.from_toml(sc.to_toml())
    assert again.to_dict() == sc.to_dict() == coopnav.Scenario.from_dict(sc.to_dict()).to_dict()
    assert sc.source == "<embedded default>" and again.source == "<string>"


def test_ctrl_c_stops_a_long_monte_carlo(tmp_path):
    """SIGINT half a second into a Monte Carlo that takes far longer raises KeyboardInterrupt at
    once (run in a child interpreter, so the signal cannot reach pytest itself)."""
    script = tmp_path / "interrupt.py"
    script.write_text(
        "import os, signal, threading, time\n"
        "import coopnav\n"
        "# A child of a non-interactive shell's background job starts with SIGINT ignored.\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "sc = coopnav.Scenario.example()\n"
        "threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()\n"
        "t0 = time.perf_counter()\n"
        "try:\n"
        "    coopnav.monte_carlo(sc, ['planner', 'centroid'], 200)\n"
        "    print('finished')\n"
        "except KeyboardInterrupt:\n"
        "    print(f'interrupted after {time.perf_counter() - t0:.2f} s')\n"
    )
    done = __import__("subprocess").run([__import__("sys").executable, str(script)], capture_output=True, text=True,
                                        timeout=120)
    assert done.stdout.startswith("interrupted after"), done.stdout + done.stderr
    # 400 one-hour missions take minutes; stopping must take about one engine step.
    assert float(done.stdout.split()[2]) < 5.0, done.stdout
