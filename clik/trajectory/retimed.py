r"""A trajectory run slower along the same path: time scaling of the reference.

The reference is sampled at an inner time :math:`\tau(t)` that advances at the
rate :math:`\sigma(\tau) \in (0, 1]` (docs/method.md, "Joint speed limits: time
scaling of the reference"):

.. math::

    \frac{d\tau}{dt} = \sigma(\tau), \qquad
    t(\tau) = \int_0^\tau \frac{du}{\sigma(u)}, \qquad
    T' = t(T)

    x_r(t) = x_d(\tau(t)), \qquad
    \dot x_r(t) = \dot x_d(\tau(t))\, \sigma(\tau(t))

The positions and rotations are those of the inner trajectory (the path is
kept); its linear and angular velocities are scaled by :math:`\sigma`, so the
feed-forward ``xdot_d`` of law (10) and of the error dynamics (7) stays the
derivative of the re-timed reference.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from clik.errors import InputError
from clik.trajectory.base import Trajectory
from clik.trajectory.reference import Reference


class Retimed(Trajectory):
    r"""The inner trajectory with its clock slowed by :math:`\sigma(\tau)`.

    :math:`\sigma` is given at increasing inner times ``tau`` (from 0 to at least
    the inner duration) and is linear between them; :math:`t(\tau)` is integrated
    with the trapezoidal rule on that grid. Outside ``[0, duration]`` the
    trajectory holds its ends with zero velocity, like every trajectory.

    Args:
        inner: The trajectory whose path is kept.
        tau: Inner times (M,) [s], strictly increasing, ``tau[0] = 0``,
            ``tau[-1] >= inner.duration``; M >= 2.
        sigma: Rate of the inner clock at those times (M,), in ``(0, 1]``.

    Attributes:
        inner: The inner trajectory.
        tau: The inner times (M,) [s].
        sigma: The rates (M,).
        t_of_tau: Outer time at each inner time (M,) [s].
        duration: Stretched duration :math:`T'` [s] (at least the inner one).

    Raises:
        InputError: A bad grid or a rate outside ``(0, 1]``.
    """

    def __init__(self, inner: Trajectory, tau: ArrayLike, sigma: ArrayLike) -> None:
        if not isinstance(inner, Trajectory):
            raise InputError("inner", "a Trajectory", type(inner).__name__)
        tau = np.array(tau, dtype=float).reshape(-1)
        sigma = np.array(sigma, dtype=float).reshape(-1)
        if tau.shape != sigma.shape or tau.size < 2:
            raise InputError(
                "sigma", f"as many rates as inner times (>= 2), {tau.size}", sigma.size
            )
        if not (np.all(np.isfinite(tau)) and tau[0] == 0.0 and np.all(np.diff(tau) > 0.0)):
            raise InputError("tau", "strictly increasing finite times from 0 [s]", tau[:3])
        if tau[-1] < inner.duration:
            raise InputError("tau", f"times up to the inner duration {inner.duration:g} s", tau[-1])
        if not np.all(np.isfinite(sigma) & (sigma > 0.0) & (sigma <= 1.0)):
            raise InputError("sigma", "rates in (0, 1]", float(sigma.min()))
        self.inner, self.tau, self.sigma = inner, tau, sigma
        steps = 0.5 * np.diff(tau) * (1.0 / sigma[:-1] + 1.0 / sigma[1:])
        self.t_of_tau = np.concatenate([[0.0], np.cumsum(steps)])
        self.duration = float(np.interp(inner.duration, tau, self.t_of_tau))

    def inner_time(self, t: ArrayLike) -> np.ndarray:
        r"""The inner time :math:`\tau(t)` [s] of outer times ``t`` [s], clipped to the run."""
        clipped = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        return np.interp(clipped, self.t_of_tau, self.tau)

    def rate(self, tau: ArrayLike) -> np.ndarray:
        r"""The rate :math:`\sigma(\tau)` at inner times ``tau`` [s], linear between grid points."""
        return np.interp(np.asarray(tau, dtype=float), self.tau, self.sigma)

    def sample(self, t: np.ndarray) -> Reference:
        r"""The inner reference at :math:`\tau(t)`, its velocities times :math:`\sigma`."""
        times, clipped = self._times(t)
        tau = self.inner_time(clipped)
        ref = self.inner.sample(tau)
        scale = self.rate(tau) * ((times >= 0.0) & (times <= self.duration))
        linear = None if ref.linear_velocity is None else ref.linear_velocity * scale[:, None]
        angular = None if ref.angular_velocity is None else ref.angular_velocity * scale[:, None]
        return Reference(times, ref.position, linear, ref.rotation, angular)

    def __repr__(self) -> str:
        return f"Retimed({self.inner!r}, duration={self.duration:.6g})"
