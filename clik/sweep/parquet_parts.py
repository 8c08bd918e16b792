"""A Parquet dataset folder written part by part, and read back as one table.

Every flush of a sweep writes one new part file into ``DIR/results.parquet/``
(:func:`write_part`): first under a hidden temporary name, synced, then renamed,
so a crash leaves whole part files only. The parts are read back in name order
as one table (:func:`read_parquet`), keeping the first row of each run id
(:func:`dedup`: a compaction interrupted after writing its file leaves
duplicates until the next one).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def part_files(folder: Path) -> list[Path]:
    """The part files of a dataset folder, in name order (hidden and ``_`` files skipped)."""
    return sorted(p for p in folder.glob("*.parquet") if not p.name.startswith((".", "_")))


def read_parquet(folder: Path, columns: list[str] | None = None) -> Any:
    """The part files of ``folder`` as one table (only ``columns`` if given), or None."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    parts = part_files(folder)
    if not parts:
        return None
    return pa.concat_tables([pq.read_table(p, columns=columns) for p in parts])


def dedup(table: Any) -> Any:
    """``table`` with the first row of each ``run_id`` only, in order."""
    ids = table.column("run_id").to_pylist()
    first: dict[str, int] = {}
    for i, run_id in enumerate(ids):
        first.setdefault(run_id, i)
    if len(first) == len(ids):
        return table
    return table.take(sorted(first.values()))


def write_part(table: Any, path: Path) -> None:
    """Write a Parquet file under a hidden temporary name, then rename it into place."""
    import pyarrow.parquet as pq

    tmp = path.with_name(f".{path.name}.tmp")
    try:
        pq.write_table(table, tmp)
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _fsync(path: Path) -> None:
    """Flush a file's bytes to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
