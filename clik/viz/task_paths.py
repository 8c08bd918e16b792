"""Where each task of a several-task run went, and where it was asked to go, in the world.

A run with ``tasks=[clik.Goal(...), ...]`` records the primary task's path
(``result.position``, ``result.reference_position``) and the others' error norms
(``result.extra["task_errors"]``), but neither the other tasks nor their paths: the
result does not keep the goals. :func:`task_paths` computes them afterwards from the
recorded configurations ``result.q`` and the goals the run was given, on the recorded
times ``result.t``:

- a frame task (:class:`~clik.tasks.task.Task`): the frame's origin ``p(q)`` and its
  trajectory's positions ``p_d(t)`` [m];
- a relative task (:class:`~clik.tasks.relative_task.RelativeTask`, frame A in frame B):
  A's origin, and the reference ``p_d(t)`` (in B's axes) mapped to the world through B's
  placement at the recorded configuration, ``oMb(q) p_d(t)`` [m]: where A should be,
  seen from where B is;
- a centre-of-mass task (:class:`~clik.tasks.com_task.ComTask`): ``c(q)`` and ``c_d(t)`` [m];
- a posture task has no path in space (it has none here).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.tasks.com_task import ComTask
from clik.tasks.goal import Goal
from clik.tasks.posture_task import PostureTask
from clik.tasks.relative_task import RelativeTask
from clik.tasks.task import Task

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult


@dataclass(frozen=True)
class TaskPath:
    """One task's path in the world over a run's recorded samples.

    Attributes:
        name: The task's name (its key in ``result.task_errors``).
        kind: The task's kind (``"pose"``, ``"position"``, ``"orientation"``, ``"com"``).
        primary: Whether it is the run's primary task (drawn as ``result.position``).
        achieved: The tracked point at each recorded sample (N, 3) [m].
        reference: Where it was asked to be (N, 3) [m]; None for an orientation task.
    """

    name: str
    kind: str
    primary: bool
    achieved: np.ndarray
    reference: np.ndarray | None


def goal_names(goals: Sequence[Goal]) -> list[str]:
    """The goals' names as a run names them: ``goal.name``, else ``"task<i>"`` (1-based)."""
    return [g.name or f"task{i + 1}" for i, g in enumerate(goals)]


def checked_goals(result: TrackingResult, goals: Sequence[Goal]) -> list[str]:
    """The goals' names, checked against the run's (``result.info["tasks"]``).

    Raises:
        InputError: Not a list of goals, or not the goals the run was given.
    """
    if isinstance(goals, Goal) or not isinstance(goals, Sequence) or not goals:
        raise InputError("tasks", "the list of clik.Goal the run was given", type(goals).__name__)
    bad = [type(g).__name__ for g in goals if not isinstance(g, Goal)]
    if bad:
        raise InputError("tasks", "a list of clik.Goal", bad[0])
    names = goal_names(goals)
    ran = result.info.get("tasks")
    if ran is None:
        raise InputError(
            "tasks",
            "a result of a run with tasks=[...] (its info['tasks'] names them)",
            "a one-task result",
        )
    if sorted(names) != sorted(ran):
        raise InputError("tasks", f"the goals the run was given, named {list(ran)}", names)
    return names


def task_paths(
    result: TrackingResult, goals: Sequence[Goal], robot: Robot | None = None
) -> list[TaskPath]:
    """Each frame, relative and centre-of-mass task's path over the run (module docstring).

    Args:
        result: A run with ``tasks=goals``.
        goals: The goals it was given (any order).
        robot: The robot, when ``result.robot`` is not set.

    Returns:
        One path per goal with a point in space, in the run's row order (the primary
        first); posture tasks are left out.

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
    frames = _frame_placements(robot, q, [by_name[n].task for n in order])
    paths = []
    for i, name in enumerate(order):
        goal = by_name[name]
        if isinstance(goal.task, PostureTask):
            continue
        achieved, reference = _points(goal, t, q, frames, robot)
        paths.append(TaskPath(name, goal.task.kind, i == 0, achieved, reference))
    return paths


def _frame_placements(
    robot: Robot, q: np.ndarray, tasks: Sequence[object]
) -> dict[int, list[pin.SE3]]:
    """The world placements of the frames the tasks read, at every recorded sample."""
    ids: set[int] = set()
    for task in tasks:
        if isinstance(task, Task | RelativeTask):
            ids.add(int(task.frame_id))
        if isinstance(task, RelativeTask):
            ids.add(int(task.relative_id))
    model = robot.model
    data = model.createData()
    out: dict[int, list[pin.SE3]] = {i: [] for i in ids}
    for qk in q if ids else ():
        pin.forwardKinematics(model, data, qk)
        for i in ids:
            out[i].append(pin.updateFramePlacement(model, data, i).copy())
    return out


def _points(
    goal: Goal, t: np.ndarray, q: np.ndarray, frames: dict[int, list[pin.SE3]], robot: Robot
) -> tuple[np.ndarray, np.ndarray | None]:
    """``(achieved (N, 3), reference (N, 3) or None)`` of one goal [m]."""
    task = goal.task
    ref = goal.trajectory.sample(t)
    p_d = getattr(ref, "position", None)
    reference = None if p_d is None else np.array(p_d, dtype=float).reshape(len(t), 3)
    if isinstance(task, ComTask):
        data = robot.model.createData()
        achieved = np.array([pin.centerOfMass(robot.model, data, qk) for qk in q])
        return achieved.reshape(len(t), 3), reference
    if not isinstance(task, Task | RelativeTask):
        raise InputError("tasks.task", "a frame, relative or com task", type(task).__name__)
    achieved = np.array([m.translation for m in frames[int(task.frame_id)]]).reshape(len(t), 3)
    if not task.has_position:
        reference = None
    if isinstance(task, RelativeTask) and reference is not None:
        oMb = frames[int(task.relative_id)]
        reference = np.array([m.act(p) for m, p in zip(oMb, reference, strict=True)])
    return achieved, reference
