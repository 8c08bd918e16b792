"""One per-tick line: a tool stepped once per 1 ms tick from Python, its joints recorded.

A tick line is a step-benchmark :class:`~benchmarks.step_variant.Variant` (its run
returns the ticks, the wall time of the whole per-tick loop and an info dict, so
:func:`~benchmarks.step.interleaved_rounds` times it beside the others) that also
keeps the joints of its last run, ``q_0, q_1, ...``, for the tracking-quality check
(:mod:`benchmarks.tick_quality`), made on the joints alone.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from benchmarks.config import DT
from benchmarks.step_variant import Variant
from clik.trajectory import Trajectory, time_grid


@dataclass(frozen=True)
class TickReference:
    """A pose reference sampled once per tick, before any clock starts.

    Attributes:
        t: Tick times ``t_k = k dt`` (n,) [s].
        poses: The desired poses ``x_d(t_k)`` as ``pin.SE3`` (n of them): pink's and
            mink's input.
        velocities: Feed-forward ``(v_d, w_d)(t_k)``, linear then angular (n, 6)
            [m/s, rad/s].
        matrices: The same poses as 4x4 float64 arrays (n, 4, 4): clik's documented
            fast input (``Controller.step`` reads it in the engine). Each tool gets its
            targets in its own input type, all built before any clock starts.
    """

    t: np.ndarray
    poses: list[pin.SE3]
    velocities: np.ndarray
    matrices: np.ndarray

    @property
    def ticks(self) -> int:
        """Samples of the reference (clik ticks once per sample)."""
        return len(self.poses)


def tick_reference(trajectory: Trajectory) -> TickReference:
    """The trajectory at every tick of :data:`~benchmarks.config.DT`, as a user would hold it.

    Args:
        trajectory: A pose reference (position and rotation).

    Raises:
        ValueError: The trajectory lacks the position or the rotation.
    """
    t = time_grid(trajectory.duration, DT)
    ref = trajectory.sample(t)
    if ref.rotation is None or ref.position is None:
        raise ValueError("the tick lines need a pose reference (position and rotation)")
    poses = [pin.SE3(R, p) for R, p in zip(ref.rotation, ref.position, strict=True)]
    v = np.zeros((len(t), 3)) if ref.linear_velocity is None else ref.linear_velocity
    w = np.zeros((len(t), 3)) if ref.angular_velocity is None else ref.angular_velocity
    matrices = np.ascontiguousarray(np.array([pose.homogeneous for pose in poses]))
    return TickReference(t, poses, np.ascontiguousarray(np.hstack([v, w])), matrices)


@dataclass
class TickVariant(Variant):
    """A per-tick line and the joints of its last run.

    Attributes:
        joints: Gives the joints of the last run, ``q_k`` at every tick time, ``q_0``
            first (m, nq) [rad]: row k is the joints at ``t_k`` (the configuration the
            tick at ``t_k`` starts from; the last row, the one the last tick commands).
        check: The line's own quality check of those joints (None: the Panda's,
            :class:`~benchmarks.tick_quality.QualityCheck`).
    """

    joints: Callable[[], np.ndarray]
    check: Callable[[np.ndarray], dict[str, Any]] | None = None
