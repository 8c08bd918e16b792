"""The reference of a run, sampled chunk by chunk for the tracking loop.

A trajectory is sampled vectorised over a block of the time grid at a time
(:data:`REFERENCE_CHUNK` samples), so a 10^6-sample run holds a few hundred
kilobytes of reference instead of hundreds of megabytes. Every chunk is
sampled once before the loop starts, so a trajectory that yields NaN or lacks
what the task needs is refused before any computation; a run of at most
:data:`KEEP_SAMPLES` samples keeps those chunks for the loop instead of sampling
them again.
"""

from __future__ import annotations

import math

import numpy as np

from clik.errors import InputError
from clik.tasks.task import Task
from clik.trajectory import Reference, Trajectory
from clik.trajectory.reference import TRAILING_SHAPES

REFERENCE_CHUNK = 4096
"""Samples per chunk of reference."""

KEEP_SAMPLES = 65536
"""Runs up to this many samples keep their sampled reference (about 10 MB for a pose task)."""

Chunk = tuple[int, int, np.ndarray | None, np.ndarray | None, np.ndarray, np.ndarray]


def task_reference(
    task: Task, ref: Reference
) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray]:
    """Positions (N, 3), rotations (N, 3, 3) and the task rows' velocities (N, m)."""
    P_d, R_d = ref.position, ref.rotation
    if task.has_position and P_d is None:
        raise InputError("trajectory", f"a position reference for the {task.kind} task")
    if task.has_orientation and R_d is None:
        raise InputError("trajectory", f"an orientation reference for the {task.kind} task")
    # FF column by column from the reference's arrays (a (N, 6) array filled then its
    # rows taken costs ~4x as much: NumPy loops over N rows of 3)
    FF = np.empty((ref.t.shape[0], len(task.rows)))
    velocities = (ref.linear_velocity, ref.angular_velocity)  # each with its pose part
    for k, row in enumerate(task.rows.tolist()):
        source = velocities[row // 3]
        if source is None:  # pragma: no cover - a Reference has both or neither
            raise InputError("trajectory", f"a velocity with the {task.kind} task's reference")
        FF[:, k] = source[:, row % 3]
    return P_d, R_d, FF


def checked_sample(ref: object, n: int) -> Reference:
    """What a trajectory's ``sample`` gave for ``n`` times, checked: a Reference of ``n``.

    A :class:`~clik.trajectory.Reference` checks its own arrays against its times when
    it is built; here its number of samples and its arrays' shapes are checked against
    the ``n`` asked for (the loop, and the engine, read ``n`` rows of each).

    Raises:
        InputError: Not a Reference, or not ``n`` samples (``trajectory.sample``), or an
            array of another shape (``trajectory.<array>``).
    """
    if not isinstance(ref, Reference):
        raise InputError(
            "trajectory.sample", "a clik.trajectory.Reference from sample(t)", type(ref).__name__
        )
    if ref.t.shape != (n,):
        raise InputError(
            "trajectory.sample", f"a Reference of the {n} samples asked for", f"{len(ref)}"
        )
    for name, trailing in TRAILING_SHAPES.items():
        array = getattr(ref, name)
        if array is not None and np.shape(array) != (n, *trailing):
            expected = f"shape {(n, *trailing)} for {n} samples"
            raise InputError(f"trajectory.{name}", expected, f"shape {np.shape(array)}")
    return ref


def rows_at_rest(ff: np.ndarray) -> np.ndarray:
    """Whether each row of feed-forward ``ff`` (N, k) is all zeros (a NaN row is not).

    ``|ff| 1 == 0`` by a matrix-vector product: a sum of magnitudes is zero only when
    each is, and it is several times faster than ``~np.any(ff != 0, axis=1)``.
    """
    return np.abs(ff) @ np.ones(ff.shape[1]) == 0.0


class ReferenceChunks:
    """Chunks of a trajectory's reference on the time grid ``t``.

    Args:
        task: The task (which rows the reference must provide).
        trajectory: The trajectory.
        t: The run's time grid [s].
        size: Samples per chunk.
        center: A point [m] whose largest distance to the position reference is kept
            in :attr:`farthest` (the reach check).
    """

    def __init__(
        self,
        task: Task,
        trajectory: Trajectory,
        t: np.ndarray,
        size: int,
        center: np.ndarray | None = None,
    ) -> None:
        self.task, self.trajectory, self.t, self.size = task, trajectory, t, size
        self.center = center
        self.farthest = (0.0, 0.0)
        """Largest distance [m] of the position reference from ``center``, and its time [s]."""
        self._kept: dict[int, Chunk] = {}
        keep = t.shape[0] <= KEEP_SAMPLES
        self._first = self._sample(0)
        for c0 in range(size, t.shape[0], size):  # validate the rest before any step
            chunk = self._sample(c0)
            if keep:
                self._kept[c0] = chunk

    def _sample(self, c0: int) -> Chunk:
        c1 = min(c0 + self.size, self.t.shape[0])
        ref = checked_sample(self.trajectory.sample(self.t[c0:c1]), c1 - c0)
        P_d, R_d, FF = task_reference(self.task, ref)
        at_rest = rows_at_rest(FF)
        if self.center is not None and P_d is not None:
            offset = P_d - self.center
            squared = (offset * offset) @ np.ones(3)  # (a row norm along axis 1: 2x slower)
            i = int(np.argmax(squared))
            dist = math.sqrt(squared[i])
            if dist > self.farthest[0]:
                self.farthest = (dist, float(self.t[c0 + i]))
        return c0, c1, P_d, R_d, FF, at_rest

    def load(self, c0: int) -> Chunk:
        """The chunk starting at sample ``c0``: ``(c0, c1, P_d, R_d, FF, at_rest)``."""
        if c0 == 0:
            return self._first
        kept = self._kept.get(c0)
        return kept if kept is not None else self._sample(c0)
