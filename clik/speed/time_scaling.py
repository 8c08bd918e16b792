r"""The next time scaling of a reference, from the joint speeds of a run.

docs/method.md, "Joint speed limits: time scaling of the reference". A run on the
grid :math:`t_k` gave the ratio :math:`r_k` (:mod:`clik.speed.speed_limits`). Its
envelope :math:`\bar r_k` is a running maximum over :math:`\pm n` samples
(``n = window / dt``) followed by a running mean over :math:`\pm n` samples:
continuous, at least :math:`r_k` everywhere (each mean is over maxima whose
windows all contain sample ``k``), and rising up to :math:`2 n` samples before a
peak, so the slowdown starts before it. The slowdown factor is

.. math::

    f_k = \max(1, \bar r_k (1 + m))

and, with :math:`\tau_k` the reference's own time at :math:`t_k`, the new rate
of the reference's clock is :math:`\sigma_{p+1}(\tau) = \sigma_p(\tau) / f(\tau)`:
it only ever slows down, where the joints went too fast.
"""

from __future__ import annotations

import math

import numpy as np

from clik.trajectory import Trajectory
from clik.trajectory.retimed import Retimed


def running_max(values: np.ndarray, half: int) -> np.ndarray:
    """Maximum of ``values`` (N,) >= 0 over ``[k - half, k + half]`` (clipped), in O(N).

    Blocks of the window's length, with prefix and suffix maxima (van Herk, Gil and
    Werman): the window starting at ``i`` spans at most two blocks.
    """
    values = np.asarray(values, dtype=float)
    if half <= 0 or values.size == 0:
        return values.copy()
    width = 2 * half + 1
    padded = np.concatenate([np.zeros(half), values, np.zeros(half)])  # values >= 0
    padded = np.concatenate([padded, np.zeros(-padded.size % width)])
    blocks = padded.reshape(-1, width)
    prefix = np.maximum.accumulate(blocks, axis=1).reshape(-1)
    suffix = np.maximum.accumulate(blocks[:, ::-1], axis=1)[:, ::-1].reshape(-1)
    start = np.arange(values.size)
    return np.maximum(suffix[start], prefix[start + width - 1])


def running_mean(values: np.ndarray, half: int) -> np.ndarray:
    """Mean of ``values`` (N,) over ``[k - half, k + half]``, the window clipped to the array."""
    values = np.asarray(values, dtype=float)
    total = np.concatenate([[0.0], np.cumsum(values)])
    k = np.arange(values.size)
    low, high = np.maximum(k - half, 0), np.minimum(k + half + 1, values.size)
    return (total[high] - total[low]) / (high - low)


def slowdown(ratio: np.ndarray, dt: float, window: float, margin: float) -> np.ndarray:
    r"""The slowdown factor :math:`f_k = \max(1, \bar r_k (1 + m)) \ge 1` of each sample.

    Args:
        ratio: The ratio :math:`r_k` of each sample (N,), >= 0.
        dt: Time between samples [s].
        window: Half-width of the running maximum and of the running mean [s].
        margin: Relative margin ``m`` >= 0.
    """
    half = max(1, round(window / dt))
    envelope = running_mean(running_max(ratio, half), half)
    return np.maximum(1.0, envelope * (1.0 + margin))


def retime(
    trajectory: Trajectory,
    current: Retimed | None,
    t: np.ndarray,
    factor: np.ndarray,
    dt: float,
) -> Retimed:
    r"""The reference slowed once more: :math:`\sigma_{p+1}(\tau) = \sigma_p(\tau) / f(\tau)`.

    Args:
        trajectory: The reference as given (its path and its own time :math:`\tau`).
        current: The time scaling the run was made with (None: the reference as given).
        t: The run's sample times (N,) [s].
        factor: The slowdown factor of each sample (N,) (:func:`slowdown`).
        dt: Spacing of the new rate's grid in the reference's own time [s].

    Returns:
        The new time scaling of ``trajectory`` (its duration is the stretched one).
    """
    duration = trajectory.duration
    run_duration = duration if current is None else current.duration
    inside = t <= run_duration + 1e-12
    tau_run = np.clip(t, 0.0, duration) if current is None else current.inner_time(t)
    tau = np.linspace(0.0, duration, max(2, math.ceil(duration / dt) + 1))
    f_tau = np.interp(tau, np.maximum.accumulate(tau_run[inside]), factor[inside])
    sigma = np.ones_like(tau) if current is None else current.rate(tau)
    return Retimed(trajectory, tau, sigma / f_tau)
