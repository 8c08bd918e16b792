"""The sample times of an open run: ``t_k = t_0 + k dt`` with no last sample.

An offline run reads its times from its grid (:func:`clik.trajectory.time_grid`, an
array); a controller's session (:class:`clik.control.Controller`) has no end, so its
times are computed, as the compiled engine's ``Clock`` computes them (the same
operations in the same order: the two engines give the same times).
"""

from __future__ import annotations

import sys
from typing import overload

import numpy as np

OPEN = sys.maxsize
"""The sample count of an open run (a controller's session: no last sample)."""


class Clock:
    """Times ``t_k = t0 + k dt`` [s] for ``k >= 0``, indexed like a time grid.

    Args:
        dt: Sample time [s].
        t0: Time of sample 0 [s].
    """

    def __init__(self, dt: float, t0: float = 0.0) -> None:
        self.dt, self.t0 = float(dt), float(t0)
        self.shape = (OPEN,)

    @overload
    def __getitem__(self, k: int) -> float: ...
    @overload
    def __getitem__(self, k: np.ndarray) -> np.ndarray: ...
    def __getitem__(self, k: int | np.ndarray) -> float | np.ndarray:
        """``t0 + k dt`` of a sample index or an array of them."""
        if isinstance(k, np.ndarray):
            return self.t0 + k.astype(float) * self.dt
        return self.t0 + float(k) * self.dt
