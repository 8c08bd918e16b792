"""Gains: validation, per-row expansion and the explicit-Euler stability bound.

With per-row gains ``K`` the discrete error map of law (9)/(23) is
``e_{k+1} ~ (I - dt J J^T K) e_k`` (plus the reference's motion), stable when
``dt lambda_max(K^{1/2} J J^T K^{1/2}) < 2`` (docs/method.md, "Implementation
notes"); ``alpha = 1/dt`` is the paper's optimal scalar choice.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from clik.errors import InputError


def row_gains(
    gain: float | Sequence[float] | np.ndarray, m: int, field: str = "gain"
) -> np.ndarray:
    """Expand a scalar or per-row gain to an array of ``m`` positive finite values [1/s]."""
    try:
        K = np.array(gain, dtype=float, ndmin=1)
    except (TypeError, ValueError):
        raise InputError(field, f"a positive number or {m} positive numbers [1/s]", gain) from None
    if K.ndim != 1 or K.shape[0] not in (1, m):
        raise InputError(field, f"a positive number or {m} positive numbers [1/s]", gain)
    if not np.all(np.isfinite(K)) or np.any(K <= 0.0):
        raise InputError(field, "positive finite values [1/s]", gain)
    return np.broadcast_to(K, (m,)).copy()


def stability_margin(J: np.ndarray, K: np.ndarray, dt: float) -> float:
    """``dt lambda_max(K^{1/2} J J^T K^{1/2})``: explicit Euler is stable below 2.

    Infinite when ``J J^T`` is not finite (its eigenvalues would not converge): no bound
    holds, and the run's own non-finite check stops it ``diverged``.
    """
    s = np.sqrt(K)[:, None] * J
    with np.errstate(over="ignore", invalid="ignore"):
        A = s @ s.T
    if not np.isfinite(A).all():
        return math.inf
    return float(dt * np.linalg.eigvalsh(A)[-1])
