"""``clik sweep --table DIR``: a sweep's results as CSV text, without pandas.

A sweep writes its table as Parquet (a folder of parts, ``results.parquet``)
or CSV (``results.csv``); :func:`clik.sweep.results.read_results` reads both
with pyarrow or the ``csv`` module. :func:`results_csv` turns those rows into
CSV text, one row per run, lists and tables as JSON, missing values empty, for
a terminal, a spreadsheet or ``pandas.read_csv``.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

from clik.errors import InputError
from clik.sweep.results import read_results


def _cell(value: Any) -> str:
    """A value as CSV cell text: None empty, lists and dicts as JSON, numbers as ``repr``."""
    if value is None:
        return ""
    if isinstance(value, list | dict):
        return json.dumps(value)
    return str(value)


def results_csv(out: str | Path) -> str:
    """The results table of the sweep output folder ``out`` as CSV text (header first).

    Args:
        out: The folder given as ``clik sweep --out``.

    Raises:
        InputError: ``out`` is not a sweep's output folder.
    """
    try:
        rows = read_results(out)
    except FileNotFoundError:
        raise InputError("--table", "a sweep's output folder (its --out)", str(out)) from None
    columns: dict[str, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(list(columns))
    for row in rows:
        writer.writerow([_cell(row.get(c)) for c in columns])
    return text.getvalue()
