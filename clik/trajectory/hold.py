"""A constant target: hold a position, a rotation or both."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from clik.errors import InputError
from clik.trajectory import _validate
from clik.trajectory.base import Trajectory
from clik.trajectory.reference import Reference


class Hold(Trajectory):
    """Constant target with zero velocity.

    Useful alone (regulation to a point, where law (9) of docs/method.md has zero
    steady-state error) or as the orientation part of a
    :class:`~clik.trajectory.pose.PoseTrajectory` whose position moves; the
    default duration 0 then defers to the other part's duration.

    Args:
        position: Target position in the world frame, shape (3,) [m], or None.
        rotation: Target orientation (world <- frame), shape (3, 3), or None.
        duration: Duration [s], >= 0.

    Raises:
        InputError: Neither target given, or a bad argument.
    """

    def __init__(
        self,
        position: ArrayLike | None = None,
        rotation: ArrayLike | None = None,
        duration: float = 0.0,
    ) -> None:
        if position is None and rotation is None:
            raise InputError("position", "a position or a rotation to hold (or both)")
        self.position = None if position is None else _validate.vector3(position, "position", "[m]")
        self.rotation = None if rotation is None else _validate.rotation(rotation, "rotation")
        self.duration = _validate.nonnegative(duration, "duration", "[s]")

    def sample(self, t: np.ndarray) -> Reference:
        """The constant target at times ``t`` [s], with zero velocities."""
        times, _ = self._times(t)
        n = times.shape[0]
        position = velocity = rotation = angular_velocity = None
        if self.position is not None:
            position = np.broadcast_to(self.position, (n, 3))
            velocity = np.zeros((n, 3))
        if self.rotation is not None:
            rotation = np.broadcast_to(self.rotation, (n, 3, 3))
            angular_velocity = np.zeros((n, 3))
        return Reference(times, position, velocity, rotation, angular_velocity)
