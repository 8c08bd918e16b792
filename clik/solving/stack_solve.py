"""Solve mode with several tasks: every task of the first level reaches its target.

``clik.solve(tasks=[clik.Goal(task, target_trajectory, ...), ...])``: each goal's
target is its trajectory's final value (a :class:`~clik.trajectory.Hold` pose, a
:class:`~clik.trajectory.JointPath` posture), held. Law (10) by priority levels
(docs/method.md, "Several tasks") is iterated on the held targets as a fixed-point
map, one sample per iteration with ``K dt = step`` (a Gauss-Newton step, each level
damped near singularities and held to the step budget), by the tracker in the engine
asked for, without joint speed limits; an attempt ends converged when every task of
the first level is within the tolerances, else (out of iterations, or stopped by the
deadlock checks) restarts from a seeded random configuration within the limits.
Lower levels and objectives shape the pose the first level reaches.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.loop.start_checks import unchecked_starts
from clik.loop.task_stack import TaskStack
from clik.loop.tracker import ReachWarning, Tracker
from clik.solving.solve_problem import SolveSettings, check_seed, check_settings
from clik.solving.solve_result import SolveResult
from clik.tasks.goal import Goal
from clik.trajectory.joint_path import JointReference
from clik.trajectory.reference import Reference

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.objectives.objective import Objective

DT = 1e-3
"""The iteration's time step [s] (only ``K dt = step`` matters)."""


class HeldEnd:
    """A trajectory's final value, held with zero velocity (a solve's target)."""

    def __init__(self, trajectory: Any) -> None:
        self.trajectory = trajectory
        self.duration = 0.0

    def sample(self, t: np.ndarray) -> Reference | JointReference:
        """The final value at every time of ``t``."""
        t = np.asarray(t, dtype=float)
        end = self.trajectory.sample(np.full(t.shape, float(self.trajectory.duration)))
        if isinstance(end, JointReference):
            return JointReference(t, end.q, np.zeros_like(end.q))
        lin = None if end.position is None else np.zeros_like(end.position)
        ang = None if end.rotation is None else np.zeros((t.shape[0], 3))
        return Reference(t, end.position, lin, end.rotation, ang)


def solve_tasks(
    task: object,
    target: object,
    goals: Sequence[Goal] | None,
    q0: object,
    constraints: ConstraintSet | None,
    objectives: Sequence[Objective] | None,
    settings: dict[str, Any],
) -> SolveResult:
    """:func:`clik.solve` with several tasks (the module's method).

    Args:
        task: None (``solve``'s single task: refused with ``goals``).
        target: None, likewise.
        goals: The goals; each target is its trajectory's final value.
        q0: Start configuration (None: the robot's reference).
        constraints: Constraint rows kept while iterating (law (10): constraints first).
        objectives: Eq. (5)'s objectives, below the levels.
        settings: ``solve``'s ``law``, ``step``, ``damping``, ``tolerance``,
            ``orientation_tolerance``, ``max_iterations``, ``restarts``, ``seed``, ``engine``.

    Raises:
        InputError: A bad goal or setting (named).
    """
    s = settings
    stack = _checked(task, target, goals, s)
    held = [
        Goal(g.task, HeldEnd(g.trajectory), name=n, priority=g.priority)
        for g, n in zip(stack.goals, stack.names, strict=True)
    ]
    tracker = Tracker(
        tasks=held, law="pseudoinverse", gain=float(s["step"]) / DT, dt=DT,
        damping=float(s["damping"]), constraints=constraints, engine=s["engine"],
        joint_speed=None, objectives=objectives,
    )  # fmt: skip
    robot = stack.robot
    q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
    top = [n for n, lv in zip(stack.names, stack.levels, strict=True) if lv == 1]
    rng = None
    iterations, best = 0, (math.inf, q.copy(), math.inf, math.inf, "")
    start = time.perf_counter()
    for attempt in range(1, s["restarts"] + 2):
        with warnings.catch_warnings(), unchecked_starts():  # no StartWarning
            warnings.simplefilter("ignore", ReachWarning)
            n = s["max_iterations"]
            result = tracker.run(q0=q, settle=n * DT, record_every=n + 1)
        iterations += result.steps
        pos, rot = _largest_errors([result.task_errors[n] for n in top])
        q_end = result.q[-1].copy()
        inside = bool(np.all(q_end >= robot.lower - 1e-9) and np.all(q_end <= robot.upper + 1e-9))
        wall = time.perf_counter() - start
        if pos <= s["tolerance"] and rot <= s["orientation_tolerance"] and inside:
            reason = f"converged in {iterations} iterations ({len(stack.goals)} tasks)"
            return SolveResult(True, reason, q_end, iterations, attempt, pos, rot, wall)
        if pos + rot < best[0]:
            best = (pos + rot, q_end, pos, rot, "" if inside else "; a joint left its range")
        if attempt <= s["restarts"]:
            rng = np.random.default_rng(s["seed"]) if rng is None else rng
            q = robot.random_configuration(rng)
    _, q_best, pos, rot, why = best
    reason = (
        f"not converged after {s['restarts'] + 1} attempt(s), {iterations} iterations: the "
        f"first level's largest errors are {pos:.3g} m and {rot:.3g} rad{why}"
    )
    attempts, wall = s["restarts"] + 1, time.perf_counter() - start
    return SolveResult(False, reason, q_best, iterations, attempts, pos, rot, wall)


def _checked(
    task: object, target: object, goals: Sequence[Goal] | None, s: dict[str, Any]
) -> TaskStack:
    """The goals as a stack, and the settings, checked (an ``InputError`` names a bad one)."""
    if task is not None or target is not None or goals is None:
        if goals is None:
            raise InputError("task", "a task and a target (or tasks=[clik.Goal, ...])")
        raise InputError("tasks", "either task and target, or tasks (a list of clik.Goal)")
    if s["law"] != "pseudoinverse":
        raise InputError("law", "'pseudoinverse' (law (10) by levels) with tasks", s["law"])
    check_settings(
        SolveSettings(
            s["law"],
            s["step"],
            s["damping"],
            0.0,
            s["tolerance"],
            s["orientation_tolerance"],
            s["max_iterations"],
            s["restarts"],
        )
    )
    if not float(s["step"]) < 2.0:
        raise InputError("step", "a number in (0, 2): K dt of law (10)'s iteration", s["step"])
    check_seed(s["seed"])
    return TaskStack(goals)


def _largest_errors(entries: list[dict[str, Any]]) -> tuple[float, float]:
    """The largest final position [m] and orientation [rad] errors of ``task_errors`` entries.

    An error in metres counts as position, any other (an orientation task's [rad], a
    posture's [rad or m]) as orientation: each entry's unit is its kind's.
    """
    pos = rot = 0.0
    for e in entries:
        if e.get("unit", "m") != "m":
            rot = max(rot, e["final"])
        else:
            pos = max(pos, e["final"])
            rot = max(rot, e.get("final_orientation", 0.0))
    return pos, rot
