"""Navigation: post-processing against `coopnav hbl postprocess`, and the AUV EKF stepped from
Python reproducing the CLI's filtered track on a hand-written log."""

import math

import numpy as np
import pytest

import coopnav
from conftest import floats, read_csv, read_json

ESTIMATES = {  # estimates.csv column -> samples column (the bias is written in degrees there)
    "t": "t", "filt_e": "filt_e", "filt_n": "filt_n", "filt_sd_e": "filt_sd_e", "filt_sd_n": "filt_sd_n",
    "smooth_e": "smooth_e", "smooth_n": "smooth_n", "smooth_sd_e": "smooth_sd_e", "smooth_sd_n": "smooth_sd_n",
    "true_e": "true_e", "true_n": "true_n",
}


@pytest.fixture(scope="module")
def hbl_log(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("hbl") / "run"
    cli("hbl", "simulate", "-o", out)
    return out / "log.csv"


def compare_estimates(got, directory):
    want = read_csv(directory / "estimates.csv")
    for csv_name, name in ESTIMATES.items():
        np.testing.assert_array_equal(got["samples"][name], floats(want[csv_name]), err_msg=csv_name)
    bias = [math.degrees(b) for b in got["samples"]["smooth_heading_bias"]]
    np.testing.assert_array_equal(bias, floats(want["smooth_heading_bias_deg"]))


def test_postprocess_of_a_log_file_matches_the_cli(cli, hbl_log, tmp_path):
    cli("hbl", "postprocess", hbl_log, "-o", tmp_path / "post")
    got = coopnav.postprocess(str(hbl_log))
    compare_estimates(got, tmp_path / "post")
    want = read_json(tmp_path / "post" / "summary.json")
    assert all(got["summary"][k] == v for k, v in want.items() if k in got["summary"])


def test_postprocess_of_numpy_columns_matches_the_file(cli, hbl_log, tmp_path):
    config = 'smoother = "unscented"\nacoustic_time_offset_s = 0.0\n'
    (tmp_path / "pp.toml").write_text(config)
    cli("hbl", "postprocess", hbl_log, "--config", tmp_path / "pp.toml", "-o", tmp_path / "post")
    columns = read_csv(hbl_log)
    arrays = {k: np.array(floats(v)) for k, v in columns.items() if k not in ("kind", "src")}
    arrays["kind"], arrays["src"] = columns["kind"], columns["src"]
    got = coopnav.postprocess(arrays, config)
    compare_estimates(got, tmp_path / "post")


def hand_log():
    """A short log: init, speed and compass rows, two buoy fixes and the ranges sent from them."""
    rows = [(0.0, "init", "", 10.0, -20.0, 1.2, 60.0)]
    for i in range(1, 40):
        rows.append((i * 1.0, "speed", "", 1.2 + 0.01 * (i % 3), "", ""))
        rows.append((i * 1.0 + 0.5, "heading", "", 60.0 + 0.3 * (i % 5), "", ""))
    for t_tx, (e, n), travel in [(10.0, (300.0, 50.0), 0.1873), (25.0, (-100.0, 200.0), 0.1542)]:
        rows.append((t_tx, "buoy_fix", "", e, n, ""))
        rows.append((t_tx + travel, "range", 13, travel, "", ""))
    rows.sort(key=lambda r: r[0])
    text = "t,kind,src,v1,v2,v3,v4\n" + "".join(
        ",".join(repr(v) if isinstance(v, float) else str(v) for v in (*r, *[""] * (7 - len(r)))) + "\n"
        for r in rows
    )
    return rows, text


def test_the_auv_ekf_stepped_from_python_follows_the_cli_filter(cli, tmp_path):
    """Replays the log with AuvEkf calls in the order the post-processor documents (0.1 s
    prediction pieces, the buoy fix at the transmit time, range = c·travel time) and compares
    the filtered track with `coopnav hbl postprocess`'s. The post-processor's start variance
    (which widens p0 from the first ranges in a pre-pass) is off, so both filters start from the
    same p0."""
    rows, text = hand_log()
    (tmp_path / "log.csv").write_text(text)
    (tmp_path / "pp.toml").write_text("[start]\nwindow_s = 0.0\n")
    post = ("hbl", "postprocess", tmp_path / "log.csv", "--config", tmp_path / "pp.toml")
    cli(*post, "-o", tmp_path / "post")
    want = read_csv(tmp_path / "post" / "estimates.csv")
    filtered = {float(t): (float(e), float(n)) for t, e, n in zip(want["t"], want["filt_e"], want["filt_n"])}

    compass = lambda deg: math.radians(90.0 - deg)  # noqa: E731
    t0, _, _, e0, n0, s0, h0 = rows[0]
    ekf = coopnav.AuvEkf(t0, e0, n0, s0, compass(h0), params={"range_gate": {"max_nis": 10.83}})
    fixes = {r[0]: (r[3], r[4]) for r in rows if r[1] == "buoy_fix"}
    checked = 0
    for t, kind, src, v1, *_ in rows[1:]:
        while t - ekf.t > 1e-9:
            if not ekf.predict(min(ekf.t + 0.1, t)):
                break
        if kind == "speed":
            assert ekf.update_speed(v1) == "applied"
        elif kind == "heading":
            assert ekf.update_heading(compass(v1)) == "applied"
        elif kind == "range":
            e, n = fixes[round(t - v1, 6)]
            assert ekf.update_range(1500.0 * v1, v1, [e, n, 1.5]) == "applied"
        assert (ekf.state[0], ekf.state[1]) == filtered[ekf.t], f"t = {ekf.t}"
        checked += 1
    assert checked == len(rows) - 1
    assert ekf.covariance.shape == (5, 5) and np.all(np.linalg.eigvalsh(ekf.covariance) > 0)


def test_the_surface_ekf_dead_reckons_and_shrinks_on_updates():
    ekf = coopnav.SurfaceEkf(0.0, 0.0, 0.0, 2.0, math.radians(30.0), params="buoy")
    ekf.predict(10.0)
    x = ekf.state
    assert ekf.t == pytest.approx(10.0)
    np.testing.assert_allclose(x[:2], [20.0 * math.cos(math.radians(30.0)), 20.0 * math.sin(math.radians(30.0))],
                               rtol=1e-9)
    before = ekf.covariance[0, 0]
    assert ekf.update("east", x[0] + 0.5) == "applied"
    assert ekf.covariance[0, 0] < before and ekf.state[0] > x[0]


def test_bad_nav_input_raises_value_error_naming_the_field(tmp_path):
    with pytest.raises(ValueError, match="sigma_speed"):
        coopnav.AuvEkf(0.0, 0.0, 0.0, 1.0, 0.0, params={"sigma_speed": -1.0})
    with pytest.raises(ValueError, match="max_gap_s"):
        coopnav.postprocess({"t": [0.0], "kind": ["init"], "src": [""], "v1": [0], "v2": [0], "v3": [1], "v4": [0]},
                            {"max_gap_s": 0.0})
    with pytest.raises(ValueError, match="no column 'v4'"):
        coopnav.postprocess({"t": [0.0], "kind": ["init"], "src": [""], "v1": [0], "v2": [0], "v3": [1]})
    with pytest.raises(ValueError, match="kind 'up'"):
        coopnav.SurfaceEkf(0.0, 0.0, 0.0, 1.0, 0.0).update("up", 1.0)
