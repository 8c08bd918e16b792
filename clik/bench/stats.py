"""Summary statistics of repeated measurements, and ratios that tolerate missing figures."""

from __future__ import annotations

import numpy as np


def stats(values: list[float] | np.ndarray) -> dict[str, float | int]:
    """Median, p10, p90, mean, min and count of ``values``.

    Args:
        values: The measurements (at least one).

    Returns:
        ``{"median", "p10", "p90", "mean", "min", "n"}``.
    """
    arr = np.asarray(values, dtype=float)
    p10, median, p90 = np.percentile(arr, [10.0, 50.0, 90.0])
    return {
        "median": float(median),
        "p10": float(p10),
        "p90": float(p90),
        "mean": float(arr.mean()),
        "min": float(arr.min()),
        "n": int(arr.size),
    }


def ratio(num: float | None, den: float | None) -> float | None:
    """``num / den``, or None when either is missing or ``den`` is not positive.

    Args:
        num: Numerator (e.g. pink's median).
        den: Denominator (e.g. clik's median).
    """
    if num is None or den is None or den <= 0.0:
        return None
    return float(num) / float(den)
