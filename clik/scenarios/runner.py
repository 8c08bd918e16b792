"""Turn a validated :class:`~clik.scenarios.scenario.Scenario` into objects, and run it.

Errors raised while building (an unknown frame, an infeasible trajectory
timing, an unknown joint in a lock or override) are re-raised as
:class:`~clik.errors.ScenarioError` naming the scenario file and key path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from clik.constraints.constraint_set import ConstraintSet
from clik.errors import (
    ClikError,
    FrameNotFound,
    InfeasibleError,
    InputError,
    JointNotFound,
    ScenarioError,
)
from clik.loop.joint_speed import JointSpeed
from clik.loop.tracker import Tracker
from clik.loop.tracking import ProgressCallback
from clik.model.reach import reach_bound
from clik.model.robot import Robot
from clik.outputs.result import TrackingResult
from clik.scenarios.build_tasks import SeveralTasks, build_objectives, build_several
from clik.scenarios.scenario import Scenario, check_dt, load_scenario
from clik.schema import Table
from clik.speed.speed_limits import SpeedLimits
from clik.speed.velocity_limits import run_within_limits
from clik.tasks.goal import Goal
from clik.tasks.task import Task
from clik.trajectory import Trajectory


@dataclass
class Run:
    """Everything a scenario builds: robot, task, trajectory, tracker and start.

    ``speed_limits`` is set when ``[constraints.velocity_limits]`` is enabled: the run
    is then re-timed until the joint speeds are within limits
    (:func:`clik.speed.velocity_limits.run_within_limits`).
    """

    scenario: Scenario
    robot: Robot
    task: Task
    trajectory: Trajectory
    tracker: Tracker
    q0: np.ndarray
    speed_limits: SpeedLimits | None = None
    goals: list[Goal] = field(default_factory=list)
    """``[[tasks]]``: every goal (``task`` and ``trajectory`` are then the primary's)."""
    scenario_file: str = ""
    """The scenario file's absolute path (resolved when built: ``info["scenario_file"]``);
    empty: resolved when the run executes."""

    def execute(self, progress: ProgressCallback | None = None) -> TrackingResult:
        """Run the tracking loop (in re-timing passes when ``speed_limits`` is set)."""
        solver = self.scenario.solver
        kwargs = {
            key: solver[key] for key in ("record_every", "settle", "tolerance", "settling_time")
        }
        if self.speed_limits is None:
            trajectory = None if self.goals else self.trajectory  # each goal has its own
            result = self.tracker.run(trajectory, self.q0, progress=progress, **kwargs)
        else:
            result = run_within_limits(
                self.tracker, self.trajectory, self.q0, self.speed_limits, progress=progress,
                **kwargs,
            )  # fmt: skip
        result.info["scenario"] = self.scenario.name
        result.info["scenario_file"] = self.scenario_file or str(self.scenario.file.resolve())
        result.info["robot_source"] = self.scenario.robot["source"]
        result.info["robot_lock"] = dict(self.scenario.robot["lock"])
        cset = self.tracker.constraints
        scene = None if cset is None else cset.scene
        if scene is not None:  # hulls coal could not build: not checked against obstacles
            result.info["unmonitored_geometries"] = list(scene.skipped_geometries)
        if self.scenario.robot.get("xacro_args"):
            result.info["robot_xacro_args"] = dict(self.scenario.robot["xacro_args"])
        if self.scenario.robot.get("base", "fixed") != "fixed":  # clik show rebuilds it
            result.info["robot_base"] = self.scenario.robot["base"]
            result.info["robot_base_speed"] = self.scenario.robot.get("base_speed")
        if self.goals:
            result.info["task_units"] = {str(g.name): g.task.norms[0].unit for g in self.goals}
        return result


def _where(scenario: Scenario, key: str, exc: ClikError) -> ScenarioError:
    message = str(exc)
    field = getattr(exc, "field", None)
    if field and message.startswith(f"{field}: "):  # do not repeat the field
        message = message[len(field) + 2 :]
    return ScenarioError(scenario.file, key, message)


def _robot_key(exc: ClikError) -> str:
    """The ``[robot]`` key a robot's loading error is about (``lock`` unless it says)."""
    field = str(getattr(exc, "field", ""))
    for key in ("xacro_args", "package_dirs", "srdf"):
        if field.startswith(key):
            return f"robot.{key}"
    return "robot.lock"


def build(scenario: Scenario | str | Path, robot: Robot | None = None) -> Run:
    """Build the objects of a scenario (loads the robot; computes nothing else).

    Args:
        scenario: A scenario or the path of a scenario file.
        robot: The scenario's robot, loaded earlier (e.g. once per sweep worker);
            default: load it from ``[robot]``.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    robot = _robot(scenario) if robot is None else robot
    try:
        q0 = robot.check_configuration(
            robot.q_reference if scenario.initial_q is None else scenario.initial_q, "initial.q"
        )
    except InputError as exc:
        raise _where(scenario, "initial.q", exc) from None
    try:
        robot.check_within_limits(q0, "initial.q")
    except InfeasibleError as exc:
        raise InfeasibleError(f"{scenario.file}: {exc.field}", exc.problem) from None
    several = None
    if scenario.tasks:
        several = build_several(scenario, robot, q0)
        task, trajectory, duration = several.task, several.trajectory, several.duration
        timed = any(t["trajectory"]["duration"] is None for t in scenario.tasks)
    else:
        task, trajectory = _single_task(scenario, robot, q0)
        duration, timed = float(trajectory.duration), scenario.trajectory["duration"] is None
    if timed:  # timed by cruise_speed: known only now
        check_dt(Table({}, scenario.file, "solver"), scenario.solver["dt"], duration)
    constraints = None
    if scenario.has_constraints:
        from clik.scenarios.build_constraints import build_constraints

        constraints = build_constraints(scenario, robot, task)
    tracker = _tracker(scenario, task, constraints, several)
    try:  # a run too long, or a record too large for memory: said before any output
        tracker.check_size(
            duration + scenario.solver["settle"], int(scenario.solver["record_every"])
        )
    except InputError as exc:
        raise _where(scenario, f"solver.{exc.field}", exc) from None
    return Run(
        scenario, robot, task, trajectory, tracker, q0, _speed_limits(scenario, robot),
        goals=[] if several is None else several.goals,
        scenario_file=str(scenario.file.resolve()),
    )  # fmt: skip


def _robot(scenario: Scenario) -> Robot:
    """The scenario's ``[robot]``, loaded; errors at its keys."""
    spec = scenario.robot
    try:
        return Robot.load(
            spec["source"],
            package_dirs=spec["package_dirs"] or None,
            lock=spec["lock"] or None,
            xacro_args=spec.get("xacro_args") or None,
            srdf=spec.get("srdf"),
            base=spec.get("base", "fixed"),
            base_speed=spec.get("base_speed"),
        )
    except (JointNotFound, InputError) as exc:
        raise _where(scenario, _robot_key(exc), exc) from None
    except ClikError as exc:
        srdf = spec.get("srdf")
        source = Path(getattr(exc, "source", ""))  # a xacro SRDF's errors name it resolved
        about_srdf = isinstance(srdf, str) and source.resolve() == Path(srdf).resolve()
        raise _where(scenario, "robot.srdf" if about_srdf else "robot.source", exc) from None


def _single_task(scenario: Scenario, robot: Robot, q0: np.ndarray) -> tuple[Task, Trajectory]:
    """``[task]`` and its ``[trajectory]``, from the start ``q0``."""
    try:
        task = Task(robot, scenario.task["frame"], scenario.task["kind"], scenario.task["axes"])
    except FrameNotFound as exc:
        raise _where(scenario, "task.frame", exc) from None
    except InputError as exc:
        raise _where(scenario, exc.field, exc) from None
    try:
        return task, task.trajectory_from(scenario.trajectory, q0)
    except InputError as exc:
        _check_goal_reach(scenario, robot, task)  # name the real cause first
        raise _where(scenario, f"trajectory.{exc.field}", exc) from None


def _tracker(
    scenario: Scenario, task: Task, constraints: ConstraintSet | None, several: SeveralTasks | None
) -> Tracker:
    """The scenario's tracker: one task, or ``[[tasks]]`` and ``[[objectives]]``."""
    solver = scenario.solver
    objectives = build_objectives(scenario, task.robot) if several is None else several.objectives
    try:
        return Tracker(
            None if several else task,
            law=solver["law"],
            gain=solver["gain"],
            dt=solver["dt"],
            damping=solver["damping"],
            constraints=constraints,
            engine=solver["engine"],
            joint_speed=_joint_speed(scenario),
            tasks=None if several is None else several.goals,
            objectives=objectives or None,
        )
    except JointNotFound as exc:
        raise _where(scenario, _joint_speed_key(scenario, exc.name), exc) from None
    except InputError as exc:
        raise _where(scenario, _tracker_key(scenario, exc.field), exc) from None


def _tracker_key(scenario: Scenario, field: str) -> str:
    """The scenario key of a field the tracker refused."""
    if field.startswith("joint_speed"):
        return f"constraints.{field}"
    if field.startswith(("tasks", "objectives")):
        names = [t["name"] for t in scenario.tasks]
        for i, name in enumerate(names):  # the tracker names a task tasks['<name>'].<key>
            if field.startswith(f"tasks[{name!r}]"):
                return field.replace(f"tasks[{name!r}]", f"tasks[{i}]", 1)
        return field.split(".")[0]
    return "solver.law" if field == "constraints" else f"solver.{field}"


def _joint_speed(scenario: Scenario) -> JointSpeed | None:
    """The scenario's ``[constraints.joint_speed]`` (None when ``enabled = false``)."""
    spec = scenario.joint_speed
    if not spec.get("enabled", True):
        return None
    keys = ("scale", "velocity", "default_velocity", "acceleration")
    return JointSpeed(**{k: spec[k] for k in keys if k in spec})


def _joint_speed_key(scenario: Scenario, joint: str) -> str:
    """The ``[constraints.joint_speed]`` key that names an unknown joint."""
    spec = scenario.joint_speed
    key = "velocity" if joint in (spec.get("velocity") or {}) else "acceleration"
    return f"constraints.joint_speed.{key}"


def _speed_limits(scenario: Scenario, robot: Robot) -> SpeedLimits | None:
    """The scenario's ``[constraints.velocity_limits]``, checked against the robot (or None)."""
    spec = scenario.velocity_limits
    if not spec.get("enabled"):
        return None
    key = "constraints.velocity_limits"
    settings = {k: spec[k] for k in ("scale", "acceleration", "margin", "max_passes", "window")}
    try:
        limits = SpeedLimits(**settings)
        limits.bounds(robot)  # an unknown joint or a robot without limits: now, not after a run
    except JointNotFound as exc:
        raise _where(scenario, f"{key}.acceleration", exc) from None
    except InputError as exc:
        raise _where(scenario, exc.field.replace("velocity_limits", key, 1), exc) from None
    return limits


def _check_goal_reach(scenario: Scenario, robot: Robot, task: Task) -> None:
    """Raise :class:`InfeasibleError` when the scenario's goal lies beyond the frame's reach.

    A trajectory that cannot be built (e.g. its cruise speed cannot cover the distance in
    its duration) often has an unreachable goal: that is the error worth reading.
    """
    goal = scenario.trajectory.get("goal")
    if goal is None or not task.has_position:
        return
    center, reach, first = reach_bound(robot, task.frame_id)
    distance = float(np.linalg.norm(np.asarray(goal, dtype=float)[:3] - center))
    if math.isfinite(reach) and distance > reach + 1e-9:
        raise InfeasibleError(
            f"{scenario.file}: trajectory.goal",
            f"the goal is out of reach: it lies {distance:.4g} m from joint {first!r}, farther "
            f"than the {reach:.4g} m that frame {task.frame!r} can reach",
        )


def run_scenario(
    scenario: Scenario | str | Path, progress: ProgressCallback | None = None
) -> TrackingResult:
    """Load, build and run a scenario file; returns the tracking result."""
    return build(scenario).execute(progress)
