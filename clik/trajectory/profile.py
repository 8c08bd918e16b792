r"""Trapezoidal velocity profile of a scalar path coordinate.

The path coordinate ``s`` (an arc length [m] or an angle [rad]) goes from 0
to ``distance`` in ``duration`` seconds: constant acceleration for
``t_a``, cruise at ``v``, constant deceleration for the last ``t_a``.

.. math::

    t_a = T - \frac{D}{v}, \qquad a = \frac{v}{t_a}

    s(t) = \begin{cases}
        \tfrac12 a t^2 & 0 \le t < t_a \\
        v (t - \tfrac12 t_a) & t_a \le t \le T - t_a \\
        D - \tfrac12 a (T - t)^2 & T - t_a < t \le T
    \end{cases}

The profile exists when ``D / T <= v <= 2 D / T``: slower, it does not cover
``D`` in ``T``; faster, each acceleration phase would last more than ``T / 2``.
``v = D / T`` is the constant-speed profile (``t_a = 0``, the velocity jumps
at both ends); ``v = 2 D / T`` is the triangular one (``t_a = T / 2``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clik.errors import InputError
from clik.trajectory import _validate

DEFAULT_SPEED_FACTOR = 1.5
"""Given only a duration, the cruise speed is ``1.5 D / T``, i.e. ``t_a = T / 3``."""

DEFAULT_ACCEL_TIME = 0.25
"""Given only a cruise speed, the acceleration time [s]."""

_RELATIVE_SLACK = 1e-9
"""Rounding slack when comparing a speed with the bounds of its feasible range."""


@dataclass(frozen=True)
class TrapezoidalProfile:
    """A feasible trapezoidal profile (see the module docstring for the math).

    Build it with :meth:`resolve` from any two of duration, cruise speed and
    acceleration time; the constructor checks feasibility.

    Attributes:
        distance: Path length D [m] or [rad], >= 0.
        duration: Duration T [s], > 0.
        cruise_speed: Cruise speed v [m/s] or [rad/s], in ``[D/T, 2D/T]``
            (any value >= 0 when ``D = 0``: the profile then stays at 0).
        unit: Unit of the path coordinate, ``"m"`` or ``"rad"`` (for messages).
    """

    distance: float
    duration: float
    cruise_speed: float
    unit: str = "m"

    def __post_init__(self) -> None:
        u = self.unit
        distance = _validate.nonnegative(self.distance, "distance", f"[{u}]")
        duration = _validate.positive(self.duration, "duration", "[s]")
        object.__setattr__(self, "distance", distance)
        object.__setattr__(self, "duration", duration)
        if distance == 0.0:
            speed = _validate.nonnegative(self.cruise_speed, "cruise_speed", f"[{u}/s]")
            object.__setattr__(self, "cruise_speed", speed)
            return
        speed = _validate.positive(self.cruise_speed, "cruise_speed", f"[{u}/s]")
        low, high = distance / duration, 2.0 * distance / duration
        feasible = f"[{low:.6g}, {high:.6g}] {u}/s for {distance:.6g} {u} in {duration:.6g} s"
        if speed < low * (1.0 - _RELATIVE_SLACK):
            raise InputError(
                "cruise_speed",
                f"at least distance/duration to cover the path in time; feasible range {feasible}",
                speed,
            )
        if speed > high * (1.0 + _RELATIVE_SLACK):
            raise InputError(
                "cruise_speed",
                "at most 2 distance/duration, or the acceleration phase would last more "
                f"than half the duration; feasible range {feasible}",
                speed,
            )
        object.__setattr__(self, "cruise_speed", min(max(speed, low), high))

    @classmethod
    def resolve(
        cls,
        distance: float,
        duration: float | None = None,
        cruise_speed: float | None = None,
        accel_time: float | None = None,
        unit: str = "m",
    ) -> TrapezoidalProfile:
        """The profile from any two of duration, cruise speed and acceleration time.

        - ``duration`` and ``cruise_speed``: ``t_a = T - D / v``.
        - ``duration`` and ``accel_time``: ``v = D / (T - t_a)``, needs ``t_a <= T / 2``.
        - ``duration`` only: ``v = 1.5 D / T`` (``t_a = T / 3``).
        - ``cruise_speed`` (and ``accel_time``, default 0.25 s): ``T = D / v + t_a``,
          needs ``t_a <= D / v``.

        Args:
            distance: Path length D [m] or [rad].
            duration: Duration T [s].
            cruise_speed: Cruise speed v [m/s] or [rad/s].
            accel_time: Acceleration time t_a [s].
            unit: ``"m"`` or ``"rad"``, for messages.

        Raises:
            InputError: Too few or too many parameters, or an infeasible combination.
        """
        distance = _validate.nonnegative(distance, "distance", f"[{unit}]")
        if duration is not None and cruise_speed is not None and accel_time is not None:
            raise InputError(
                "accel_time",
                "at most two of duration, cruise_speed and accel_time "
                "(with duration and cruise_speed, accel_time = duration - distance/cruise_speed)",
                accel_time,
            )
        if duration is not None:
            duration = _validate.positive(duration, "duration", "[s]")
            if cruise_speed is not None:
                return cls(distance, duration, cruise_speed, unit)
            if accel_time is None:
                return cls(distance, duration, DEFAULT_SPEED_FACTOR * distance / duration, unit)
            accel_time = _validate.nonnegative(accel_time, "accel_time", "[s]")
            if accel_time > 0.5 * duration:
                raise InputError(
                    "accel_time", f"at most half the duration, {0.5 * duration:.6g} s", accel_time
                )
            return cls(distance, duration, distance / (duration - accel_time), unit)
        if cruise_speed is None:
            raise InputError("duration", "a duration or a cruise_speed (or both)")
        speed = _validate.positive(cruise_speed, "cruise_speed", f"[{unit}/s]")
        if distance == 0.0:
            raise InputError("duration", "a duration when the path has zero length")
        accel = DEFAULT_ACCEL_TIME if accel_time is None else accel_time
        accel = _validate.nonnegative(accel, "accel_time", "[s]")
        if accel > distance / speed:
            raise InputError(
                "accel_time",
                f"at most distance/cruise_speed = {distance / speed:.6g} s "
                f"(default {DEFAULT_ACCEL_TIME} s): at {speed:.6g} {unit}/s the path of "
                f"{distance:.6g} {unit} is too short to accelerate that long; lower "
                "cruise_speed or accel_time, or give a duration",
                accel,
            )
        return cls(distance, distance / speed + accel, speed, unit)

    @property
    def accel_time(self) -> float:
        """Duration of the acceleration (and of the deceleration) phase t_a [s]."""
        if self.distance == 0.0:
            return 0.0
        return min(max(self.duration - self.distance / self.cruise_speed, 0.0), 0.5 * self.duration)

    @property
    def acceleration(self) -> float:
        """Acceleration a = v / t_a [m/s^2] or [rad/s^2] (inf for t_a = 0, 0 for D = 0)."""
        if self.distance == 0.0:
            return 0.0
        ta = self.accel_time
        return math.inf if ta == 0.0 else self.cruise_speed / ta

    def __call__(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Evaluate ``(s, sdot)`` at times ``t`` [s], clipped to ``[0, duration]``.

        Returns:
            ``s`` [m] or [rad] and ``sdot`` [m/s] or [rad/s], arrays shaped like ``t``.
        """
        tc = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        if self.distance == 0.0:
            return np.zeros_like(tc), np.zeros_like(tc)
        d, big_t, v, ta = self.distance, self.duration, self.cruise_speed, self.accel_time
        if ta == 0.0:
            return v * tc, np.full_like(tc, v)
        a = v / ta
        rest = big_t - tc
        accelerating = tc < ta
        decelerating = tc > big_t - ta
        s = np.where(
            accelerating,
            0.5 * a * tc**2,
            np.where(decelerating, d - 0.5 * a * rest**2, v * (tc - 0.5 * ta)),
        )
        sdot = np.where(accelerating, a * tc, np.where(decelerating, a * rest, v))
        return np.clip(s, 0.0, d), sdot


def trapezoidal_profile(
    t: np.ndarray | float,
    distance: float,
    duration: float,
    cruise_speed: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Trapezoidal profile ``(s, sdot)`` of a path coordinate, vectorised over ``t``.

    Args:
        t: Times [s], any shape; clipped to ``[0, duration]``.
        distance: Path length D [m] (or [rad]), >= 0.
        duration: Duration T [s], > 0.
        cruise_speed: Cruise speed v, in ``[D/T, 2D/T]``; default ``1.5 D / T``
            (acceleration time ``T / 3``).

    Returns:
        ``s`` in ``[0, D]`` and ``sdot >= 0``, arrays shaped like ``t``.

    Raises:
        InputError: A bad argument, or a cruise speed outside the feasible range.
    """
    return TrapezoidalProfile.resolve(distance, duration, cruise_speed)(t)
