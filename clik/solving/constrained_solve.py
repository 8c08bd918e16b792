r"""Single-pose IK with constraints: the unconstrained solve, checked, else the constrained law.

docs/method.md, "Solve mode with constraints". :func:`clik.solve` with
``constraints=`` calls :func:`solve_constrained`:

1. The unconstrained solve (:mod:`clik.solving.solve_mode`, compiled or Python, with its
   seeded restarts). When it fails, the target is out of reach whatever the
   constraints: that failure is returned (``blocked_by`` None).
2. Its pose is checked directly (:class:`~clik.constraints.pose_check.PoseCheck`: coal distances
   ``d >= d_o`` (13), joints at least ``d_q`` inside their limits (17)). A pose that
   satisfies every constraint is returned: the fast path.
3. Otherwise law (10) with the constraint rows, the extended task (23)-(25) with the
   constraints first, is run toward the target held still (``x_d`` constant,
   ``xdot_d = 0``), with ``alpha dt = 1``: each sample is a damped Gauss-Newton step
   of the extended task. Starts, in this order: the unconstrained pose (its links are
   pushed out of the thresholds while the task holds, through the redundancy), ``q0``,
   then configurations drawn from ``default_rng(seed)`` (deterministic for an integer
   seed), ``tracking_attempts`` starts in all. A start runs in chunks of
   :data:`CHUNK_SAMPLES` samples, at most :data:`MAX_CHUNKS`; after each chunk its
   last pose is checked as in 2, and accepted when the task error is within the
   tolerances and every constraint holds. The attempt ends when the run stops (a
   deadlock, Remark 2) or a chunk no longer reduces the error.

The rows run on a copy of the constraint set whose thresholds are :data:`MARGIN` larger
(and obstacle rows on even where the set only monitors obstacles), so that a pose held by
a row sits just outside the threshold that is checked (each kind makes its own copy,
:meth:`~clik.constraints.kind.ConstraintKind.with_margin`). Without joint-range rows the
copy gets rows :data:`~clik.constraints.joint_limits.ROBOT_LIMIT_ROWS` inside the robot's
own limits, which the check holds every pose to.

A failure names the constraint that blocks the target: the one the unconstrained pose
misses by most (:attr:`~clik.solving.solve_result.SolveResult.blocked_by`), and the rows active
at the end of the closest attempt.
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from clik.constraints import ConstraintSet
from clik.constraints.kind import Violation
from clik.constraints.pose_check import PoseCheck, constraint_label
from clik.errors import InputError
from clik.loop.start_checks import unchecked_starts
from clik.loop.tracker import Tracker
from clik.solving.solve_result import SolveResult
from clik.tasks.task import Task
from clik.trajectory import Hold

MARGIN = 1e-5
"""Added to every threshold of the rows [m or rad]: a held row sits this far outside."""

TRACK_DT = 1e-3
"""Sample time of the constrained law [s] (it sets only the stop checks' windows)."""

TRACK_GAIN = 1.0 / TRACK_DT
"""Gain of the constrained law [1/s]: ``alpha dt = 1``, a Gauss-Newton step per sample."""

CHUNK_SAMPLES = 250
"""Samples of the constrained law between two checks of its pose."""

MAX_CHUNKS = 8
"""Chunks per start at most (each sample moves a joint 0.02 rad at most)."""

PROGRESS = 0.99
"""A chunk must bring the task error below this fraction of the best before it."""

DEADLOCK_WINDOW = 2 * CHUNK_SAMPLES * TRACK_DT
"""The run's own deadlock window [s], longer than a chunk: the check between chunks
(:data:`PROGRESS`) takes its place. With ``alpha dt = 1`` the demand ``K e`` far from the
target exceeds the step budget (0.02 rad per sample), which the deadlock test of law (10)
would read as blocked while the error still falls."""
"""A chunk must bring the task error below this fraction of the best before it."""

Unconstrained = Callable[[np.ndarray], SolveResult]
"""The unconstrained solve from a start configuration."""


@dataclass
class _Attempt:
    """One start of the constrained law: where it ended and why."""

    q: np.ndarray
    solved: bool
    samples: int
    position_error: float
    orientation_error: float
    violation: Violation | None
    active: list[str]

    @property
    def rank(self) -> tuple[bool, float]:
        """Sort key of a failed attempt: clear of the constraints first, then nearest."""
        return self.violation is not None, self.position_error + self.orientation_error


class _Prepared:
    """What solves with one constraint set reuse: the check and the rows' copy."""

    def __init__(self, cset: ConstraintSet, task: Task, key: tuple[Any, ...]) -> None:
        self.key = key
        self.check = PoseCheck(cset, task)
        self.rows = cset.with_margin(MARGIN)


_PREPARED: dict[int, _Prepared] = {}
"""Prepared constraint sets by ``id`` (dropped with the set). A solve takes its entry out
while it runs and puts it back after, so solves in other threads build their own."""


def _take(cset: ConstraintSet, task: Task) -> _Prepared:
    """The prepared set for ``cset``, out of the cache (built when missing or stale).

    Built on a snapshot of the set (:meth:`ConstraintSet.snapshot`): a change to the set
    while the solve runs applies to the next solve.
    """
    snapshot = cset.snapshot()
    key = (snapshot.fingerprint(), id(task), task.frame_id, tuple(task.rows))
    prepared = _PREPARED.pop(id(cset), None)
    if prepared is None or prepared.key != key:
        if prepared is None:
            weakref.finalize(cset, _PREPARED.pop, id(cset), None)
        prepared = _Prepared(snapshot, task, key)
    return prepared


class _ConstrainedLaw:
    """Law (10) with the constraint rows toward a held target, run in checked chunks.

    Args:
        task: The task.
        target: Target position [m] and rotation (placeholders where the task has none).
        tolerances: Position [m] and orientation [rad] tolerances.
        prepared: The check and the rows' constraint set.
        damping: ``lambda_0`` of law (10).
        engine: ``"compiled"`` or ``"python"``.
    """

    def __init__(
        self,
        task: Task,
        target: tuple[np.ndarray, np.ndarray],
        tolerances: tuple[float, float],
        prepared: _Prepared,
        damping: float,
        engine: str,
    ) -> None:
        self.task, self.check = task, prepared.check
        self.p_d, self.R_d = target
        self.tolerance, self.orientation_tolerance = tolerances
        self.tracker = Tracker(
            task, law="pseudoinverse", gain=TRACK_GAIN, dt=TRACK_DT, damping=damping,
            constraints=prepared.rows, engine=engine,
        )  # fmt: skip
        self.hold = Hold(
            self.p_d if task.has_position else None,
            self.R_d if task.has_orientation else None,
            duration=(CHUNK_SAMPLES - 1) * TRACK_DT,
        )
        robot = task.robot
        self.lo = np.where(np.isfinite(robot.lower), robot.lower, -np.inf)
        self.hi = np.where(np.isfinite(robot.upper), robot.upper, np.inf)
        self.clip = robot.nq == robot.nv

    def errors(self, q: np.ndarray) -> tuple[float, float]:
        """Task error norms at ``q``: position rows [m], orientation rows [rad] (6)."""
        task = self.task
        placement = self.check.frame_placement(q, task.frame_id)  # the solve's own data
        e6 = task.full_error(placement, self.p_d, self.R_d)
        rows = task.rows
        return (
            float(np.linalg.norm(e6[rows[rows < 3]])),
            float(np.linalg.norm(e6[rows[rows >= 3]])),
        )

    def attempt(self, q: np.ndarray) -> _Attempt:
        """Run from ``q`` until the pose is accepted, the run stops, or it stops progressing."""
        best, samples = math.inf, 0
        active: list[str] = []
        pos = rot = math.inf
        violation = None
        for _ in range(MAX_CHUNKS):
            if self.clip:  # a start must lie within the robot's limits
                q = np.clip(q, self.lo, self.hi)
            with unchecked_starts():  # the solve's own starts: no StartWarning
                result = self.tracker.run(
                    self.hold, q, record_every=CHUNK_SAMPLES, deadlock_window=DEADLOCK_WINDOW
                )
            samples += result.steps
            q = np.array(result.q[-1])
            pos, rot = self.errors(q)
            violation = self.check.worst(q)
            active = _active_at_end(result.extra.get("active"), result.info)
            within = pos <= self.tolerance and rot <= self.orientation_tolerance
            if within and violation is None:
                return _Attempt(q, True, samples, pos, rot, None, active)
            if result.status in ("deadlock", "diverged"):
                break
            if not within and pos + rot > PROGRESS * best:
                break
            best = min(best, pos + rot)
        return _Attempt(q, False, samples, pos, rot, violation, active)


def _active_at_end(active: Any, info: dict[str, Any]) -> list[str]:
    """Keys of the constraint rows active at a run's last recorded sample."""
    names = info.get("constraint_names") or []
    if active is None or len(active) == 0:
        return []
    return [names[int(c)] for c in np.asarray(active)[-1] if 0 <= int(c) < len(names)]


def _starts(
    first: SolveResult, q0: np.ndarray, task: Task, seed: int | None, count: int
) -> Iterator[tuple[str, np.ndarray]]:
    """The starts of the constrained law, named: unconstrained pose, ``q0``, seeded draws."""
    given = 0
    if count > given:
        given += 1
        yield "the unconstrained pose", first.q
    if count > given and not np.array_equal(q0, first.q):
        given += 1
        yield "q0", q0
    rng = np.random.default_rng(seed)
    for k in range(count - given):
        yield f"random start {k + 1}", task.robot.random_configuration(rng)


def solve_constrained(
    task: Task,
    target: tuple[np.ndarray, np.ndarray],
    q0: np.ndarray,
    constraints: ConstraintSet,
    unconstrained: Unconstrained,
    *,
    tolerances: tuple[float, float],
    damping: float,
    tracking_attempts: int,
    seed: int | None,
    engine: str,
) -> SolveResult:
    """Solve for ``target`` keeping clear of ``constraints`` (the module's method).

    Args:
        task: The task.
        target: Target position [m] and rotation, checked (placeholders where the task
            has no such rows).
        q0: Start configuration (nq,), checked.
        constraints: The constraints; obstacles at rest, built on the task's robot.
        unconstrained: The unconstrained solve from a start configuration.
        tolerances: Position [m] and orientation [rad] tolerances.
        damping: ``lambda_0`` of law (10).
        tracking_attempts: Starts of the constrained law (0: check the unconstrained
            pose only).
        seed: Seed of the random starts.
        engine: ``"compiled"`` or ``"python"``, for both the solve and the law.

    Raises:
        InputError: Moving obstacles, a set built on another robot, or a bad
            ``tracking_attempts``.
    """
    _check_constraints(task, constraints, tracking_attempts)
    start = time.perf_counter()
    prepared = _take(constraints, task)
    try:
        first = unconstrained(q0)
        if not first.success:
            reason = f"{first.reason} (without the constraints: no constraint was checked)"
            return replace(first, reason=reason, wall_time_s=time.perf_counter() - start)
        blocking = prepared.check.worst(first.q)
        if blocking is None:
            return replace(first, wall_time_s=time.perf_counter() - start)
        law = _ConstrainedLaw(task, target, tolerances, prepared, damping, engine)
        attempts: list[_Attempt] = []
        for name, q_start in _starts(first, q0, task, seed, tracking_attempts):
            attempt = law.attempt(q_start)
            attempts.append(attempt)
            if attempt.solved:
                return _solved(first, blocking, attempts, name, time.perf_counter() - start)
        return _blocked(first, blocking, attempts, time.perf_counter() - start)
    finally:
        _PREPARED[id(constraints)] = prepared


def _check_constraints(task: Task, constraints: ConstraintSet, tracking_attempts: int) -> None:
    """Refuse what solve mode cannot use, naming the argument."""
    if not isinstance(constraints, ConstraintSet):
        raise InputError("constraints", "a ConstraintSet or None", type(constraints).__name__)
    if constraints.robot is not task.robot:
        raise InputError("constraints", "a ConstraintSet built on the task's robot")
    task.robot.check_model()
    moving = [o.name for o in constraints.obstacles if o.moving]
    if moving:
        raise InputError("constraints", "obstacles at rest (solve mode has no time)", moving)
    attempts = tracking_attempts
    if not isinstance(attempts, int) or isinstance(attempts, bool) or attempts < 0:
        raise InputError("tracking_attempts", "an integer >= 0", tracking_attempts)


def _solved(
    first: SolveResult, blocking: Violation, attempts: list[_Attempt], name: str, wall: float
) -> SolveResult:
    """The result of the attempt that reached the target clear of the constraints."""
    last = attempts[-1]
    samples = sum(a.samples for a in attempts)
    reason = (
        f"converged with the constraints: the unconstrained pose missed them "
        f"({blocking.describe()}); law (10) with the constraint rows from {name} reached "
        f"the target in {last.samples} samples"
    )
    return SolveResult(
        True, reason, last.q, first.iterations + samples, first.attempts + len(attempts),
        last.position_error, last.orientation_error, wall,
    )  # fmt: skip


def _blocked(
    first: SolveResult, blocking: Violation, attempts: list[_Attempt], wall: float
) -> SolveResult:
    """The failure: the blocking constraint, and the closest attempt's last pose."""
    reason = f"{blocking.describe()} in the unconstrained solution"
    samples = sum(a.samples for a in attempts)
    q, pos, rot = first.q, first.position_error, first.orientation_error
    if attempts:
        best = min(attempts, key=lambda a: a.rank)
        q, pos, rot = best.q, best.position_error, best.orientation_error
        reason += (
            f"; law (10) with the constraint rows from {len(attempts)} start(s) ended at best "
            f"{pos:.3g} m and {rot:.3g} rad from the target"
        )
        if best.active:
            reason += ", held by " + ", ".join(constraint_label(k) for k in best.active)
        if best.violation is not None:
            reason += f"; its last pose still misses a constraint: {best.violation.describe()}"
    return SolveResult(
        False, reason, q, first.iterations + samples, first.attempts + len(attempts),
        pos, rot, wall, blocked_by=blocking.constraint,
    )  # fmt: skip
