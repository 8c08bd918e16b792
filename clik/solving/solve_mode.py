"""Solve mode: reach one target pose from ``q0`` by iterating a CLIK law to tolerance.

The reference is held (``xdot_d = 0``) and the law is iterated as a
fixed-point map: ``q <- q (+) alpha dt J^+ e`` for law (10), with
``alpha dt = 1`` (a Gauss-Newton step, damped as Levenberg-Marquardt with
``lambda^2 = lambda_0^2 + mu |e|^2``, ``mu = 10^-2``), or ``q <- q (+) alpha dt J^T e`` for
law (9). For a full pose task the error is ``log6(oMf^-1 oMd)`` in the frame,
with its exact Jacobian ``Jlog6 J_local`` (far from the target this converges
where the world-frame ``log3`` error stalls). After each step joints are
clipped into their limits; an attempt that stalls (no 0.1 % progress in 15
iterations) or hits the iteration limit restarts from a seeded random
configuration inside the limits, up to ``restarts`` times.

This module (the attempts and restarts) and :mod:`clik.solving.solve_problem`
(the iteration) are the readable specification; ``engine="compiled"`` (the
default) runs the same iteration in C++ (``src/engine/solving/solve.cpp``), with
the same restart configurations drawn from the same seed
(:mod:`clik.solving.compiled_solve`).

With ``constraints=`` (a :class:`~clik.constraints.ConstraintSet`, obstacles at
rest) the solve above runs first and its pose is checked with coal against every
obstacle threshold (13) and joint-range band (17); a pose that misses one is
looked for again with law (10) on the extended task (23)-(25) toward the held
target, from seeded starts, and a failure names the blocking constraint
(:mod:`clik.solving.constrained_solve`, docs/method.md "Solve mode with constraints").
Without constraints nothing of that runs: the same iteration, the same speed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.loop.laws import LawName, check_law
from clik.solving.compiled_solve import solve_compiled
from clik.solving.solve_problem import (
    SolveProblem,
    SolveSettings,
    check_seed,
    check_settings,
    checked_target,
)
from clik.solving.solve_result import SolveResult, converged_reason, failure_reason
from clik.solving.stack_solve import solve_tasks
from clik.tasks.task import Task

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.objectives.objective import Objective
    from clik.tasks.goal import Goal

EngineName = Literal["compiled", "python"]


def solve(
    task: Task | None = None,
    target: pin.SE3 | np.ndarray | Sequence[float] | None = None,
    q0: np.ndarray | Sequence[float] | None = None,
    *,
    tasks: Sequence[Goal] | None = None,
    objectives: Sequence[Objective] | None = None,
    law: LawName = "pseudoinverse",
    step: float = 1.0,
    damping: float = 1e-6,
    mu: float = 1e-2,
    tolerance: float = 1e-4,
    orientation_tolerance: float = 1e-3,
    max_iterations: int = 100,
    restarts: int = 50,
    seed: int | None = 0,
    engine: EngineName = "compiled",
    constraints: ConstraintSet | None = None,
    tracking_attempts: int = 4,
) -> SolveResult:
    """Iterate a CLIK law until the task error is within tolerance.

    Args:
        task: The task (its mask selects which components must match).
        target: Target pose (``pin.SE3`` or 4x4), position (3,) or rotation (3, 3).
        q0: Start configuration (default: the robot's reference configuration).
        tasks: Several tasks instead of ``task`` and ``target`` (``clik.Goal``, each target
            its trajectory's final value; :mod:`clik.solving.stack_solve`).
        objectives: With ``tasks``, eq. (5)'s objectives below the levels.
        law: ``"pseudoinverse"`` (10) (default) or ``"transpose"`` (9).
        step: ``alpha dt``, the fraction of the law's velocity applied per iteration.
        damping: ``lambda_0`` of the damped pseudoinverse.
        mu: Levenberg-Marquardt factor: ``lambda^2 = lambda_0^2 + mu |e|^2``.
        tolerance: Position tolerance [m].
        orientation_tolerance: Orientation tolerance [rad].
        max_iterations: Iterations per attempt, an integer in [1, ``clik.bounds.MAX_ITERATIONS``].
        restarts: Random restarts within the limits, in [0, ``clik.bounds.MAX_RESTARTS``].
        seed: Seed of the restarts' random generator, an integer >= 0 (None: fresh entropy).
        engine: ``"compiled"`` (default: clik's C++ engine) or ``"python"`` (this module);
            both give the same results (the same restarts; ``q`` equal to rounding).
        constraints: Obstacle, joint-range and link-pair constraints, obstacles at rest: the
            pose returned keeps clear of them, a failure names the constraint that blocks
            the target (:mod:`clik.solving.constrained_solve`). None: no check.
        tracking_attempts: With ``constraints``, the starts of the constrained law (10).

    Raises:
        InputError: A bad argument, named; or the robot's model changed after loading.
    """
    if seed is not None and (type(seed) is not int or seed < 0):
        check_seed(seed)  # raises unless a NumPy integer >= 0
    if tasks is not None or objectives is not None or task is None or target is None:
        return solve_tasks(task, target, tasks, q0, constraints, objectives, {
            "law": law, "step": step, "damping": damping, "tolerance": tolerance,
            "orientation_tolerance": orientation_tolerance, "max_iterations": max_iterations,
            "restarts": restarts, "seed": seed, "engine": engine,
        })  # fmt: skip
    if constraints is not None:
        given: dict[str, Any] = {
            "law": law, "step": step, "damping": damping, "mu": mu, "tolerance": tolerance,
            "orientation_tolerance": orientation_tolerance, "max_iterations": max_iterations,
            "restarts": restarts, "seed": seed, "engine": engine,
        }  # fmt: skip
        return _solve_with_constraints(task, target, q0, constraints, tracking_attempts, given)
    if engine == "compiled":
        # The cache key of the settings: their values, and the integers' types (equal
        # keys pass or fail the checks alike: 100.0 iterations are refused, 100 not).
        key = (
            law, step, damping, mu, tolerance, orientation_tolerance, max_iterations, restarts,
            type(max_iterations), type(restarts),
        )  # fmt: skip
        return solve_compiled(task, target, q0, key, seed)
    if engine != "python":
        raise InputError("engine", "'compiled' or 'python'", engine)
    task.robot.check_model()
    settings = SolveSettings(
        check_law(law), step, damping, mu, tolerance, orientation_tolerance,
        max_iterations, restarts,
    )  # fmt: skip
    check_settings(settings)
    return _solve_python(task, target, q0, settings, seed)


def _solve_python(
    task: Task, target: object, q0: object, settings: SolveSettings, seed: int | None
) -> SolveResult:
    """:func:`solve` in Python: the first attempt from ``q0``, then seeded restarts."""
    problem = SolveProblem(task, target, settings)
    robot = task.robot
    restarts = settings.restarts
    q = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
    rng = None  # created at the first restart (it costs ~20 us)
    iterations = 0
    best_total, best_q, best_errors = math.inf, q.copy(), (math.inf, math.inf)
    start = time.perf_counter()
    with np.errstate(invalid="ignore", divide="ignore"):  # solve_small checks for NaN
        for attempt in range(1, restarts + 2):
            q, converged, used, pos, rot = problem.attempt(q)
            iterations += used
            if converged:
                reason = converged_reason(iterations)
                elapsed = time.perf_counter() - start
                return SolveResult(True, reason, q, iterations, attempt, pos, rot, elapsed)
            if pos + rot < best_total:  # keep the best attempt for a failure report
                best_total, best_q, best_errors = pos + rot, q.copy(), (pos, rot)
            if attempt <= restarts:
                rng = np.random.default_rng(seed) if rng is None else rng
                q = robot.random_configuration(rng)
    pos, rot = best_errors
    reason = failure_reason(restarts + 1, iterations, pos, rot)
    elapsed = time.perf_counter() - start
    return SolveResult(False, reason, best_q, iterations, restarts + 1, pos, rot, elapsed)


def _solve_with_constraints(
    task: Task,
    target: object,
    q0: object,
    constraints: ConstraintSet,
    tracking_attempts: int,
    settings: dict[str, Any],
) -> SolveResult:
    """:func:`solve` with constraints (:func:`clik.solving.constrained_solve.solve_constrained`)."""
    from clik.solving.constrained_solve import solve_constrained

    task.robot.check_model()
    checked = checked_target(task, target)
    robot = task.robot
    q_start = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")

    def unconstrained(q: np.ndarray) -> SolveResult:
        return solve(task, target, q, **settings)

    return solve_constrained(
        task, checked, q_start, constraints, unconstrained,
        tolerances=(settings["tolerance"], settings["orientation_tolerance"]),
        damping=settings["damping"], tracking_attempts=tracking_attempts,
        seed=settings["seed"], engine=settings["engine"],
    )  # fmt: skip
