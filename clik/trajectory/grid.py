"""The time grid on which trajectories are sampled."""

from __future__ import annotations

import numpy as np

from clik.trajectory import _validate


def time_grid(duration: float, dt: float) -> np.ndarray:
    """Uniform sample times ``t_k = k dt`` for ``k = 0 .. N - 1``, ``N = round(duration / dt) + 1``.

    The last sample is ``duration`` up to rounding when ``dt`` divides it; otherwise
    it is the multiple of ``dt`` nearest to ``duration`` (trajectories hold their
    final value past their duration, so overshooting by less than ``dt / 2`` is harmless).

    Args:
        duration: Time span [s], >= 0.
        dt: Sampling period [s], > 0 (the paper uses 1 ms).

    Returns:
        Times of shape (N,) [s].

    Raises:
        InputError: ``dt`` not positive or ``duration`` negative (or not finite).
    """
    duration = _validate.nonnegative(duration, "duration", "[s]")
    dt = _validate.positive(dt, "dt", "[s]")
    n = round(duration / dt) + 1
    t = np.arange(n, dtype=float)
    t *= dt  # in place: a 10^8-sample grid is 800 MB, not twice that
    return t
