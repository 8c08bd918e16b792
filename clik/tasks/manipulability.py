r"""The task's manipulability ``w(q) = sqrt(det(J J^T))`` (docs/method.md, "Dexterity").

``J`` is the task Jacobian of eq. (3): the frame's ``LOCAL_WORLD_ALIGNED``
Jacobian masked to the task's rows (3 x n for a position task, 6 x n for a
pose task, 2 x n for the case study's ``["x", "y"]``), the very rows the law
runs on. ``w`` is the volume of the velocity ellipsoid ``J J^T`` (Yoshikawa's
measure): zero at a singularity of the task, in [m^p] for a task with ``p``
position rows (orientation rows are [rad/rad], unitless).

Every tracking run reports ``w`` post hoc, from its recorded configurations:
:func:`manipulability_record` gives the per-sample array (kept in
``result.extra["manipulability"]``) and the summary's ``min_manipulability`` is
its minimum. The dexterity row (:mod:`clik.constraints.dexterity`) evaluates
the same ``w`` every sample.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import pinocchio as pin

if TYPE_CHECKING:
    from clik.model.robot import Robot

RECORD_KEY = "manipulability"
"""Name of the per-sample array in ``result.extra``."""

AXES = ("x", "y", "z", "rx", "ry", "rz")
"""A result's ``info["axes"]`` names, in row order (``clik.tasks.task.AXES``; this ground-floor
module imports no task)."""


class RecordedRun(Protocol):
    """What these functions read of a :class:`~clik.outputs.result.TrackingResult`."""

    q: np.ndarray
    info: dict[str, Any]
    extra: dict[str, np.ndarray]
    robot: Robot | None


def manipulability(J: np.ndarray) -> float:
    """``w = sqrt(det(J J^T))`` (D1) of a task Jacobian ``J`` (m, nv).

    Computed from the Cholesky factor ``L`` of ``J J^T`` as ``prod(diag(L))``, the
    same way as the compiled engine; 0 when ``J J^T`` is not positive definite
    (``J`` loses rank: a singularity of the task).

    Returns:
        ``w`` [m^p, p the task's position rows].
    """
    try:
        L = np.linalg.cholesky(J @ J.T)
    except np.linalg.LinAlgError:
        return 0.0
    return float(np.prod(np.diagonal(L)))


def manipulability_along(
    robot: Robot, frame_id: int, rows: np.ndarray, q: np.ndarray
) -> np.ndarray:
    """``w`` (D1) at each configuration of ``q`` (N, nq), for the task ``(frame_id, rows)``.

    One Jacobian per sample, then ``sqrt(det(J J^T))`` batched over the samples (the
    measure of :func:`manipulability` to rounding; a negative rounded determinant is 0).

    Returns:
        A new array (N,) [m^p].
    """
    model, data = robot.model, robot.thread_data()  # the calling thread's own
    n = q.shape[0]
    J = np.empty((n, len(rows), model.nv))
    for k in range(n):
        J6 = pin.computeFrameJacobian(model, data, q[k], frame_id, pin.LOCAL_WORLD_ALIGNED)
        np.take(J6, rows, axis=0, out=J[k])
    det = np.linalg.det(J @ J.transpose(0, 2, 1)) if n else np.zeros(0)
    return np.sqrt(np.maximum(det, 0.0))


def manipulability_record(result: RecordedRun) -> np.ndarray | None:
    """The run's per-sample ``w`` at its recorded samples (N,) [m^p], or None.

    Read from ``result.extra["manipulability"]`` when there (a saved result keeps
    it), else computed from the recorded ``q`` with the result's robot and its
    task (``info["frame"]``, ``info["axes"]``) and kept there. None for a result
    without the array and without a robot.
    """
    kept = result.extra.get(RECORD_KEY)
    if kept is not None:
        return np.asarray(kept, dtype=float)
    robot, info = result.robot, result.info
    if robot is None or "frame" not in info or "axes" not in info:
        return None
    rows = np.array([AXES.index(a) for a in info["axes"]], dtype=np.intp)
    w = manipulability_along(robot, robot.frame_id(info["frame"]), rows, np.asarray(result.q))
    result.extra[RECORD_KEY] = w
    return w


def min_manipulability(result: RecordedRun) -> float | None:
    """Smallest ``w`` (D1) over the run's recorded samples [m^p] (the summary's field).

    Samples with a non-finite ``w`` (a diverged run's last ``q``) are skipped; None when
    the run cannot say (no such sample, or a result loaded from a file that has neither
    the array nor a robot).
    """
    w = manipulability_record(result)
    if w is None:
        return None
    finite = w[np.isfinite(w)]
    return float(finite.min()) if finite.size else None
