r"""A joint-space reference ``q_d(t)`` for a posture task: held values or waypoints.

Between waypoints ``q_j`` at times ``t_j`` the joints move along the straight segment
with the quintic timing ``s(u) = 10 u^3 - 15 u^4 + 6 u^5``, ``u = (t - t_j) / (t_{j+1}
- t_j)``: position, velocity and acceleration continuous, at rest at each waypoint.
``qdot_d`` is its analytic derivative. One waypoint holds it (zero velocity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from clik.errors import InputError
from clik.trajectory import _validate
from clik.trajectory.base import Trajectory


@dataclass(frozen=True, eq=False)
class JointReference:
    """A joint-space reference sampled on a time grid.

    Attributes:
        t: Sample times (N,) [s].
        q: Joint values (N, n) [rad or m].
        qdot: Their velocities (N, n) [rad/s or m/s].
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray


class JointPath(Trajectory):
    """Joint values held, or moved through waypoints (the module's timing).

    Args:
        waypoints: One joint vector (n,) to hold, or waypoints (K, n) [rad or m].
        duration: Total time [s] (waypoints evenly spaced in it); default 0 for a hold.
        times: Waypoint times (K,) [s], increasing from 0 (instead of ``duration``).

    Raises:
        InputError: Non-finite values, a bad shape, or bad times (named).
    """

    def __init__(
        self,
        waypoints: ArrayLike,
        duration: float | None = None,
        times: ArrayLike | None = None,
    ) -> None:
        try:
            W = np.array(waypoints, dtype=float, ndmin=2)
        except (TypeError, ValueError):
            raise InputError(
                "waypoints", "joint values (n,) or waypoints (K, n)", waypoints
            ) from None
        if W.ndim != 2 or W.shape[1] == 0 or not np.isfinite(W).all():
            raise InputError("waypoints", "finite joint values (n,) or waypoints (K, n)", waypoints)
        K = W.shape[0]
        if times is not None:
            if duration is not None:
                raise InputError("duration", "either duration or times, not both", duration)
            T = np.array(times, dtype=float)
            if (
                T.shape != (K,)
                or not np.isfinite(T).all()
                or T[0] != 0.0
                or np.any(np.diff(T) <= 0)
            ):
                raise InputError("times", f"{K} increasing times [s] from 0", times)
        else:
            total = 0.0 if duration is None else _validate.nonnegative(duration, "duration", "[s]")
            if K > 1 and total <= 0.0:
                raise InputError(
                    "duration", "a positive time [s] to move through waypoints", duration
                )
            T = np.linspace(0.0, total, K)
        self.waypoints, self.times = W, T
        self.duration = float(T[-1])
        self.n = W.shape[1]

    def sample(self, t: np.ndarray) -> JointReference:  # type: ignore[override]
        """The joint values and velocities at times ``t`` [s] (clipped to the duration)."""
        times, tc = self._times(t)
        W, T = self.waypoints, self.times
        if W.shape[0] == 1:
            n = times.shape[0]
            return JointReference(times, np.repeat(W, n, axis=0), np.zeros((n, self.n)))
        j = np.clip(np.searchsorted(T, tc, side="right") - 1, 0, len(T) - 2)
        span = T[j + 1] - T[j]
        u = (tc - T[j]) / span
        s = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
        ds = 30.0 * u**2 * (1.0 - u) ** 2 / span
        step = W[j + 1] - W[j]
        return JointReference(times, W[j] + s[:, None] * step, ds[:, None] * step)

    def __repr__(self) -> str:
        return f"JointPath(waypoints={self.waypoints.shape[0]}, duration={self.duration:.6g})"
