r"""Circular arc with a trapezoidal velocity profile along the arc."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from clik.errors import InputError
from clik.trajectory import _validate
from clik.trajectory.base import Trajectory
from clik.trajectory.profile import TrapezoidalProfile
from clik.trajectory.reference import Reference


def plane_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal basis ``(e1, e2)`` of the plane orthogonal to a unit ``normal``.

    ``e1`` is the world x axis projected on the plane (the y axis when the
    normal is close to x), and ``e2 = normal x e1``, so ``(e1, e2, normal)`` is
    right-handed. For ``normal = z`` this is ``(x, y)``.
    """
    reference = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = reference - (reference @ normal) * normal
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(normal, e1)


class Circle(Trajectory):
    r"""Arc of a circle, travelled with a trapezoidal profile on its length.

    .. math::

        \varphi(t) = \varphi_0 + \operatorname{sign}(\Delta)\, \frac{s(t)}{r}, \qquad
        p(t) = c + r (\cos\varphi\, e_1 + \sin\varphi\, e_2)

        \dot p(t) = \operatorname{sign}(\Delta)\, \dot s(t)
                    (-\sin\varphi\, e_1 + \cos\varphi\, e_2)

    where ``s(t)`` is the trapezoidal profile over the arc length ``r |angle|``
    and ``(e1, e2)`` the basis of :func:`plane_basis` (for the default normal
    ``z``: ``e1 = x``, ``e2 = y``). Positive angles turn counter-clockwise
    about ``normal``; ``|angle|`` may exceed ``2 pi`` (several turns).

    Timing: as :class:`~clik.trajectory.line.Line`, any two of ``duration``,
    ``cruise_speed`` (along the arc) and ``accel_time``, or one of the first two.

    Args:
        center: Center c in the world frame, shape (3,) [m].
        radius: Radius r [m], > 0.
        normal: Normal of the circle's plane, shape (3,) (normalised here).
        start_angle: Start angle phi0 in the plane, from e1 toward e2 [rad].
        angle: Signed angle swept Delta [rad], non-zero (default a full turn).
        duration: Duration [s].
        cruise_speed: Cruise speed along the arc [m/s].
        accel_time: Acceleration time [s].

    Attributes:
        center, radius, normal, start_angle, angle: As given (normal normalised).
        e1, e2: In-plane basis.
        length: Arc length ``r |angle|`` [m].
        profile: The trapezoidal profile.
        duration: Duration [s].
    """

    def __init__(
        self,
        center: ArrayLike,
        radius: float,
        normal: ArrayLike = (0.0, 0.0, 1.0),
        start_angle: float = 0.0,
        angle: float = 2.0 * math.pi,
        duration: float | None = None,
        cruise_speed: float | None = None,
        accel_time: float | None = None,
    ) -> None:
        self.center = _validate.vector3(center, "center", "[m]")
        self.radius = _validate.positive(radius, "radius", "[m]")
        self.normal = _validate.unit_vector3(normal, "normal")
        self.start_angle = _validate.finite_scalar(start_angle, "start_angle", "[rad]")
        self.angle = _validate.finite_scalar(angle, "angle", "[rad]")
        if self.angle == 0.0:
            raise InputError("angle", "a non-zero angle to sweep [rad]", angle)
        self.e1, self.e2 = plane_basis(self.normal)
        self.length = self.radius * abs(self.angle)
        self.profile = TrapezoidalProfile.resolve(
            self.length, duration, cruise_speed, accel_time, unit="m"
        )
        self.duration = self.profile.duration

    @classmethod
    def through(
        cls,
        start_point: ArrayLike,
        center: ArrayLike,
        normal: ArrayLike = (0.0, 0.0, 1.0),
        angle: float = 2.0 * math.pi,
        duration: float | None = None,
        cruise_speed: float | None = None,
        accel_time: float | None = None,
    ) -> Circle:
        """The arc that starts at ``start_point`` (e.g. the frame's initial position).

        The circle lies in the plane through ``start_point`` orthogonal to
        ``normal``: ``center`` is first projected onto that plane along the
        normal (so a center given at another height is accepted). The radius
        is the distance from the start point to the projected center.

        Args:
            start_point: Where the arc starts, shape (3,) [m].
            center: Center, shape (3,) [m] (projected as above).
            normal: Plane normal, shape (3,).
            angle: Signed angle swept [rad].
            duration: Duration [s].
            cruise_speed: Cruise speed along the arc [m/s].
            accel_time: Acceleration time [s].

        Raises:
            InputError: ``start_point`` on the circle's axis (zero radius), or a bad argument.
        """
        start = _validate.vector3(start_point, "start_point", "[m]")
        c = _validate.vector3(center, "center", "[m]")
        n = _validate.unit_vector3(normal, "normal")
        c = c + ((start - c) @ n) * n
        offset = start - c
        radius = float(np.linalg.norm(offset))
        if radius < 1e-12:
            raise InputError(
                "start_point",
                "a point away from the circle's axis (a positive radius)",
                start_point,
            )
        e1, e2 = plane_basis(n)
        start_angle = math.atan2(float(offset @ e2), float(offset @ e1))
        return cls(c, radius, n, start_angle, angle, duration, cruise_speed, accel_time)

    @property
    def cruise_speed(self) -> float:
        """Cruise speed along the arc [m/s]."""
        return self.profile.cruise_speed

    def sample(self, t: np.ndarray) -> Reference:
        """Positions and velocities at times ``t`` [s] (see :meth:`Trajectory.sample`)."""
        times, clipped = self._times(t)
        s, sdot = self.profile(clipped)
        sign = math.copysign(1.0, self.angle)
        phi = self.start_angle + sign * s / self.radius
        cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
        position = self.center + self.radius * (cos * self.e1 + sin * self.e2)
        velocity = (sign * sdot)[:, None] * (-sin * self.e1 + cos * self.e2)
        return Reference(times, position=position, linear_velocity=velocity)

    def __repr__(self) -> str:
        return (
            f"Circle(center={self.center.tolist()}, radius={self.radius:.6g}, "
            f"normal={self.normal.tolist()}, start_angle={self.start_angle:.6g}, "
            f"angle={self.angle:.6g}, duration={self.duration:.6g})"
        )
