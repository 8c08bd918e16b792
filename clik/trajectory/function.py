"""A position trajectory given by any user function of time."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np

from clik.errors import InputError
from clik.trajectory import _validate
from clik.trajectory.base import Trajectory
from clik.trajectory.reference import Reference

_EXPECTED = "a callable returning (x_d, xdot_d), each finite of shape (3,) [m], [m/s]"


class Function(Trajectory):
    """Position trajectory from a user callable ``f(t) -> (x_d, xdot_d)``.

    By default ``f`` takes one time (a float [s]) and returns the desired
    position (3,) [m] and velocity (3,) [m/s]; it is then called once per
    sample in a Python loop, the one exception to the vectorised sampling of
    this package, since the callable is arbitrary user code. With
    ``vectorized=True``, ``f`` takes the whole array of times (N,) and returns
    two arrays of shape (N, 3), in one call.

    ``f`` is evaluated on times clipped to ``[0, duration]``; outside that
    interval the velocity is set to zero (the trajectory holds its end
    values), whatever ``f`` returns there. ``f`` is responsible for
    ``xdot_d`` being the derivative of ``x_d``.

    Args:
        f: The callable.
        duration: Duration [s], > 0.
        vectorized: Whether ``f`` takes an array of times.

    Raises:
        InputError: ``f`` not callable or a bad duration; when sampling,
            ``trajectory: expected ..., got '... at t = ... s'`` naming the
            first time where ``f`` returned a wrong shape or NaN/inf.
    """

    def __init__(
        self,
        f: Callable[[Any], tuple[Any, Any]],
        duration: float,
        vectorized: bool = False,
    ) -> None:
        if not callable(f):
            raise InputError("f", "a callable t -> (x_d, xdot_d)", type(f).__name__)
        self.f = f
        self.duration = _validate.positive(duration, "duration", "[s]")
        self.vectorized = bool(vectorized)

    def sample(self, t: np.ndarray) -> Reference:
        """Positions and velocities from ``f`` at times ``t`` [s]."""
        times, clipped = self._times(t)
        if self.vectorized:
            position, velocity = self._call_vectorized(clipped)
        else:
            position, velocity = self._call_per_sample(clipped)
        velocity[(times < 0.0) | (times > self.duration)] = 0.0
        return Reference(times, position=position, linear_velocity=velocity)

    def _call_per_sample(self, clipped: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = clipped.shape[0]
        position, velocity = np.empty((n, 3)), np.empty((n, 3))
        for k, tk in enumerate(clipped):
            x, xdot = _pair(self.f(float(tk)), f"at t = {tk:.6g} s")
            for name, value, out in (("x_d", x, position), ("xdot_d", xdot, velocity)):
                if value.shape != (3,):
                    raise InputError(
                        "trajectory", _EXPECTED, f"{name} of shape {value.shape} at t = {tk:.6g} s"
                    )
                if not np.all(np.isfinite(value)):
                    raise InputError(
                        "trajectory", _EXPECTED, f"{name} = {value.tolist()} at t = {tk:.6g} s"
                    )
                out[k] = value
        return position, velocity

    def _call_vectorized(self, clipped: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = clipped.shape[0]
        expected = "a vectorized callable returning (x_d, xdot_d), each finite of shape (N, 3)"
        x, xdot = _pair(self.f(clipped.copy()), f"for {n} times")
        for name, value in (("x_d", x), ("xdot_d", xdot)):
            if value.shape != (n, 3):
                raise InputError("trajectory", expected, f"{name} of shape {value.shape}")
            finite = np.isfinite(value)
            if not finite.all():
                k = int(np.flatnonzero(~finite.all(axis=1))[0])
                raise InputError(
                    "trajectory",
                    expected,
                    f"{name}[{k}] = {value[k].tolist()} at t = {clipped[k]:.6g} s",
                )
        return x.copy(), xdot.copy()


def _pair(result: object, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Split the callable's result into two float arrays."""
    try:
        x, xdot = cast("tuple[object, object]", result)  # checked here, at run time
        return np.asarray(x, dtype=float), np.asarray(xdot, dtype=float)
    except (TypeError, ValueError):
        raise InputError("trajectory", _EXPECTED, f"{type(result).__name__} {where}") from None
