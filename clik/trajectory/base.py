"""The trajectory interface: a duration and a vectorised ``sample``."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from clik.trajectory import _validate
from clik.trajectory.reference import Reference


class Trajectory(ABC):
    """A desired task trajectory over ``[0, duration]``.

    Subclasses evaluate the whole time grid at once (numpy, no Python loop
    over samples). Times outside ``[0, duration]`` are clipped: the
    trajectory holds its initial value before 0 and its final value after
    ``duration``, with zero velocity there.

    Attributes:
        duration: Length of the motion [s].
    """

    duration: float

    @abstractmethod
    def sample(self, t: np.ndarray) -> Reference:
        """Sample the trajectory.

        Args:
            t: Sample times, shape (N,) [s]; a scalar gives one sample.
                Values are clipped to ``[0, duration]``.

        Returns:
            The reference at the given times (``Reference.t`` is ``t`` as given,
            not clipped).
        """

    def _times(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Check sample times and clip them to ``[0, duration]``.

        Returns:
            ``(t, t_clipped)``, both float arrays of shape (N,) [s].
        """
        times = _validate.times(t)
        return times, np.clip(times, 0.0, self.duration)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(duration={self.duration:.6g})"
