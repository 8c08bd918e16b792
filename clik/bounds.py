"""Budgets that bound what one input may ask of clik, and the test of a number's range."""

from __future__ import annotations

import math

MAX_COORDINATE = 1000.0
"""Largest absolute position or size [m] (1 km): a URDF origin, a mesh's scaled vertices,
a scenario's positions, lengths and thresholds."""

SCALE_RANGE = (1e-6, 1e6)
"""Accepted range of the absolute value of each mesh scale factor (URDF and scenario)."""

MAX_STEPS = 100_000_000
"""Largest run, ``(duration + settle) / dt + 1`` samples (about 15 minutes at 8 us per
step): a typo in ``dt`` fails at once, not as a run that never ends or an allocation
that cannot succeed."""

MAX_RECORD_BYTES = 512 * 2**20
"""Largest memory for a run's record (the arrays of its kept samples) [bytes]: a long run
keeps every ``record_every``-th sample within it (a million samples of a 7-joint arm
with obstacles take about 400 MB)."""

MAX_ITERATIONS = 2**31 - 1
"""Largest ``max_iterations`` of a solve: the engine counts iterations in a C ``int``."""

MAX_RESTARTS = 100_000
"""Largest ``restarts`` of a solve: their start configurations are drawn at once, an
array of ``restarts x nq`` doubles (5.6 MB for the Panda's 7 joints)."""


def real(value: object) -> float:
    """``value`` as a float when it is a number (not a bool nor a string), else NaN.

    A NumPy scalar or 0-d array is a number; an integer beyond a double is infinite.
    """
    if isinstance(value, bool | str | bytes):
        return math.nan
    try:
        return float(value)  # type: ignore[arg-type]
    except OverflowError:  # an int beyond a double
        return math.inf if value > 0 else -math.inf  # type: ignore[operator]
    except (TypeError, ValueError):
        return math.nan


def in_range(value: object, low: float, high: float = math.inf, strict: bool = False) -> bool:
    """``value`` is a finite number in ``[low, high]`` (``(low, high]`` when ``strict``)."""
    number = real(value)
    return math.isfinite(number) and (number > low if strict else number >= low) and number <= high
