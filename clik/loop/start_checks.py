"""Checks of a run's start ``q0``: singular for the task, or on a joint limit.

A poor start is legal but often ends a run early: a stretched arm (the UR5's
reference, all zeros) has a task Jacobian ``J`` (3) of lower rank, so the law
cannot move the frame along some direction and the run may end ``deadlock``; a
joint on its limit (Kinova's reference, clipped into its limits) or inside its
joint-range threshold band activates a row at t = 0. :func:`warn_start` says so
once, before the run, naming the joints and a single-joint move that fixes it, so
the user can give a better start (``q0=`` in Python, ``[initial] q`` in a
scenario).

Thresholds:

- singular: the smallest singular value of the (primary) task's Jacobian
  ``sigma_r(J) < SINGULAR_VALUE`` [m/rad for position rows, 1 for orientation
  rows], ``r`` the rank ``J`` has at generic configurations (a task's rows that no
  joint ever moves, such as a planar arm's ``z``, are not the start's fault);
- on a limit: a joint within ``LIMIT_MARGIN`` [rad or m] of one of the robot's
  limits, or inside its joint-range threshold band when the run has joint-range
  rows (then its row is active at the first sample).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from clik.errors import ClikWarning, user_stacklevel
from clik.model.joints import PRISMATIC, REVOLUTE, joint_kind

if TYPE_CHECKING:
    from clik.constraints.constraint_set import ConstraintSet
    from clik.tasks.task import Task

SINGULAR_VALUE = 1e-3
"""A start whose task Jacobian's smallest singular value is below this is singular."""
LIMIT_MARGIN = {REVOLUTE: math.radians(0.5), PRISMATIC: 5e-4}
"""Distance to a joint limit that counts as on it [rad for revolute joints, m for prismatic]."""
TRIAL_STEP = math.radians(20.0)
"""Size [rad] of the single-joint moves tried to leave a singular start (revolute joints)."""


class StartWarning(ClikWarning):
    """The start configuration is singular for the task, or on a joint limit."""


_UNCHECKED: ContextVar[bool] = ContextVar("clik_unchecked_starts", default=False)


@contextmanager
def unchecked_starts() -> Iterator[None]:
    """Runs started inside are not checked: starts that are not the user's (a solve's).

    Solve mode runs the loop from its seed, its restarts and the end of each chunk; a
    warning for each would be noise. Per thread and task (a context variable).
    """
    token = _UNCHECKED.set(True)
    try:
        yield
    finally:
        _UNCHECKED.reset(token)


def warn_start(task: Task, q0: np.ndarray, constraints: ConstraintSet | None = None) -> None:
    """Warn (:class:`StartWarning`) when ``q0`` is a poor start for ``task``.

    Args:
        task: The (primary) task.
        q0: The start configuration (nq,).
        constraints: The run's constraint set (its joint-range thresholds count as
            limits), or None.

    Warns:
        StartWarning: ``q0`` is singular for the task, or joints are on a limit;
            the message names the joints and suggests a value.
    """
    if _UNCHECKED.get():
        return
    on_limit = limit_message(task, q0, constraints)
    if on_limit:
        warnings.warn(on_limit, StartWarning, stacklevel=user_stacklevel())
    singular = singular_message(task, q0)
    if singular:
        warnings.warn(singular, StartWarning, stacklevel=user_stacklevel())


def _one_dof(task: Task) -> list[tuple[str, int, str, float, float]]:
    """``(name, q index, kind, lower, upper)`` of the robot's revolute and prismatic joints."""
    robot = task.robot
    model = robot.model
    out = []
    for name, joint in zip(robot.joint_names, model.joints[1:], strict=True):
        kind = joint_kind(joint)
        if kind in (REVOLUTE, PRISMATIC):
            i = joint.idx_q
            out.append((name, i, kind, model.lowerPositionLimit[i], model.upperPositionLimit[i]))
    return out


def task_rank(task: Task, q0: np.ndarray) -> int:
    """The rank of the task Jacobian at generic configurations (seeded random moves from ``q0``).

    A task can have rows no joint ever moves (a planar arm's ``z``, or more rows than
    joints): that rank deficit is the task's, not the start's, and is not warned about.
    """
    model = task.robot.model
    rng = np.random.default_rng(0)
    rank = 0
    for _ in range(2):
        q = pin.integrate(model, q0, rng.uniform(-1.0, 1.0, model.nv))
        rank = max(rank, int(np.linalg.matrix_rank(task.jacobian(q), tol=1e-6)))
    return rank


def singular_value(task: Task, q: np.ndarray, rank: int) -> float:
    """The ``rank``-th singular value of the task Jacobian at ``q`` (its smallest when full)."""
    if rank == 0:
        return math.inf
    return float(np.linalg.svd(task.jacobian(q), compute_uv=False)[rank - 1])


def singular_message(task: Task, q0: np.ndarray) -> str:
    """Why ``q0`` is singular for the task, with a single-joint move that leaves it; or ``""``."""
    rank = task_rank(task, q0)
    sigma = singular_value(task, q0, rank)
    if sigma >= SINGULAR_VALUE:
        return ""
    moves, best = _leave_singularity(task, q0, rank)
    head = (
        f"q0 ([initial] q): the start is singular for the task of frame {task.frame!r} "
        f"(singular value {sigma:.2g} of its Jacobian < {SINGULAR_VALUE:g}): the run may "
        "end in deadlock"
    )
    if best >= SINGULAR_VALUE:
        return f"{head}; start elsewhere, e.g. with " + ", ".join(moves)
    return f"{head}; start elsewhere"


def _leave_singularity(task: Task, q0: np.ndarray, rank: int) -> tuple[list[str], float]:
    """Greedy single-joint moves of :data:`TRIAL_STEP` (within the limits) that leave it.

    Each move is the one that most raises ``sum(log sigma_i)`` over the task's rank (a
    double singularity, such as the UR5's zero posture, needs two moves).

    Returns:
        The moves (``"joint = value unit"``) and the ``rank``-th singular value they
        give (below :data:`SINGULAR_VALUE` when three moves do not leave it).
    """

    def score(q: np.ndarray) -> tuple[float, float]:
        s = np.linalg.svd(task.jacobian(q), compute_uv=False)[:rank]
        return float(np.sum(np.log(np.maximum(s, 1e-12)))), float(s[-1])

    q, moves = q0.copy(), {}
    best, sigma = score(q)
    joints = _one_dof(task)
    for _ in range(min(3, len(joints))):
        found = None
        for name, i, kind, lower, upper in joints:
            step = TRIAL_STEP if kind == REVOLUTE else 0.1 * (upper - lower)
            if not math.isfinite(step) or name in moves:
                continue
            for sign in (1.0, -1.0):
                trial = q.copy()
                trial[i] = q[i] + sign * step
                if lower <= trial[i] <= upper:
                    log_w, trial_sigma = score(trial)
                    if log_w > best + 1e-9:
                        best, sigma = log_w, trial_sigma
                        found = (name, i, float(trial[i]), kind)
        if found is None:
            break
        name, i, moved, kind = found
        q[i] = moved
        moves[name] = f"{name} = {moved:.4g} {'rad' if kind == REVOLUTE else 'm'}"
        if sigma >= SINGULAR_VALUE:
            break
    return list(moves.values()), sigma


def limit_message(task: Task, q0: np.ndarray, constraints: ConstraintSet | None = None) -> str:
    """The joints of ``q0`` on a limit (or inside their joint-range band), or ``""``."""
    bands: dict[str, tuple[float, float, float]] = {}
    jl = None if constraints is None else constraints.joint_limits
    if jl is not None:
        for k, name in enumerate(jl.joint_names):
            bands[name] = (float(jl.lower[k]), float(jl.upper[k]), float(jl.threshold[k]))
    found = []
    for name, i, kind, lower, upper in _one_dof(task):
        unit = "rad" if kind == REVOLUTE else "m"
        margin = LIMIT_MARGIN[kind]
        lo, hi, thr = bands.get(name, (lower, upper, 0.0))
        margin = max(margin, thr)
        band = " (its joint-range threshold)" if thr >= LIMIT_MARGIN[kind] else ""
        for side, limit, d in (("lower", lo, q0[i] - lo), ("upper", hi, hi - q0[i])):
            if math.isfinite(limit) and d <= margin:
                span = hi - lo
                inside = (
                    min(0.5 * span, max(2.0 * margin, 0.1 * span))
                    if math.isfinite(span)
                    else 2.0 * margin
                )
                better = lo + inside if side == "lower" else hi - inside
                where = "beyond" if d < 0 else f"within {margin:.3g} {unit}{band} of"
                found.append(
                    f"{name} = {q0[i]:.4g} {unit} is {where} its {side} limit {limit:.4g} "
                    f"{unit}; try {better:.4g} {unit}"
                )
                break
    if not found:
        return ""
    why = "its joint-range row is active from t = 0" if jl is not None else "it can move one way"
    return f"q0 ([initial] q): start on a joint limit ({'; '.join(found)}): {why}"
