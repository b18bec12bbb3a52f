"""Transmission loss and packet success against `coopnav channel`, BELLHOP when installed."""

import numpy as np
import pytest

import coopnav
from conftest import floats, read_csv


def channel_table(cli, tmp_path, *args):
    cli("channel", *args, "-o", tmp_path / "ch")
    return {k: np.array(floats(v)) for k, v in read_csv(tmp_path / "ch" / "channel.csv").items()}


@pytest.mark.parametrize("k, noise_db", [(2.0, 0.0), (1.5, 6.0)])
def test_analytic_tl_and_success_match_the_cli(cli, tmp_path, k, noise_db):
    want = channel_table(cli, tmp_path, "--k", k, "--noise-db", noise_db)
    ranges = want["range_m"]
    tl = coopnav.TransmissionLoss.analytic(k=k).field([0.0, 0.0, 20.0], 0.0, ranges, np.array([20.0]))
    np.testing.assert_array_equal(tl[0], want["tl_db"])
    for rate in (0, 1, 4, 5):
        np.testing.assert_array_equal(coopnav.p_success(rate, tl[0], noise_db=noise_db), want[f"p_rate{rate}"])


def test_between_and_field_agree_and_success_keeps_the_shape():
    tl = coopnav.TransmissionLoss.analytic()
    rx = np.array([[300.0, 400.0, 20.0], [0.0, 1000.0, 20.0]])
    direct = tl.between([0.0, 0.0, 20.0], rx)
    along = tl.field([0.0, 0.0, 20.0], 0.0, np.array([500.0, 1000.0]), np.array([20.0]))[0]
    np.testing.assert_allclose(direct, along, rtol=1e-12)
    p = coopnav.p_success(1, np.array([[30.0, 70.0], [85.0, 200.0]]))
    assert p.shape == (2, 2) and p[0, 0] >= p[0, 1] >= p[1, 0] >= p[1, 1]
    assert isinstance(coopnav.p_success(0, 45.0), float)


def test_a_cached_grid_reproduces_its_provider_on_the_grid_nodes():
    analytic = coopnav.TransmissionLoss.analytic(k=2.0)
    grid = {"bearings": 8, "range_step": 50.0, "max_range": 2000.0, "depth_step": 10.0, "max_depth": 100.0}
    cached = analytic.cached([0.0, 0.0, 10.0], grid)
    ranges, depths = np.arange(50.0, 2001.0, 50.0), np.arange(10.0, 101.0, 10.0)
    exact = analytic.field([0.0, 0.0, 10.0], 45.0, ranges, depths)
    # Stored as f32: equal to single precision on the nodes of a stored bearing.
    np.testing.assert_allclose(cached.field([0.0, 0.0, 10.0], 45.0, ranges, depths), exact, rtol=1e-6)


def test_bad_channel_input_raises_value_error():
    with pytest.raises(ValueError, match="WHOI rate 7 does not exist"):
        coopnav.p_success(7, [50.0])
    with pytest.raises(ValueError, match="field noise_db = -1: allowed a finite number >= 0"):
        coopnav.p_success(1, [50.0], noise_db=-1.0)
    with pytest.raises(ValueError, match="bearings"):
        coopnav.TransmissionLoss.analytic().cached([0, 0, 10], {"bearings": 0, "range_step": 1.0,
                                                               "max_range": 10.0, "depth_step": 1.0,
                                                               "max_depth": 10.0})


def test_bellhop_matches_the_cli_when_installed(cli, tmp_path):
    try:
        bellhop = coopnav.TransmissionLoss.bellhop()
    except ValueError as e:
        pytest.skip(f"BELLHOP is not installed ({e}); scripts/install-bellhop.sh installs it")
    want = channel_table(cli, tmp_path, "--model", "bellhop", "--max-range", 1000, "--step", 100)
    tl = bellhop.field([0.0, 0.0, 20.0], 0.0, want["range_m"], np.array([20.0]))
    np.testing.assert_array_equal(tl[0], want["tl_db"])
