"""A figure as a ``bench.md`` table cell."""

from __future__ import annotations

from typing import Any

import numpy as np


def fmt(value: Any, digits: int = 3) -> str:
    """A table cell: ``-`` for None, yes / **no** for booleans, ``digits`` significant digits.

    Args:
        value: The figure.
        digits: Significant digits of a float.
    """
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "**no**"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{value:.{digits}g}"
    return str(value)
