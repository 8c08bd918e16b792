"""Build a scenario's ``[[tasks]]`` and ``[[objectives]]``: goals, their trajectories, objectives.

Each ``[[tasks]]`` entry (:mod:`clik.scenarios.task_tables`) becomes a
:class:`~clik.tasks.goal.Goal`: the task its kind builds
(:meth:`~clik.tasks.kind.BaseTask.from_spec`) and its trajectory, which starts where the
task is at the start configuration ``q0`` (:meth:`~clik.tasks.kind.BaseTask.trajectory_from`).
Errors name the scenario key (``tasks[2].relative_to``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import ClikError, FrameNotFound, InputError, JointNotFound, ScenarioError
from clik.model.joints import JointValues
from clik.objectives.objective import Objective
from clik.tasks.goal import Goal
from clik.tasks.registry import kind_of_spec

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.scenarios.scenario import Scenario
    from clik.tasks.kind import BaseTask
    from clik.tasks.task import Task
    from clik.trajectory import Trajectory


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
        task: Any = self.goals[self.primary].task
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
            trajectory = task.trajectory_from(spec["trajectory"], q0)
        except InputError as exc:
            key = f"{where}.trajectory.{exc.field}".rstrip(".")
            raise _error(scenario, key, exc) from None
        goals.append(
            Goal(task, trajectory, name=spec["name"], priority=spec["priority"], gain=spec["gain"])
        )
    top = min(s["priority"] for s in scenario.tasks)
    primary = next(i for i, g in enumerate(goals) if g.task.leads and g.priority == top)
    return SeveralTasks(goals, primary, build_objectives(scenario, robot))


def _error(scenario: Scenario, key: str, exc: ClikError) -> ScenarioError:
    """``exc`` as a :class:`ScenarioError` at ``key`` (its own field not repeated)."""
    field = getattr(exc, "field", None)
    message = str(exc)
    if field and message.startswith(f"{field}: "):
        message = message[len(field) + 2 :]
    return ScenarioError(scenario.file, key, message)


def _task(scenario: Scenario, robot: Robot, spec: dict[str, Any], where: str) -> BaseTask:
    """The task of a ``[[tasks]]`` entry (its kind builds it); errors at ``tasks[i].<key>``."""
    try:
        return kind_of_spec(spec).from_spec(robot, spec)
    except FrameNotFound as exc:
        key = next((k for k, v in spec.items() if v == exc.name), "frame")
        raise _error(scenario, f"{where}.{key}", exc) from None
    except JointNotFound as exc:
        raise _error(scenario, f"{where}.joints", exc) from None
    except InputError as exc:
        key = exc.field.removeprefix("task.") if exc.field.startswith("task.") else "kind"
        raise _error(scenario, f"{where}.{key}", exc) from None


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
