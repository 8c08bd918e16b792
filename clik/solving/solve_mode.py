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

This module is the readable specification; ``engine="compiled"`` (the default)
runs the same iteration in C++ (``src/engine/solving/solve.cpp``), with the same
restart configurations drawn here from the same seed.

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
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.loop.laws import LawName, check_law, solve_small
from clik.solving.solve_result import SolveResult
from clik.tasks.task import Task

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.model.robot import Robot

EngineName = Literal["compiled", "python"]


def _target_arrays(target: object) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Target position and rotation, each None where ``target`` has none."""
    if isinstance(target, pin.SE3):
        return target.translation.copy(), target.rotation.copy()
    arr = np.asarray(target, dtype=float)
    if arr.shape == (3,):
        return arr.copy(), None
    if arr.shape == (4, 4):
        return arr[:3, 3].copy(), arr[:3, :3].copy()
    if arr.shape == (3, 3):
        return None, arr.copy()
    raise InputError(
        "target", "a pin.SE3, a (4, 4) pose, a (3,) position or a (3, 3) rotation", arr.shape
    )


def _checked_target(task: Task, target: object) -> tuple[np.ndarray, np.ndarray]:
    """Target position and rotation for ``task``, placeholders where it has no such rows.

    Raises:
        InputError: The target misses what the task needs, or is not finite.
    """
    p_d, R_d = _target_arrays(target)
    if task.has_position and p_d is None:
        raise InputError("target", f"a position for the {task.kind} task")
    if task.has_orientation and R_d is None:
        raise InputError("target", f"an orientation for the {task.kind} task")
    for arr in (p_d, R_d):
        if arr is not None and not np.all(np.isfinite(arr)):
            raise InputError("target", "finite values", arr.tolist())
    return (np.zeros(3) if p_d is None else p_d), (np.eye(3) if R_d is None else R_d)


@dataclass(frozen=True)
class _Settings:
    """What :func:`solve` iterates with (see its arguments)."""

    law: str
    step: float
    damping: float
    mu: float
    tolerance: float
    orientation_tolerance: float
    max_iterations: int
    restarts: int


def _check_settings(settings: _Settings) -> None:
    """Refuse settings the iteration cannot use, naming the argument."""
    if settings.law == "nonlinear":
        raise InputError("law", "'pseudoinverse' or 'transpose' in solve mode", settings.law)
    if not isinstance(settings.max_iterations, int) or settings.max_iterations < 1:
        raise InputError("max_iterations", "an integer >= 1", settings.max_iterations)
    if not isinstance(settings.restarts, int) or settings.restarts < 0:
        raise InputError("restarts", "an integer >= 0", settings.restarts)
    for name in ("tolerance", "orientation_tolerance", "step"):
        value = getattr(settings, name)
        if not (math.isfinite(value) and value > 0):
            raise InputError(name, "a positive finite number", value)
    for name in ("damping", "mu"):
        value = getattr(settings, name)
        if not (math.isfinite(value) and value >= 0):
            raise InputError(name, "a finite number >= 0", value)


class _Problem:
    """One target for one task: the error, its Jacobian and one step of the law.

    Args:
        task: The task (its mask selects the rows).
        target: What :func:`solve` was given.
        settings: The iteration's settings.
    """

    def __init__(self, task: Task, target: object, settings: _Settings) -> None:
        self.task, self.settings = task, settings
        self.robot = task.robot
        # (unused placeholders where the task has no such rows)
        self.p_d, self.R_d = _checked_target(task, target)
        self.full_pose = task.m == 6
        self.target_se3 = pin.SE3(self.R_d, self.p_d) if self.full_pose else None
        robot = self.robot
        bounded = np.isfinite(robot.lower) & np.isfinite(robot.upper) & (robot.nq == robot.nv)
        self.clip = bool(bounded.any())
        self.lo = np.where(bounded, robot.lower, -np.inf)
        self.hi = np.where(bounded, robot.upper, np.inf)
        self.e6 = np.zeros(6)
        self.diagonal = slice(None, None, task.m + 1)

    def error(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Task error ``e``, its Jacobian ``J``, position [m] and orientation [rad] norms.

        A full pose uses ``log6(oMf^-1 oMd)`` in the frame with its exact Jacobian
        ``Jlog6 J_local``; a masked task the world-aligned error (6) and ``J`` (3).
        """
        model, data, fid = self.robot.model, self.robot.data, self.task.frame_id
        if self.full_pose:
            pin.computeJointJacobians(model, data, q)
            fMd = pin.updateFramePlacement(model, data, fid).actInv(self.target_se3)
            e = pin.log6(fMd).vector
            J = pin.Jlog6(fMd.inverse()).dot(pin.getFrameJacobian(model, data, fid, pin.LOCAL))
            return e, J, _norm3(e[:3]), _norm3(e[3:])
        J6 = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        oMf = data.oMf[fid]
        e6 = self.e6
        if self.task.has_position:
            np.subtract(self.p_d, oMf.translation, out=e6[:3])
        if self.task.has_orientation:
            e6[3:] = pin.log3(self.R_d.dot(oMf.rotation.T))
        rows = self.task.rows
        return e6[rows], J6[rows], _norm3(e6[:3]), _norm3(e6[3:])

    def world_errors(self) -> tuple[float, float]:
        """Position and orientation error norms in the world frame, at the last ``q``."""
        oMf = self.robot.data.oMf[self.task.frame_id]
        pos = rot = 0.0
        if self.task.has_position:
            pos = float(np.linalg.norm(self.p_d - oMf.translation))
        if self.task.has_orientation:
            rot = float(np.linalg.norm(pin.log3(self.R_d.dot(oMf.rotation.T))))
        return pos, rot

    def step(self, q: np.ndarray, e: np.ndarray, J: np.ndarray, err2: float) -> np.ndarray:
        """One iteration, ``q (+) step qdot``, clipped into the joint limits.

        Law (10): ``qdot = J^T (J J^T + lambda^2 I)^-1 e`` with
        ``lambda^2 = lambda_0^2 + mu |e|^2`` (Levenberg-Marquardt); law (9):
        ``qdot = J^T e``.
        """
        s = self.settings
        if s.law == "pseudoinverse":
            A = J.dot(J.T)
            A.flat[self.diagonal] += s.damping * s.damping + s.mu * err2
            dq = J.T.dot(solve_small(A, e))
        else:
            dq = J.T.dot(e)
        dq *= s.step
        q = pin.integrate(self.robot.model, q, dq)
        if self.clip and ((q < self.lo).any() or (q > self.hi).any()):
            np.maximum(q, self.lo, out=q)
            np.minimum(q, self.hi, out=q)
        return q

    def attempt(self, q: np.ndarray) -> tuple[np.ndarray, bool, int, float, float]:
        """Iterate from ``q`` until converged, stalled or out of iterations.

        Returns:
            The last ``q``, whether it converged, the iterations used, and the
            position [m] and orientation [rad] error norms at the last ``q``.
        """
        s = self.settings
        best, since_best = math.inf, 0
        pos = rot = math.inf
        for iteration in range(s.max_iterations):
            e, J, pos, rot = self.error(q)
            if pos <= s.tolerance and rot <= s.orientation_tolerance:
                return q, True, iteration, *self.world_errors()
            q = self.step(q, e, J, pos * pos + rot * rot)
            if pos + rot < STALL_PROGRESS * best:
                best, since_best = pos + rot, 0
            else:
                since_best += 1
                if since_best >= STALL_ITERATIONS:
                    return q, False, iteration + 1, pos, rot
        return q, False, s.max_iterations, pos, rot


STALL_PROGRESS = 0.999
"""An iteration makes progress when the error falls below this fraction of the best."""

STALL_ITERATIONS = 15
"""Iterations without progress after which an attempt restarts."""


def _norm3(v: np.ndarray) -> float:
    a, b, c = v.tolist()
    return math.sqrt(a * a + b * b + c * c)


def _converged_reason(iterations: int) -> str:
    return f"converged in {iterations} iterations"


def _failure_reason(attempts: int, iterations: int, pos: float, rot: float) -> str:
    return (
        f"no convergence after {attempts} attempt(s), {iterations} iterations; best "
        f"attempt: position error {pos:.3g} m, orientation error {rot:.3g} rad"
    )


def _random_configurations(robot: Robot, rng: np.random.Generator, count: int) -> np.ndarray:
    """``count`` configurations (count, nq), row ``k`` the ``k``-th ``random_configuration(rng)``.

    One vectorised draw: ``Generator.uniform`` with array bounds takes the same
    doubles from the stream in the same order (row by row, joint by joint) and maps
    each as the scalar call does, ``low + (high - low) u``.
    """
    model = robot.model
    q = np.tile(pin.neutral(model), (count, 1))
    lows: list[float] = []
    highs: list[float] = []
    bounded: list[tuple[int, int]] = []  # (column of the draw, q index)
    continuous: list[tuple[int, int]] = []
    for joint in model.joints[1:]:
        i = joint.idx_q
        low, high = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        if joint.nq == 2 and joint.nv == 1:
            continuous.append((len(lows), i))
            lows.append(-math.pi)
            highs.append(math.pi)
        elif joint.nq == 1 and math.isfinite(low) and math.isfinite(high):
            if not low <= high:  # as random_configuration refuses it
                expected = "a margin >= 0 [rad or m] smaller than half of every joint range"
                raise InputError("margin", expected, got=0.0)
            bounded.append((len(lows), i))
            lows.append(float(low))
            highs.append(float(high))
    if not lows or count == 0:
        return q
    u = rng.uniform(lows, highs, size=(count, len(lows)))
    for column, i in bounded:
        q[:, i] = u[:, column]
    for column, i in continuous:  # math.cos, math.sin as random_configuration
        for k in range(count):
            angle = float(u[k, column])
            q[k, i : i + 2] = (math.cos(angle), math.sin(angle))
    return q


def _compiled_engine() -> ModuleType:
    """The compiled engine module, its versions checked (the one place that loads it)."""
    from clik.engine import load

    return load()


class _Compiled:
    """A compiled solver of one task with one set of settings, and its last restarts.

    The restart configurations are kept for the next solve with the same integer
    seed (and the same joint limits): drawing them costs ~30-70 us.

    Args:
        solver: The engine's ``Solver``.
        nq: The robot's ``nq``.
    """

    __slots__ = ("limits", "nq", "seed", "solver", "starts")

    def __init__(self, solver: Any, nq: int) -> None:
        self.solver, self.nq = solver, nq
        self.seed: int | None = None
        self.limits: tuple[bytes, bytes] | None = None
        self.starts: np.ndarray | None = None

    def restart_configurations(self, robot: Robot, seed: int | None, count: int) -> np.ndarray:
        """:func:`_random_configurations` of ``default_rng(seed)``, kept for an integer seed."""
        model = robot.model
        limits = (model.lowerPositionLimit.tobytes(), model.upperPositionLimit.tobytes())
        kept = type(seed) is int and (seed, limits) == (self.seed, self.limits)
        if kept and self.starts is not None:
            return self.starts
        starts = _random_configurations(robot, np.random.default_rng(seed), count)
        starts.flags.writeable = False
        if type(seed) is int:  # other seeds (None: fresh entropy) draw anew each time
            self.seed, self.limits, self.starts = seed, limits, starts
        return starts


_SOLVERS: dict[int, dict[tuple[Any, ...], _Compiled]] = {}
"""Compiled solvers kept per task (by ``id``, dropped with the task), keyed by the
settings as given (the key :func:`solve` builds), least recently used first. A solver
holds no result between solves; each solve takes its solver out of here while it runs
and puts it back after, so a solve running meanwhile in another thread builds its own."""

_SOLVERS_PER_TASK = 8
"""Solvers kept per task (the least recently used goes first)."""


def _solvers_of(task: Task) -> dict[tuple[Any, ...], _Compiled]:
    """The solvers kept for ``task``: an empty dict at its first compiled solve."""
    solvers = _SOLVERS.get(id(task))
    if solvers is None:
        solvers = _SOLVERS[id(task)] = {}
        weakref.finalize(task, _SOLVERS.pop, id(task), None)
    return solvers


def _new_compiled(task: Task, key: tuple[Any, ...]) -> _Compiled:
    """A new compiled solver for ``task``, once the settings in ``key`` are checked.

    Raises:
        InputError: A bad setting, named.
    """
    s = _Settings(check_law(key[0]), *key[1:8])
    _check_settings(s)
    robot = task.robot
    return _Compiled(
        _compiled_engine().Solver(
            robot.model, task.frame_id, task.rows.tolist(), robot.q_reference, law=s.law,
            step=s.step, damping=s.damping, mu=s.mu, tolerance=s.tolerance,
            orientation_tolerance=s.orientation_tolerance, max_iterations=s.max_iterations,
        ),
        robot.nq,
    )  # fmt: skip


def _solve_compiled(
    task: Task, target: object, q0: object, key: tuple[Any, ...], seed: int | None
) -> SolveResult:
    """:func:`solve` in the compiled engine: the same checks, iteration, attempts and restarts.

    The solver comes from the cache (:data:`_SOLVERS`), so a repeated solve costs
    little more than the C++ run. A ``pin.SE3`` target and a ``q0`` that is None or
    a float array of ``nq`` entries go to C++ as they are, and C++ checks that their
    values are finite; anything else, or a value that is not finite, goes through
    :func:`_checked_target` and ``check_configuration`` (which name the bad input).
    The engine runs the first attempt from ``q0``; only when it fails are the
    restart configurations drawn (all ``restarts`` of them at once, vectorised:
    creating the generator costs ~10-20 us; kept for the next solve with the same
    seed) and handed over to continue the solve.
    """
    solvers = _SOLVERS.get(id(task)) or _solvers_of(task)
    try:
        compiled = solvers.pop(key, None)  # out of the cache while it runs
    except TypeError:  # an unhashable setting (e.g. a 0-d NumPy array): never kept
        compiled = None
    if compiled is None:
        compiled = _new_compiled(task, key)
    solver, robot = compiled.solver, task.robot
    q = np.empty(compiled.nq)  # where the engine writes the solve's configuration
    if type(target) is pin.SE3 and (q0 is None or _plain_configuration(q0, compiled.nq)):
        start = time.perf_counter()
        out = solver.start_se3(target, q0, q)
    else:
        p_d, R_d = _checked_target(task, target)
        q_start = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        start = time.perf_counter()
        out = solver.start(p_d, R_d, q_start, q)
    if out is None:  # a value that is not finite: the checks in Python name it
        _checked_target(task, target)
        robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        raise AssertionError("the engine refused a finite target and q0")  # pragma: no cover
    restarts = key[7]
    if not out[0] and restarts:
        out = solver.run(compiled.restart_configurations(robot, seed, restarts), q)
    elapsed = time.perf_counter() - start
    while len(solvers) >= _SOLVERS_PER_TASK:  # the least recently used goes
        solvers.pop(next(iter(solvers)), None)
    try:
        solvers[key] = compiled  # back into the cache, most recently used
    except TypeError:
        pass
    success, iterations, attempts, pos, rot = out
    if success:
        reason = _converged_reason(iterations)
    else:
        reason = _failure_reason(attempts, iterations, pos, rot)
    return SolveResult(success, reason, q, iterations, attempts, pos, rot, elapsed)


def _plain_configuration(q: object, nq: int) -> bool:
    """``q`` is a float64 NumPy array of shape (nq,) (its values are checked in C++)."""
    return type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (nq,)


def solve(
    task: Task,
    target: pin.SE3 | np.ndarray | Sequence[float],
    q0: np.ndarray | Sequence[float] | None = None,
    *,
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
        law: ``"pseudoinverse"`` (10) (default) or ``"transpose"`` (9).
        step: ``alpha dt``, the fraction of the law's velocity applied per iteration.
        damping: ``lambda_0`` of the damped pseudoinverse.
        mu: Levenberg-Marquardt factor: ``lambda^2 = lambda_0^2 + mu |e|^2``.
        tolerance: Position tolerance [m].
        orientation_tolerance: Orientation tolerance [rad].
        max_iterations: Iterations per attempt.
        restarts: Random restarts (within joint limits) after a failed attempt.
        seed: Seed of the restarts' random generator.
        engine: ``"compiled"`` (default) runs the iteration in clik's C++ engine;
            ``"python"`` runs the code of this module. Both give the same results
            (the same restarts from the same seed; ``q`` equal to rounding).
        constraints: Obstacle, joint-range and link-pair constraints (the
            :class:`~clik.constraints.ConstraintSet` :func:`clik.track` takes), obstacles
            at rest. The pose returned on success keeps every monitored link at least its
            obstacle's threshold away and every joint at least ``d_q`` inside its range
            (checked with coal); a failure's ``reason`` and ``blocked_by`` name the
            constraint that blocks the target. None (default): no constraint, no check.
            See :mod:`clik.solving.constrained_solve`.
        tracking_attempts: With ``constraints``, the starts of the constrained law (10)
            tried when the unconstrained pose misses a constraint.

    Raises:
        InputError: A bad argument, named.
    """
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
        return _solve_compiled(task, target, q0, key, seed)
    if engine != "python":
        raise InputError("engine", "'compiled' or 'python'", engine)
    settings = _Settings(
        check_law(law), step, damping, mu, tolerance, orientation_tolerance,
        max_iterations, restarts,
    )  # fmt: skip
    _check_settings(settings)
    return _solve_python(task, target, q0, settings, seed)


def _solve_python(
    task: Task, target: object, q0: object, settings: _Settings, seed: int | None
) -> SolveResult:
    """:func:`solve` in Python: the first attempt from ``q0``, then seeded restarts."""
    problem = _Problem(task, target, settings)
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
                reason = _converged_reason(iterations)
                elapsed = time.perf_counter() - start
                return SolveResult(True, reason, q, iterations, attempt, pos, rot, elapsed)
            if pos + rot < best_total:  # keep the best attempt for a failure report
                best_total, best_q, best_errors = pos + rot, q.copy(), (pos, rot)
            if attempt <= restarts:
                rng = np.random.default_rng(seed) if rng is None else rng
                q = robot.random_configuration(rng)
    pos, rot = best_errors
    reason = _failure_reason(restarts + 1, iterations, pos, rot)
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

    checked = _checked_target(task, target)
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
