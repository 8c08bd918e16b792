"""Where each task of a several-task run went, and where it was asked to go, in the world.

A run with ``tasks=[clik.Goal(...), ...]`` records the primary task's path
(``result.position``, ``result.reference_position``) and the others' error norms
(``result.extra["task_errors"]``), but neither the other tasks nor their paths: the
result does not keep the goals. :func:`task_paths` computes them afterwards from the
recorded configurations ``result.q`` and the goals the run was given, on the recorded
times ``result.t``, each as its kind draws it
(:meth:`~clik.tasks.kind.BaseTask.trail`: the achieved point and the reference point at
a sample). For example a frame task's origin ``p(q)`` and its reference ``p_d(t)``; a
relative task's A origin and its reference mapped to the world through B's placement
``oMb(q) p_d(t)``; the centre of mass. A kind with no point in space (a posture) has no
path here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.outputs.goal_check import checked_goals
from clik.tasks.goal import Goal

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult


@dataclass(frozen=True)
class TaskPath:
    """One task's path in the world over a run's recorded samples.

    Attributes:
        name: The task's name (its key in ``result.task_errors``).
        kind: The task's kind (``"pose"``, ``"com"``, ...).
        primary: Whether it is the run's primary task (drawn as ``result.position``).
        achieved: The tracked point at each recorded sample (N, 3) [m].
        reference: Where it was asked to be (N, 3) [m]; None where its kind has no point
            (an orientation task).
    """

    name: str
    kind: str
    primary: bool
    achieved: np.ndarray
    reference: np.ndarray | None


def task_paths(
    result: TrackingResult, goals: Sequence[Goal], robot: Robot | None = None
) -> list[TaskPath]:
    """Each task's path over the run, as its kind draws it (module docstring).

    Args:
        result: A run with ``tasks=goals``.
        goals: The goals it was given (any order).
        robot: The robot, when ``result.robot`` is not set.

    Returns:
        One path per goal with a point in space, in the run's row order (the primary
        first); kinds with no point (a posture) are left out.

    Raises:
        InputError: Not the run's goals, a task on another robot than the result's, or
            no robot.
    """
    names = checked_goals(result, goals)
    robot = robot if robot is not None else result.robot
    if robot is None:
        raise InputError("robot", "the Robot the result was computed with")
    by_name = dict(zip(names, goals, strict=True))
    order = [n for n in result.info["tasks"] if n in by_name]
    if any(g.task.robot.nq != robot.nq for g in goals):
        raise InputError("tasks", f"tasks on {robot.name} (nq = {robot.nq})")
    t, q = np.asarray(result.t, dtype=float), np.asarray(result.q, dtype=float)
    model = robot.model
    data = model.createData()
    refs = [by_name[n].task.reference_arrays(by_name[n].trajectory.sample(t))[0] for n in order]
    points: list[list[tuple[np.ndarray, np.ndarray | None] | None]] = [[] for _ in order]
    for k, qk in enumerate(q):
        pin.forwardKinematics(model, data, qk)
        pin.updateFramePlacements(model, data)
        pin.centerOfMass(model, data, qk, False)
        for i, name in enumerate(order):
            points[i].append(by_name[name].task.trail(model, data, refs[i][k]))
    paths = []
    for i, name in enumerate(order):
        if not points[i] or points[i][0] is None:
            continue  # no point in space (a posture)
        trail = [p for p in points[i] if p is not None]
        achieved = np.array([a for a, _ in trail], dtype=float).reshape(len(t), 3)
        reference = (
            None
            if trail[0][1] is None
            else np.array([r for _, r in trail], dtype=float).reshape(len(t), 3)
        )
        paths.append(TaskPath(name, by_name[name].task.kind, i == 0, achieved, reference))
    return paths
