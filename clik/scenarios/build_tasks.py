"""Build a scenario's ``[[tasks]]`` and ``[[objectives]]``: goals, their trajectories, objectives.

Each ``[[tasks]]`` entry (:mod:`clik.scenarios.task_tables`) becomes a
:class:`~clik.tasks.goal.Goal`: its task (:class:`~clik.tasks.task.Task`,
:class:`~clik.tasks.relative_task.RelativeTask`, :class:`~clik.tasks.posture_task.PostureTask`
or :class:`~clik.tasks.com_task.ComTask`) and its trajectory, which starts where the task
is at the start configuration ``q0``: a frame's pose (in ``relative_to``'s axes for a
relative task), the centre of mass, the joints' values. Joint values written in degrees
are converted here, per joint: revolute and continuous joints from ``unit``, prismatic
ones kept in metres. Errors name the scenario key (``tasks[2].relative_to``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import ClikError, FrameNotFound, InputError, JointNotFound, ScenarioError
from clik.model.joints import PRISMATIC, JointValues, unit_scale
from clik.objectives.objective import Objective
from clik.tasks.com_task import ComTask
from clik.tasks.goal import Goal
from clik.tasks.posture_task import PostureTask
from clik.tasks.relative_task import RelativeTask
from clik.tasks.task import Task
from clik.trajectory import (
    Circle,
    Hold,
    JointPath,
    Line,
    PoseTrajectory,
    Slerp,
    Trajectory,
    Waypoints,
)

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.scenarios.scenario import Scenario
    from clik.tasks.kind import BaseTask


@dataclass
class SeveralTasks:
    """What a scenario's ``[[tasks]]`` builds.

    Attributes:
        goals: One goal per ``[[tasks]]`` table, in the file's order.
        primary: The primary goal's index (the run's primary task, constraints read it).
        objectives: The ``[[objectives]]``.
    """

    goals: list[Goal]
    primary: int
    objectives: list[Objective]

    @property
    def task(self) -> Task:
        """The primary task (a frame task in the world)."""
        task = self.goals[self.primary].task
        assert isinstance(task, Task)
        return task

    @property
    def trajectory(self) -> Trajectory:
        """The primary task's trajectory."""
        return self.goals[self.primary].trajectory

    @property
    def duration(self) -> float:
        """The longest trajectory [s]: the run's (each task holds its end after its own)."""
        return max(float(g.trajectory.duration) for g in self.goals)


def build_several(scenario: Scenario, robot: Robot, q0: np.ndarray) -> SeveralTasks:
    """The goals of ``[[tasks]]`` and the ``[[objectives]]``, from the start ``q0``.

    Raises:
        ScenarioError: A frame, joint, trajectory or value the robot refuses (its key).
    """
    goals = []
    for i, spec in enumerate(scenario.tasks):
        where = f"tasks[{i}]"
        task = _task(scenario, robot, spec, where)
        try:
            trajectory = _trajectory(spec, task, q0)
        except InputError as exc:
            key = f"{where}.trajectory.{exc.field}".rstrip(".")
            raise _error(scenario, key, exc) from None
        goals.append(
            Goal(task, trajectory, name=spec["name"], priority=spec["priority"], gain=spec["gain"])
        )
    top = min(s["priority"] for s in scenario.tasks)
    primary = next(i for i, g in enumerate(goals) if type(g.task) is Task and g.priority == top)
    return SeveralTasks(goals, primary, build_objectives(scenario, robot))


def _error(scenario: Scenario, key: str, exc: ClikError) -> ScenarioError:
    """``exc`` as a :class:`ScenarioError` at ``key`` (its own field not repeated)."""
    field = getattr(exc, "field", None)
    message = str(exc)
    if field and message.startswith(f"{field}: "):
        message = message[len(field) + 2 :]
    return ScenarioError(scenario.file, key, message)


def _task(scenario: Scenario, robot: Robot, spec: dict[str, Any], where: str) -> BaseTask:
    """The task of a ``[[tasks]]`` entry; errors at ``tasks[i].<key>``."""
    kind = spec["kind"]
    try:
        if kind == "posture":
            return PostureTask(robot, spec["joints"])
        if kind == "com":
            return ComTask(robot, spec["axes"])
        if spec["relative_to"] is not None:
            return RelativeTask(robot, spec["frame"], spec["relative_to"], kind, spec["axes"])
        return Task(robot, spec["frame"], kind, spec["axes"])
    except FrameNotFound as exc:
        key = "frame" if exc.name == spec["frame"] else "relative_to"
        raise _error(scenario, f"{where}.{key}", exc) from None
    except JointNotFound as exc:
        raise _error(scenario, f"{where}.joints", exc) from None
    except InputError as exc:
        key = exc.field.removeprefix("task.") if exc.field.startswith("task.") else "kind"
        raise _error(scenario, f"{where}.{key}", exc) from None


def _trajectory(spec: dict[str, Any], task: BaseTask, q0: np.ndarray) -> Trajectory:
    """A task's trajectory, from where the task is at ``q0``."""
    if isinstance(task, PostureTask):
        return joint_path(spec["trajectory"], task, q0)
    if isinstance(task, ComTask):
        start = pin.SE3(np.eye(3), task.position(q0))
    else:
        assert isinstance(task, Task | RelativeTask)
        start = task.placement(q0)
    return build_trajectory(spec["trajectory"], task, start)


def error_unit(task: BaseTask) -> str:
    """The unit of a task's error norm ``task_errors[name]["max"]``: ``"m"``, ``"rad"`` ...

    A frame task's position rows [m] (its orientation rows [rad] without them), the centre
    of mass [m], a posture's joints: [rad], [m] for prismatic joints only, else
    ``"rad, m"`` (a norm over both).
    """
    if isinstance(task, PostureTask):
        kinds = {task.robot.joint_kinds[j] == PRISMATIC for j in task.joints}
        return "rad, m" if len(kinds) > 1 else ("m" if True in kinds else "rad")
    return "m" if getattr(task, "has_position", True) else "rad"


def joint_scale(task: PostureTask, unit: str) -> np.ndarray:
    """Per joint of ``task``, the factor from its written value to [rad] or [m]."""
    kinds = task.robot.joint_kinds
    angle = unit_scale(unit, "unit")
    return np.array([1.0 if kinds[j] == PRISMATIC else angle for j in task.joints])


def joint_path(spec: dict[str, Any], task: PostureTask, q0: np.ndarray) -> JointPath:
    """A posture task's reference: hold (the start, or ``values``), or move through waypoints.

    Raises:
        InputError: Values of the wrong length (field ``values`` or ``waypoints``).
    """
    scale = joint_scale(task, spec["unit"])
    start = task.angles(q0)
    duration = float(spec["duration"])
    if spec["kind"] == "hold":
        held = start if spec["values"] is None else _values(spec["values"], task, scale, "values")
        return JointPath([held, held], duration=duration) if duration > 0 else JointPath(held)
    rows = [_values(row, task, scale, f"waypoints[{k}]") for k, row in enumerate(spec["waypoints"])]
    if spec["times"] is not None:
        return JointPath([start, *rows], times=[0.0, *spec["times"]])
    return JointPath([start, *rows], duration=duration)


def _values(values: list[float], task: PostureTask, scale: np.ndarray, field: str) -> np.ndarray:
    if len(values) != task.m:
        raise InputError(
            field, f"{task.m} values, one per joint of the posture task ({', '.join(task.joints)})",
            f"{len(values)} values",
        )  # fmt: skip
    return np.asarray(values, dtype=float) * scale


def build_objectives(scenario: Scenario, robot: Robot) -> list[Objective]:
    """The ``[[objectives]]`` (a posture objective's ``posture`` checked against the robot)."""
    out = []
    for i, spec in enumerate(scenario.objectives):
        posture = None
        if spec["posture"] is not None:
            key = f"objectives[{i}].posture"
            try:
                posture = robot.check_configuration(JointValues(spec["posture"], spec["unit"]), key)
            except InputError as exc:
                raise _error(scenario, key, exc) from None
        out.append(Objective(spec["kind"], spec["gain"], spec["priority"], posture))
    return out


def build_trajectory(
    spec: dict[str, Any], task: Task | RelativeTask | ComTask, start: pin.SE3
) -> Trajectory:
    """The trajectory of a scenario's ``[trajectory]`` table, starting at the frame's pose."""
    p0 = start.translation.copy() if spec["start"] is None else np.asarray(spec["start"])
    kind, duration, speed = spec["kind"], spec["duration"], spec.get("cruise_speed")
    position: Trajectory
    if kind == "line":
        position = Line(p0, spec["goal"], duration=duration, cruise_speed=speed)
    elif kind == "circle":
        position = Circle.through(
            p0, spec["center"], spec["normal"], spec["angle"], duration=duration, cruise_speed=speed
        )
    elif kind == "waypoints":
        points = np.vstack([p0, np.asarray(spec["points"])])
        position = Waypoints(
            points, duration=duration, cruise_speed=speed, blend_radius=spec["blend_radius"]
        )
    else:
        goal = p0 if spec["goal"] is None else np.asarray(spec["goal"])
        position = Hold(position=goal, duration=duration)
    if not task.has_orientation:
        return position
    R0 = start.rotation.copy()
    rpy = spec["goal_rpy"]
    if rpy is None:
        orientation: Trajectory = Hold(rotation=R0, duration=position.duration)
    else:
        orientation = Slerp(R0, pin.rpy.rpyToMatrix(*rpy), duration=position.duration)
    if not task.has_position:
        return orientation
    return PoseTrajectory(position, orientation)
