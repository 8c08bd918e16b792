"""How values become cells of a sweep's results table, and back.

A parameter's Parquet column takes a simple type (``bool``, ``string``, ``int``,
``float``, ``ints``, ``floats``) when every value it takes has it, else JSON text
(:func:`column_types`); a CSV cell is text (:func:`csv_text`), read back by its
column's type (:func:`from_csv`).
"""

from __future__ import annotations

import json
from typing import Any


def column_types(values: dict[str, list[Any]]) -> dict[str, str]:
    """A simple column type per parameter (``float``, ``floats``, ...), else ``json``."""
    out = {}
    for name, vals in values.items():
        out[name] = _simple_type(vals)
    return out


def _simple_type(values: list[Any]) -> str:
    """The column type all of ``values`` share, else ``json``."""

    def number(v: Any) -> bool:
        return isinstance(v, int | float) and not isinstance(v, bool)

    if all(isinstance(v, bool) for v in values):
        return "bool"
    if all(isinstance(v, str) for v in values):
        return "string"
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return "int"
    if all(number(v) for v in values):
        return "float"
    if all(isinstance(v, list) and all(number(x) for x in v) for v in values):
        if all(isinstance(x, int) and not isinstance(x, bool) for v in values for x in v):
            return "ints"
        return "floats"
    return "json"


def csv_text(value: Any, as_json: bool) -> str:
    """A value as a CSV cell: JSON text for a parameter (``as_json``), a list or a dict."""
    if as_json:
        return json.dumps(value)
    if value is None:
        return ""
    if isinstance(value, list | dict):
        return json.dumps(value)
    if isinstance(value, float):
        return repr(value)
    return str(value).replace("\r", " ").replace("\n", " ")  # one physical line per row


def from_csv(text: str, kind: str) -> Any:
    """A CSV cell of a column of type ``kind`` (:data:`~clik.sweep.store.COLUMNS`) as a value."""
    if text == "":
        return None
    if kind == "int":
        return int(text)
    if kind == "float":
        return float(text)
    if kind == "floats":
        return json.loads(text)
    return text
