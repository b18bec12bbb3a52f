"""A sweep planned, run and merged by the CLI, its Parquet tables read with pandas, polars and
pyarrow and through ``coopnav.sweep``: the same rows and values as the CSV the merge writes beside
them, the types docs/sweeps.md gives, and the paired comparison's per-run means."""

import math

import pandas
import polars
import pyarrow.parquet as pq
import pytest

from coopnav import sweep
from conftest import floats, read_csv, read_json

SWEEP = """scenarios = ["default"]
policies = ["zigzag", "racetrack"]
runs = 2
[[axis]]
path = "fleet.n_auvs"
values = [2, 3]
[[axis]]
overlays = ["plain", "short"]
[overlay.plain]
[overlay.short]
comms = { max_range_m = 1500.0 }
"""


@pytest.fixture(scope="module")
def merged(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("sweep")
    (d / "s.toml").write_text(SWEEP)
    cli("sweep", "plan", d / "s.toml", "--shards", "2", "-o", d / "plan")
    cli("sweep", "run", d / "plan", "--all")
    cli("sweep", "merge", d / "plan")
    return d / "plan"


def test_pandas_polars_and_pyarrow_read_the_same_tables_as_the_csv(merged):
    for table, rows in (("runs", (2 + 3) * 2 * 2 * 2), ("fleet", 4 * 2 * 2)):
        csv = read_csv(merged / "merged" / f"{table}.csv")
        frames = {
            "pandas": pandas.read_parquet(merged / "merged" / f"{table}.parquet"),
            "polars": polars.read_parquet(merged / "merged" / f"{table}.parquet").to_pandas(),
            "pyarrow": pq.read_table(merged / "merged" / f"{table}.parquet").to_pandas(),
            "coopnav": sweep.read_table(merged, table),
        }
        for name, df in frames.items():
            assert list(df.columns) == list(csv), name
            assert len(df) == rows, name
            assert [int(v) for v in df["run_id"]] == [int(v) for v in csv["run_id"]], name
            got = [float(v) for v in df["error_mean_m"]]
            want = floats(csv["error_mean_m"])
            assert all(math.isclose(a, b, rel_tol=0, abs_tol=0) for a, b in zip(got, want)), name


def test_columns_have_the_documented_types(merged):
    schema = pq.read_schema(merged / "merged" / "runs.parquet")
    types = {f.name: str(f.type) for f in schema}
    assert types["run_id"] == "int64" and types["fleet.n_auvs"] == "int64"
    assert types["overlay"] == "string" and types["policy"] == "string" and types["seed"] == "string"
    assert types["error_mean_m"] == "double" and types["uplink_received"] == "int64"
    fleet = sweep.read_fleet(merged, engine="polars")
    assert isinstance(fleet, polars.DataFrame)
    assert fleet.schema["healthy"] == polars.Boolean
    assert sorted(set(fleet["overlay"].to_list())) == ["plain", "short"]
    assert fleet["error"].null_count() == len(fleet)


def test_the_fleet_table_holds_the_runs_the_comparison_is_over(merged):
    fleet = sweep.read_fleet(merged)
    report = read_json(merged / "merged" / "comparison.json")
    for cell in report["cells"]:
        for summary in cell["comparison"]["policies"]:
            rows = fleet[(fleet["cell"] == cell["cell"]) & (fleet["policy"] == summary["policy"])]
            assert list(rows["error_mean_m"]) == summary["runs"]
            assert int(rows["fleet.n_auvs"].iloc[0]) == cell["axes"]["fleet.n_auvs"]


def test_a_directory_without_a_merge_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="coopnav sweep merge"):
        sweep.read_runs(tmp_path)
    with pytest.raises(ValueError, match="allowed pandas, polars"):
        sweep.read_table(tmp_path, "runs", engine="spark")
