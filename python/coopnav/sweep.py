"""A sweep's results as DataFrames: the Parquet tables ``coopnav sweep merge`` writes.

``read_runs(dir)`` is one row per run and survey AUV, ``read_fleet(dir)`` one row per run; the
columns are documented in docs/sweeps.md. ``dir`` is the sweep's plan directory (its ``merged/``
is read) or a merge's output directory itself. ``engine="pandas"`` (the default) returns a
``pandas.DataFrame``, ``engine="polars"`` a ``polars.DataFrame``; each needs its package (and
pandas needs pyarrow to read Parquet). Pure Python: the compiled extension is not involved.
"""

from pathlib import Path

__all__ = ["merged_dir", "read_fleet", "read_runs", "read_table"]

TABLES = ("runs", "fleet")
ENGINES = ("pandas", "polars")


def merged_dir(path):
    """The directory holding the merged tables: ``path`` itself, or ``path/merged``."""
    path = Path(path)
    if (path / "runs.parquet").is_file():
        return path
    merged = path / "merged"
    if (merged / "runs.parquet").is_file():
        return merged
    raise FileNotFoundError(
        f"{path} holds no merged sweep (runs.parquet): run `coopnav sweep merge {path}` first"
    )


def read_table(path, table, engine="pandas"):
    """The sweep table ``table`` ("runs" or "fleet") of ``path`` as a DataFrame of ``engine``."""
    if table not in TABLES:
        raise ValueError(f"table {table!r}: allowed {', '.join(TABLES)}")
    if engine not in ENGINES:
        raise ValueError(f"engine {engine!r}: allowed {', '.join(ENGINES)}")
    file = merged_dir(path) / f"{table}.parquet"
    if engine == "pandas":
        import pandas

        return pandas.read_parquet(file)
    import polars

    return polars.read_parquet(file)


def read_runs(path, engine="pandas"):
    """One row per run and survey AUV (docs/sweeps.md)."""
    return read_table(path, "runs", engine)


def read_fleet(path, engine="pandas"):
    """One row per run (docs/sweeps.md)."""
    return read_table(path, "fleet", engine)
