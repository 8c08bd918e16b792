"""The results of a sweep on disk: one row per run, appended as runs finish, read back by id.

Layout of the output folder ``DIR``:

- ``DIR/sweep.json``: the manifest: sweep file, base scenario, parameters,
  number of runs, the sweep's fingerprint, and which table format is used.
  Written before any result. A rerun of the *same* sweep (same fingerprint)
  resumes: rows already present are kept and their runs skipped.
- ``DIR/results.parquet/``: a Parquet *dataset folder*. Every flush writes
  one new part file (``part-<n>-<uuid>.parquet``) into it, first under a
  hidden temporary name then renamed, so a crash leaves whole part files
  only; readers (``pyarrow.parquet.read_table(DIR / "results.parquet")``,
  pandas, DuckDB, Dask) read the folder as one table and skip hidden files.
  When a sweep completes, the parts are compacted into one file (a crash
  during that leaves duplicate rows, which readers here drop by ``run_id``
  and the next run of the sweep compacts away).
- ``DIR/results.csv`` instead, with ``fmt="csv"`` (``clik sweep --format
  csv``): a header, then rows appended with ``flush`` and ``fsync``;
  a partial last line (a crash mid-write) is cut off when the file is opened.
  Parameters, lists and dicts are written as JSON text.
- ``DIR/runs/<run_id>/summary.json`` and ``trajectory.npz`` with
  ``--keep-trajectories`` (written before the run's row).

Only the client (the process that runs the sweep) writes here, and it writes
each run id at most once.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import uuid
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clik.errors import InputError, OutputExistsError
from clik.outputs.io import write_json
from clik.sweep.cells import column_types, csv_text
from clik.sweep.parquet_parts import dedup, part_files, read_parquet, write_part

MANIFEST = "sweep.json"
PARQUET = "results.parquet"
CSV = "results.csv"
RUNS = "runs"

COLUMNS: tuple[tuple[str, str], ...] = (
    ("status", "string"),
    ("reason", "string"),
    ("error", "string"),
    ("steps", "int"),
    ("wall_time_s", "float"),
    ("run_wall_time_s", "float"),
    ("max_task_error", "float"),
    ("final_task_error", "float"),
    ("max_orientation_error", "float"),
    ("min_obstacle_distance", "float"),
    ("min_obstacle_distance_by_obstacle", "string"),
    ("event_count", "int"),
    ("events", "string"),
    ("joint_min", "floats"),
    ("joint_max", "floats"),
    ("warnings", "string"),
    ("worker", "string"),
    ("finished_at", "float"),
)
"""Columns after ``run_id`` and the parameters, with their types.

``status`` is the run's (``completed``, ``deadlock``, ``diverged``,
``violated``) or ``error`` for a run that raised (``error`` then holds the message).
``wall_time_s`` is the tracking loop's, ``run_wall_time_s`` the whole task's
(scenario, build, run) on the worker [s]. ``events`` and
``min_obstacle_distance_by_obstacle`` are JSON text.
"""


class SweepOutputExistsError(OutputExistsError):
    """The output folder holds something else than this sweep's results, and no ``force``."""

    def __init__(self, path: str | Path, what: str) -> None:
        super().__init__(path)
        self.what = what
        self.args = (
            f"output folder {path} {what}; rerun the same sweep to resume, or pass --force to "
            "start over (removes its sweep.json, results and runs/)",
        )


@dataclass
class ResultStore:
    """Appends result rows of one sweep to ``DIR`` and knows which run ids are there.

    Attributes:
        out: The output folder.
        parameters: The sweep's key paths (the parameter columns, in order).
        fmt: ``"parquet"`` or ``"csv"``.
        json_parameters: Parameters stored as JSON text (always for CSV; in
            Parquet those whose values have no simple column type).
        ids: Run ids present.
    """

    out: Path
    parameters: list[str]
    fmt: str
    json_parameters: list[str]
    param_types: dict[str, str] = field(default_factory=dict)
    ids: set[str] = field(default_factory=set)
    _parts: int = 0

    @property
    def path(self) -> Path:
        """``DIR/results.parquet`` (a folder) or ``DIR/results.csv``."""
        return self.out / (PARQUET if self.fmt == "parquet" else CSV)

    @property
    def columns(self) -> list[str]:
        """Every column, in order."""
        return ["run_id", *self.parameters, *(c for c, _ in COLUMNS)]

    # -- opening -------------------------------------------------------------------

    @classmethod
    def open(
        cls,
        out: Path,
        manifest: dict[str, Any],
        param_values: dict[str, list[Any]],
        force: bool = False,
        fmt: str = "auto",
    ) -> ResultStore:
        """Open ``out`` for a sweep: a fresh folder, or resume the same sweep.

        Args:
            out: The output folder (created).
            manifest: The sweep's manifest (``fingerprint``, ``parameters``, ...).
            param_values: Every value each parameter takes (to type its column).
            force: Start over in a folder holding something else.
            fmt: ``"parquet"``, ``"csv"`` or ``"auto"`` (Parquet). Resuming keeps the
                folder's format, whatever ``fmt``.

        Raises:
            SweepOutputExistsError: ``out`` is not empty and holds no results of this
                sweep, and ``force`` is false.
        """
        out = Path(out)
        if fmt not in ("auto", "parquet", "csv"):
            raise InputError("format", "'auto', 'parquet' or 'csv'", fmt)
        same = check_folder(out, manifest["fingerprint"], force)
        old = _read_manifest(out)
        if out.exists() and not same:
            clear(out)  # check_folder let it through: empty, or force
        out.mkdir(parents=True, exist_ok=True)
        if same:
            assert old is not None
            fmt = old["format"]
            json_parameters = list(old.get("json_parameters", []))
            param_types = dict(old.get("param_types", {}))
        else:
            if fmt == "auto":
                fmt = "parquet"
            param_types = column_types(param_values) if fmt == "parquet" else {}
            json_parameters = [p for p in param_values if param_types.get(p, "json") == "json"]
            write_json(
                out / MANIFEST,
                {
                    **manifest,
                    "format": fmt,
                    "results": PARQUET if fmt == "parquet" else CSV,
                    "json_parameters": json_parameters,
                    "param_types": param_types,
                },
            )
        store = cls(out, list(manifest["parameters"]), fmt, json_parameters, param_types)
        store._load_ids()
        return store

    def _load_ids(self) -> None:
        if self.fmt == "parquet":
            self.path.mkdir(exist_ok=True)
            parts = part_files(self.path)
            self._parts = len(parts)
            table = read_parquet(self.path, ["run_id"])
            ids = [] if table is None else table.column("run_id").to_pylist()
            self.ids = set(ids)
            if len(ids) != len(self.ids):  # a compaction was interrupted: finish it
                self.compact()
        else:
            _repair_csv(self.path)
            if not self.path.exists():
                with open(self.path, "w", newline="", encoding="utf-8") as f:
                    csv.writer(f).writerow(self.columns)
                    f.flush()
                    os.fsync(f.fileno())
            with open(self.path, newline="", encoding="utf-8") as f:
                self.ids = {row["run_id"] for row in csv.DictReader(f)}

    # -- writing -------------------------------------------------------------------

    def append(self, rows: Iterable[dict[str, Any]]) -> int:
        """Write rows whose ids are not present yet (one part file, or appended lines).

        Returns:
            The number of rows written.
        """
        fresh: dict[str, dict[str, Any]] = {}
        for row in rows:
            if row["run_id"] not in self.ids:
                fresh.setdefault(row["run_id"], row)
        if not fresh:
            return 0
        if self.fmt == "parquet":
            self._append_parquet(list(fresh.values()))
        else:
            self._append_csv(list(fresh.values()))
        self.ids.update(fresh)  # only once they are on disk
        return len(fresh)

    def _cell(self, column: str, value: Any) -> Any:
        if column in self.json_parameters:
            return json.dumps(value)
        return value

    def _append_parquet(self, rows: list[dict[str, Any]]) -> None:
        import pyarrow as pa

        schema = self.schema()
        data = {c: [self._cell(c, r.get(c)) for r in rows] for c in self.columns}
        table = pa.Table.from_pydict(data, schema=schema)
        self._parts += 1
        name = f"part-{self._parts:06d}-{uuid.uuid4().hex[:8]}.parquet"
        write_part(table, self.path / name)

    def _append_csv(self, rows: list[dict[str, Any]]) -> None:
        size = self.path.stat().st_size
        try:
            with open(self.path, "a", newline="", encoding="utf-8") as f:
                writer = csv.writer(f)
                for row in rows:
                    cells = [csv_text(row.get(c), c in self.parameters) for c in self.columns]
                    writer.writerow(cells)
                f.flush()
                os.fsync(f.fileno())
        except BaseException:
            os.truncate(self.path, size)  # all the batch or none of it
            raise

    def compact(self) -> None:
        """Rewrite a Parquet dataset folder as one part file (rows deduplicated by id)."""
        if self.fmt != "parquet":
            return
        parts = part_files(self.path)
        table = read_parquet(self.path)
        if table is None or (len(parts) <= 1 and table.num_rows == len(self.ids)):
            return
        table = dedup(table)
        name = f"part-{len(parts) + 1:06d}-{uuid.uuid4().hex[:8]}.parquet"
        write_part(table, self.path / name)
        for part in parts:
            part.unlink()
        self._parts = 1

    def schema(self) -> Any:
        """The Parquet schema of the table."""
        import pyarrow as pa

        kinds = {
            "string": pa.string(),
            "int": pa.int64(),
            "float": pa.float64(),
            "floats": pa.list_(pa.float64()),
            "bool": pa.bool_(),
            "ints": pa.list_(pa.int64()),
            "json": pa.string(),
        }
        fields = [pa.field("run_id", pa.string(), nullable=False)]
        fields += [pa.field(p, kinds[self.param_types.get(p, "json")]) for p in self.parameters]
        fields += [pa.field(c, kinds[k]) for c, k in COLUMNS]
        return pa.schema(fields)

    def write_run_files(self, run_id: str, summary: dict[str, Any], trajectory: bytes) -> Path:
        """``DIR/runs/<run_id>/summary.json`` and ``trajectory.npz`` (``--keep-trajectories``)."""
        from clik.outputs.io import atomic_write

        folder = self.out / RUNS / run_id
        folder.mkdir(parents=True, exist_ok=True)
        write_json(folder / "summary.json", summary)
        atomic_write(folder / "trajectory.npz", lambda f: f.write(trajectory))
        return folder


# -- the folder ------------------------------------------------------------------------


def check_folder(out: Path, fingerprint: str, force: bool = False) -> bool:
    """Whether ``out`` holds this sweep (resume); raises if it holds something else.

    Nothing is written: a missing or empty folder, or any folder with ``force``,
    passes (returns False).

    Raises:
        SweepOutputExistsError: ``out`` is a file, or a non-empty folder without this
            sweep's manifest, and ``force`` is false.
    """
    old = _read_manifest(out)
    if old is not None and old.get("fingerprint") == fingerprint:
        return True
    if out.exists() and not out.is_dir():
        raise SweepOutputExistsError(out, "is a file")
    if out.exists() and any(out.iterdir()) and not force:
        what = (
            "holds the results of another sweep"
            if old is not None
            else "exists already and holds no sweep results"
        )
        raise SweepOutputExistsError(out, what)
    return False


def read_manifest(out: str | Path) -> dict[str, Any] | None:
    """The manifest of a sweep output folder, or None."""
    return _read_manifest(Path(out))


def _read_manifest(out: Path) -> dict[str, Any] | None:
    try:
        data = json.loads((out / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and "fingerprint" in data else None


def clear(out: Path) -> None:
    """Remove a sweep's own outputs from ``out`` (manifest, results, runs/); keep the rest."""
    for name in (MANIFEST, CSV):
        (out / name).unlink(missing_ok=True)
    for name in (PARQUET, RUNS):
        if (out / name).is_dir():
            shutil.rmtree(out / name)


def _repair_csv(path: Path) -> None:
    """Cut a partial last line (a crash in the middle of a write)."""
    if not path.exists() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        f.seek(-1, os.SEEK_END)
        if f.read(1) == b"\n":
            return
        f.seek(0)
        data = f.read()
        f.seek(data.rfind(b"\n") + 1)
        f.truncate()
