"""The task points a replay measures: each frame task's origin and the centre of mass.

A replay compares where a task's point went in the simulation with where its reference
wanted it (docs/method.md, "A physics check"): the scenario's trajectories, rebuilt from
the run's scenario file; without it, the one task the output folder records
(``position`` and ``reference_position`` of ``trajectory.npz``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from clik.model.robot import Robot
from clik.outputs.result import TrackingResult
from clik.tasks.com_task import ComTask
from clik.tasks.task import Task


@dataclass
class TaskPoint:
    """A point of a task, its reference and the axes it is held on.

    Attributes:
        name: The task's name (``task_errors``' key).
        frame_id: The frame whose origin it is, or -1 for the centre of mass.
        axes: The world axes held (indices among x, y, z).
        reference: Its reference at the run's sample times (N, 3) [m].
    """

    name: str
    frame_id: int
    axes: np.ndarray
    reference: np.ndarray

    def points(self, robot: Robot, q: np.ndarray) -> np.ndarray:
        """The point [m] (N, 3) at each configuration (N, nq)."""
        model, data = robot.model, robot.model.createData()
        out = np.empty((len(q), 3))
        for k, qk in enumerate(q):
            if self.frame_id < 0:
                out[k] = pin.centerOfMass(model, data, qk)
            else:
                pin.framesForwardKinematics(model, data, qk)
                out[k] = data.oMf[self.frame_id].translation
        return out

    def errors(self, robot: Robot, q: np.ndarray) -> np.ndarray:
        """The distance [m] (N,) from the reference on the held axes."""
        gap = self.points(robot, q) - self.reference
        return np.asarray(np.linalg.norm(gap[:, self.axes], axis=1))


def _goal_point(
    name: str, task: Any, trajectory: Any, t: np.ndarray, q0: np.ndarray
) -> TaskPoint | None:
    """A frame task's or a centre-of-mass task's point; None for any other task."""
    if isinstance(task, Task):
        if not task.has_position:
            return None
        frame_id, axes = task.frame_id, task.rows[task.rows < 3]
    elif isinstance(task, ComTask):
        frame_id, axes = -1, task.rows
    else:
        return None
    if trajectory is None:  # held where it starts
        start = TaskPoint(name, frame_id, axes, np.zeros((1, 3))).points(task.robot, q0[None])
        reference = np.repeat(start, len(t), axis=0)
    else:
        position = trajectory.sample(t).position
        if position is None:
            return None
        reference = np.asarray(position, dtype=float)
    return TaskPoint(name, frame_id, np.asarray(axes, dtype=np.intp), reference)


def task_points(result: TrackingResult, run: Any | None) -> list[TaskPoint]:
    """The points to measure: from the rebuilt scenario run, else the recorded task.

    A run re-timed for its joint speed limits (a reference longer than the scenario's)
    is measured on its recorded task only.

    Args:
        result: The saved run (``result.robot`` set).
        run: The scenario's :class:`~clik.scenarios.runner.Run`, or None.
    """
    t, q0 = result.t, result.q[0]
    points: list[TaskPoint] = []
    duration = result.info.get("duration")
    if run is not None and duration is not None and abs(run.trajectory.duration - duration) > 1e-9:
        run = None  # re-timed (joint speed limits): only the recorded reference holds
    if run is not None:
        if run.goals:
            stack = run.tracker.stack
            for goal, name in zip(stack.goals, stack.names, strict=True):
                point = _goal_point(name, goal.task, goal.trajectory, t, q0)
                if point is not None:
                    points.append(point)
        else:
            point = _goal_point("task", run.task, run.trajectory, t, q0)
            if point is not None:
                points.append(point)
        return points
    robot = result.robot
    frame = result.info.get("frame")
    if robot is None or result.reference_position is None or not frame:
        return points
    axes = np.array([i for i, a in enumerate("xyz") if a in result.info.get("axes", "xyz")])
    frame_id = robot.model.getFrameId(str(frame))
    return [TaskPoint("task", frame_id, axes, np.asarray(result.reference_position, float))]
