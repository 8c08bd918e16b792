r"""Orientation interpolation along the geodesic of SO(3) (slerp)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from clik.trajectory import _validate
from clik.trajectory.base import Trajectory
from clik.trajectory.profile import TrapezoidalProfile
from clik.trajectory.reference import Reference

_SAME_ROTATION = 1e-12
"""Rotations closer than this [rad] are taken as equal (no motion)."""


def skew(vector: np.ndarray) -> np.ndarray:
    """The cross-product matrix ``[v]`` of a 3-vector, so ``[v] w = v x w``."""
    x, y, z = vector
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


class Slerp(Trajectory):
    r"""Rotation from ``start_rotation`` to ``goal_rotation`` about a fixed axis.

    .. math::

        R_0^T R_1 = \exp(\theta [a]), \qquad
        R(t) = R_0 \exp(s(t) [a]), \qquad
        \omega(t) = R_0\, a\, \dot s(t)

    with ``theta`` in ``[0, pi]`` and unit axis ``a`` from ``log3``, and
    ``s(t)`` the trapezoidal profile over the angle ``theta`` [rad]. The body
    angular velocity is ``a sdot``; in the world frame it is
    ``R(t) a sdot = R0 a sdot`` because ``exp(s [a]) a = a``: the world axis
    ``R0 a`` is constant. Exponentials are evaluated with the vectorised
    Rodrigues formula ``exp(phi [a]) = I + sin(phi) [a] + (1 - cos(phi)) [a]^2``.

    Timing: any two of ``duration``, ``cruise_speed`` [rad/s] and
    ``accel_time``, or one of the first two (as :class:`~clik.trajectory.line.Line`).

    Args:
        start_rotation: R0 (world <- frame), shape (3, 3).
        goal_rotation: R1 (world <- frame), shape (3, 3).
        duration: Duration [s].
        cruise_speed: Cruise angular speed [rad/s].
        accel_time: Acceleration time [s].

    Attributes:
        start_rotation, goal_rotation: R0, R1.
        angle: theta [rad].
        axis: Unit axis a in the start frame (zero when R0 = R1 to within 1e-12 rad).
        profile: The trapezoidal profile over the angle.
        duration: Duration [s].
    """

    def __init__(
        self,
        start_rotation: ArrayLike,
        goal_rotation: ArrayLike,
        duration: float | None = None,
        cruise_speed: float | None = None,
        accel_time: float | None = None,
    ) -> None:
        self.start_rotation = _validate.rotation(start_rotation, "start_rotation")
        self.goal_rotation = _validate.rotation(goal_rotation, "goal_rotation")
        relative = self.start_rotation.T @ self.goal_rotation
        rotation_vector = np.asarray(pin.log3(relative), dtype=float)
        angle = float(np.linalg.norm(rotation_vector))
        if angle < _SAME_ROTATION:  # rounding of log3(R0^T R0): hold still
            angle, rotation_vector = 0.0, np.zeros(3)
        self.angle = angle
        self.axis = rotation_vector / angle if angle > 0.0 else np.zeros(3)
        self.profile = TrapezoidalProfile.resolve(
            self.angle, duration, cruise_speed, accel_time, unit="rad"
        )
        self.duration = self.profile.duration

    @property
    def cruise_speed(self) -> float:
        """Cruise angular speed [rad/s]."""
        return self.profile.cruise_speed

    def sample(self, t: np.ndarray) -> Reference:
        """Rotations and world angular velocities at times ``t`` [s]."""
        times, clipped = self._times(t)
        s, sdot = self.profile(clipped)
        k = skew(self.axis)
        exp = np.eye(3) + np.sin(s)[:, None, None] * k + (1.0 - np.cos(s))[:, None, None] * (k @ k)
        rotation = self.start_rotation @ exp
        angular_velocity = sdot[:, None] * (self.start_rotation @ self.axis)
        return Reference(times, rotation=rotation, angular_velocity=angular_velocity)

    def __repr__(self) -> str:
        return f"Slerp(angle={self.angle:.6g}, duration={self.duration:.6g})"
