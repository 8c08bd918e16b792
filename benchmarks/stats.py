"""Summary statistics of repeated measurements, and ratios that tolerate missing figures."""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmarks.config import DT


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


def line_timing(
    description: str, samples: list[float], count_key: str, count: int
) -> dict[str, Any]:
    """A timed line's entry of ``bench.json``: its description and timing statistics [us].

    Args:
        description: The line in one sentence.
        samples: One mean per run [us per step or tick].
        count_key: The key of the count (``steps_per_run``, ``ticks_per_run``).
        count: Steps or ticks per run.
    """
    s = stats(samples)
    return {
        "description": description,
        "median_us": s["median"],
        "p10_us": s["p10"],
        "p90_us": s["p90"],
        "min_us": s["min"],
        "runs": s["n"],
        count_key: count,
        "realtime_factor": DT / (1e-6 * s["median"]),
    }
