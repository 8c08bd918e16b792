"""Solve mode in the compiled engine: its solvers kept per task, its restarts drawn here.

The engine (``src/engine/solving/solve.cpp``) runs the iteration of
:class:`~clik.solving.solve_problem.SolveProblem`; a solver is built once per task
and settings and kept (:data:`_SOLVERS`), and the restart configurations are drawn
in Python from the seed the Python engine uses (:func:`_random_configurations`),
so both engines restart from the same configurations.
"""

from __future__ import annotations

import math
import time
import weakref
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.loop.laws import check_law
from clik.solving.solve_problem import SolveSettings, check_settings, checked_target
from clik.solving.solve_result import SolveResult, converged_reason, failure_reason
from clik.tasks.task import Task

if TYPE_CHECKING:
    from clik.model.robot import Robot


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

    __slots__ = ("limits", "nq", "seed", "signature", "solver", "starts")

    def __init__(self, solver: Any, nq: int, signature: tuple[int, ...]) -> None:
        self.solver, self.nq, self.signature = solver, nq, signature
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
settings as given (the key :func:`~clik.solving.solve_mode.solve` builds), least
recently used first. A solver holds no result between solves; each solve takes its
solver out of here while it runs and puts it back after, so a solve running meanwhile
in another thread builds its own."""

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
    s = SolveSettings(check_law(key[0]), *key[1:8])
    check_settings(s)
    robot = task.robot
    robot.check_model()  # the whole model, joints too: the solver is kept
    return _Compiled(
        _compiled_engine().Solver(
            robot.model, task.frame_id, task.rows.tolist(), robot.q_reference, law=s.law,
            step=s.step, damping=s.damping, mu=s.mu, tolerance=s.tolerance,
            orientation_tolerance=s.orientation_tolerance, max_iterations=s.max_iterations,
        ),
        robot.nq,
        robot.signature,
    )  # fmt: skip


def solve_compiled(
    task: Task, target: object, q0: object, key: tuple[Any, ...], seed: int | None
) -> SolveResult:
    """``solve`` in the compiled engine: the same checks, iteration, attempts and restarts.

    The solver comes from the cache (:data:`_SOLVERS`), so a repeated solve costs
    little more than the C++ run. The robot's model is checked first (its sizes,
    :attr:`~clik.model.robot.Robot.signature`): a model changed after loading is refused,
    and a cached solver is used only on the model sizes it was built for. A
    ``pin.SE3`` target and a ``q0`` that is None or a float array of ``nq`` entries go
    to C++ as they are, and C++ checks that their values are finite; anything else, or
    a value that is not finite, goes through
    :func:`~clik.solving.solve_problem.checked_target` and ``check_configuration``
    (which name the bad input).
    The engine runs the first attempt from ``q0``; only when it fails are the
    restart configurations drawn (all ``restarts`` of them at once, vectorised:
    creating the generator costs ~10-20 us; kept for the next solve with the same
    seed) and handed over to continue the solve.
    """
    robot, model = task.robot, task.robot.model
    signature = (model.nq, model.nv, model.njoints, model.nframes)  # ~0.5 us: robot.signature
    if signature != robot.signature:
        robot.check_model()  # raises: the model changed after loading
    solvers = _SOLVERS.get(id(task)) or _solvers_of(task)
    try:
        compiled = solvers.pop(key, None)  # out of the cache while it runs
    except TypeError:  # an unhashable setting (e.g. a 0-d NumPy array): never kept
        compiled = None
    if compiled is None or compiled.signature != signature:  # never another model's
        compiled = _new_compiled(task, key)
    solver = compiled.solver
    q = np.empty(compiled.nq)  # where the engine writes the solve's configuration
    if type(target) is pin.SE3 and (q0 is None or _plain_configuration(q0, compiled.nq)):
        start = time.perf_counter()
        out = solver.start_se3(target, q0, q)
    else:
        p_d, R_d = checked_target(task, target)
        q_start = robot.check_configuration(robot.q_reference if q0 is None else q0, "q0")
        start = time.perf_counter()
        out = solver.start(p_d, R_d, q_start, q)
    if out is None:  # a value that is not finite: the checks in Python name it
        checked_target(task, target)
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
        reason = converged_reason(iterations)
    else:
        reason = failure_reason(attempts, iterations, pos, rot)
    return SolveResult(success, reason, q, iterations, attempts, pos, rot, elapsed)


def _plain_configuration(q: object, nq: int) -> bool:
    """``q`` is a float64 NumPy array of shape (nq,) (its values are checked in C++)."""
    return type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (nq,)
