"""A tick's targets, as the loop reads them: each task's reference at ``t_k`` (one sample).

A controller is given, at each tick, each task's target (and, optionally, its velocity
for the feed-forward of (10)); here they become the one-sample references an offline
run samples from its trajectories (:class:`~clik.trajectory.Reference`,
:class:`~clik.trajectory.joint_path.JointReference`), read by the same functions, so a
controller given a trajectory's samples runs exactly what ``clik.track`` runs.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.tasks.posture_task import PostureTask
from clik.trajectory import Reference
from clik.trajectory.joint_path import JointReference


def _array(value: Any, field: str, expected: str) -> np.ndarray:
    if value is None:
        raise InputError(field, expected, "None")
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, expected, type(value).__name__) from None


def _pose(task: Any, target: Any, field: str) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Position (3,) and rotation (3, 3) of a frame task's target (those it tracks)."""
    pos_needed, rot_needed = bool(task.has_position), bool(task.has_orientation)
    expected = "a pin.SE3 or a 4x4 pose" + (
        ", or a position (3,)" if not rot_needed else ""
    ) + (", or a rotation (3, 3)" if not pos_needed else "")  # fmt: skip
    if isinstance(target, pin.SE3):
        return target.translation.copy(), target.rotation.copy()
    a = _array(target, field, expected)
    if a.shape == (4, 4):
        if not np.array_equal(a[3], [0.0, 0.0, 0.0, 1.0]):
            raise InputError(field, "a 4x4 homogeneous pose (its last row 0 0 0 1)", a[3])
        return a[:3, 3].copy(), a[:3, :3].copy()
    if a.shape == (3,) and not rot_needed:
        return a, None
    if a.shape == (3, 3) and not pos_needed:
        return None, a
    raise InputError(field, expected, f"shape {a.shape}")


def _velocity(task: Any, velocity: Any, field: str) -> tuple[np.ndarray, np.ndarray]:
    """Linear and angular velocity (3,) each of a frame task [m/s, rad/s] (zero: none)."""
    v, w = np.zeros(3), np.zeros(3)
    if velocity is None:
        return v, w
    a = _array(velocity, field, "a velocity (6,) [m/s, rad/s] or (3,)")
    if a.shape == (6,):
        return a[:3].copy(), a[3:].copy()
    if a.shape == (3,) and not (task.has_position and task.has_orientation):
        return (a, w) if task.has_position else (v, a)
    expected = "(linear, angular) (6,) [m/s, rad/s]" + (
        "" if task.has_position and task.has_orientation else ", or (3,)"
    )
    raise InputError(field, expected, f"shape {a.shape}")


def one_sample(task: Any, target: Any, velocity: Any, tk: float, name: str) -> Any:
    """The task's reference at ``t_k``: a one-sample Reference (or JointReference).

    Raises:
        InputError: A target or velocity of the wrong shape for the task, or not finite
            (``targets[name]``, ``velocities[name]``).
    """
    field, vfield = f"targets[{name!r}]", f"velocities[{name!r}]"
    t = np.array([tk])
    if isinstance(task, PostureTask):
        q = _array(target, field, f"{task.m} joint values [rad or m]")
        qdot = np.zeros(task.m) if velocity is None else _array(velocity, vfield, "velocities")
        for a, f in ((q, field), (qdot, vfield)):
            if a.shape != (task.m,) or not np.isfinite(a).all():
                raise InputError(f, f"{task.m} finite values (the posture's joints)", a.shape)
        return JointReference(t, q[None], qdot[None])
    if not task.has_orientation:  # a position task or a centre of mass
        given = _array(target, field, "a position (3,) [m]")
        pose = isinstance(target, pin.SE3) or given.shape == (4, 4)
        p = _pose(task, target, field)[0] if pose else given
        v, _ = _velocity(task, velocity, vfield)
        return _reference(t, p, v, None, None, field, vfield)
    p, R = _pose(task, target, field)
    v, w = _velocity(task, velocity, vfield)
    return _reference(t, p, v, R, w if R is not None else None, field, vfield)


def _reference(
    t: np.ndarray, p: np.ndarray | None, v: np.ndarray, R: np.ndarray | None,
    w: np.ndarray | None, field: str, vfield: str,
) -> Reference:  # fmt: skip
    if p is not None and p.shape != (3,):
        raise InputError(field, "a position (3,) [m]", f"shape {p.shape}")
    try:
        pos = {} if p is None else {"position": p[None], "linear_velocity": v[None]}
        rot = {} if R is None or w is None else {"rotation": R[None], "angular_velocity": w[None]}
        return Reference(t, **pos, **rot)
    except InputError as exc:  # named by what the caller gave: the target or its velocity
        velocity = "velocity" in f"{exc.field} {exc.got}"
        raise InputError(vfield if velocity else field, exc.expected, exc.got) from None


def by_name(value: Any, names: list[str], field: str) -> dict[str, Any]:
    """Targets (or velocities) by task name: a mapping, or one value with one task."""
    if isinstance(value, Mapping):
        unknown = sorted(set(value) - set(names))
        if unknown:
            raise InputError(field, f"task names among {names}", unknown[0])
        return dict(value)
    if len(names) != 1:
        raise InputError(field, f"a mapping of task name to target ({', '.join(names)})", value)
    return {names[0]: value}
