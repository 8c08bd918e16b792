"""A sweep's results read back: its rows (one per run id, parameters decoded), its statuses.

Both table formats of :mod:`clik.sweep.store`, Parquet and CSV; a run written
twice (by an interrupted compaction) counts once.
"""

from __future__ import annotations

import csv
import json
from collections import Counter
from pathlib import Path
from typing import Any

from clik.sweep.cells import from_csv
from clik.sweep.parquet_parts import dedup, read_parquet
from clik.sweep.store import COLUMNS, CSV, MANIFEST, PARQUET, read_manifest


def _manifest_of(out: Path) -> dict[str, Any]:
    """The manifest of a sweep's output folder.

    Raises:
        FileNotFoundError: ``out`` holds no sweep manifest.
    """
    manifest = read_manifest(out)
    if manifest is None:
        raise FileNotFoundError(f"{out / MANIFEST}: not a sweep output folder")
    return manifest


def read_results(out: str | Path) -> list[dict[str, Any]]:
    """The rows of a sweep's output folder, one per run id, parameters decoded.

    Works for both formats; lists come back as lists, missing numbers as None.

    Raises:
        FileNotFoundError: ``out`` holds no sweep manifest.
    """
    out = Path(out)
    manifest = _manifest_of(out)
    if manifest["format"] == "parquet":
        return _parquet_rows(out / PARQUET, set(manifest.get("json_parameters", [])))
    return _csv_rows(out / CSV, list(manifest["parameters"]))


def _parquet_rows(folder: Path, json_parameters: set[str]) -> list[dict[str, Any]]:
    """The rows of a Parquet dataset folder, one per run id, JSON parameters decoded."""
    table = read_parquet(folder)
    rows: list[dict[str, Any]] = [] if table is None else dedup(table).to_pylist()
    for row in rows:
        for p in json_parameters:
            if row.get(p) is not None:
                row[p] = json.loads(row[p])
    return rows


def _csv_rows(path: Path, parameters: list[str]) -> list[dict[str, Any]]:
    """The rows of a CSV results table, one per run id (the first), cells typed."""
    types = dict(COLUMNS)
    rows: list[dict[str, Any]] = []
    seen: set[str] = set()
    with open(path, newline="", encoding="utf-8") as f:
        for raw in csv.DictReader(f):
            if raw["run_id"] in seen:
                continue
            seen.add(raw["run_id"])
            row: dict[str, Any] = {"run_id": raw["run_id"]}
            for p in parameters:
                row[p] = json.loads(raw[p]) if raw[p] != "" else None
            for c, kind in types.items():
                row[c] = from_csv(raw.get(c, ""), kind)
            rows.append(row)
    return rows


def read_statuses(out: str | Path) -> Counter[str]:
    """How many runs of a sweep's output folder have each ``status`` (one per run id).

    Reads only the ``run_id`` and ``status`` columns (a run written twice, by an
    interrupted compaction, counts once).

    Raises:
        FileNotFoundError: ``out`` holds no sweep manifest.
    """
    out = Path(out)
    manifest = _manifest_of(out)
    status: dict[str, str] = {}
    if manifest["format"] == "parquet":
        table = read_parquet(out / PARQUET, ["run_id", "status"])
        if table is not None:
            pairs = zip(
                table.column("run_id").to_pylist(), table.column("status").to_pylist(), strict=True
            )
            for run_id, value in pairs:
                status.setdefault(run_id, value)
    elif (out / CSV).exists():
        with open(out / CSV, newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                status.setdefault(row["run_id"], row["status"])
    return Counter(status.values())
