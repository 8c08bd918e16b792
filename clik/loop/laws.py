"""The three closed-loop laws of docs/method.md, as functions on preallocated arrays.

Each law maps the (possibly extended) task Jacobian ``J`` (r, n), the error
``e`` (r,), per-row gains ``K`` (r,) and the reference velocity ``xdot_d``
(r,) to joint velocities ``qdot`` (n,), written into ``out``. With constraint
rows appended, ``J`` is ``J_e`` of eq. (24) and ``e`` is ``e_e`` of eq. (25).

- ``"transpose"``, eq. (9) / (23): ``qdot = J^T K e``.
- ``"nonlinear"``, eq. (8): ``qdot = J^T K e + beta J^T e`` with
  ``beta = (e^T xdot_d) / (e^T J J^T e)``; for a scalar gain ``K = alpha I``
  this is ``gamma J^T e``, ``gamma = alpha + beta``.
- ``"pseudoinverse"``, eq. (10): ``qdot = J^+ (K e + xdot_d)``, solved by
  :func:`prioritized` with the constraint rows first and the task in their null
  space, singularity-robust (:func:`damped_solve`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal, cast

import numpy as np

from clik.errors import InputError

LawName = Literal["transpose", "nonlinear", "pseudoinverse"]
LAWS: tuple[str, ...] = ("transpose", "nonlinear", "pseudoinverse")


def check_law(law: str) -> LawName:
    """Return ``law`` if it is a known law name, else raise :class:`InputError`."""
    if law not in LAWS:
        raise InputError("law", "one of 'transpose', 'nonlinear', 'pseudoinverse'", law)
    return cast(LawName, law)


def transpose(
    J: np.ndarray,
    e: np.ndarray,
    K: np.ndarray,
    xdot_d: np.ndarray,
    out: np.ndarray,
    work: np.ndarray,
) -> np.ndarray:
    """Jacobian-transpose law, eq. (9) (and (23) on the extended task): ``qdot = J^T K e``.

    Args:
        J: Task Jacobian (r, n).
        e: Task error (r,).
        K: Gains per row [1/s] (r,).
        xdot_d: Reference velocity (r,); unused by this law (kept for a common signature).
        out: Joint velocity output (n,) [rad/s].
        work: Scratch array (r,).
    """
    np.multiply(K, e, out=work)
    return J.T.dot(work, out=out)


def nonlinear(
    J: np.ndarray,
    e: np.ndarray,
    K: np.ndarray,
    xdot_d: np.ndarray,
    out: np.ndarray,
    work: np.ndarray,
    jte: np.ndarray,
    beta_max: float,
) -> np.ndarray:
    """Nonlinear-gain law, eq. (8): ``qdot = J^T K e + beta J^T e``.

    ``beta = (e^T xdot_d) / |J^T e|^2`` makes ``Vdot = -e^T J J^T K e`` along
    the exact flow. It is unbounded as ``e -> 0``; in discrete time it is
    clipped to ``|beta| <= beta_max`` [1/s] (docs/method.md: "filter it").

    Args:
        J: Task Jacobian (r, n).
        e: Task error (r,).
        K: Gains per row [1/s] (r,).
        xdot_d: Reference velocity (r,).
        out: Joint velocity output (n,) [rad/s].
        work: Scratch array (r,).
        jte: Scratch array (n,) for ``J^T e``.
        beta_max: Bound on ``|beta|`` [1/s].
    """
    np.dot(J.T, e, out=jte)
    den = float(np.dot(jte, jte))
    num = float(np.dot(e, xdot_d))
    beta = num / den if den > 0.0 else 0.0
    if beta > beta_max:
        beta = beta_max
    elif beta < -beta_max:
        beta = -beta_max
    np.multiply(K, e, out=work)
    np.dot(J.T, work, out=out)
    out += beta * jte
    return out


def solve_small(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A^-1 b`` for a small square ``A``; the SVD pseudoinverse when ``A`` is singular.

    Calls LAPACK's ``gesv`` through numpy's gufunc directly: ``np.linalg.solve``'s
    Python-side checks cost three times the solve itself for a 6x6 system.
    """
    y = _solve1(A, b)  # hot loops run under np.errstate(invalid="ignore")
    if math.isfinite(y.dot(y)):
        return y
    if not finite(A, b):  # the SVD of a non-finite matrix may never return: give NaN back
        return np.full(b.shape, np.nan)
    return np.linalg.pinv(A).dot(b)  # singular A: gesv gave NaN


def finite(*arrays: np.ndarray) -> bool:
    """Whether every entry of every array is finite, and their sum too (no solver call else).

    LAPACK's SVD and eigensolvers may loop without end, or fail, on inf or NaN; the laws
    return NaN joint velocities instead, which the tracking loop stops as ``diverged``
    (:func:`clik.loop.stop_checks.non_finite_reason`), as the compiled engine does.
    """
    return all(math.isfinite(float(a.sum())) for a in arrays)  # inf or NaN: a sum not finite


def _numpy_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.solve(A, b)


_solve1: Callable[[np.ndarray, np.ndarray], np.ndarray]
try:  # numpy's private gufunc: checked once here, with a public fallback
    from numpy.linalg import _umath_linalg

    _solve1 = _umath_linalg.solve1
    _solve1(np.eye(2), np.ones(2))
except (ImportError, AttributeError, TypeError):  # pragma: no cover - other numpy builds
    _solve1 = _numpy_solve


# -- law (10) on the extended task: constraints first, the task in their null space ----

CONDITION_RATIO = 0.01
"""Damping starts when a singular value falls below this fraction of ``sigma_max(J)``."""

RANK_TOLERANCE = 1e-9
"""A constraint direction counts (its singular value, relative to ``max(scale, 1)``) above this:
a duplicated row adds no direction to the null-space projection."""
STEP_BUDGET = 0.02
"""Largest joint step [rad or m] each level of law (10) may ask for in one sample; a larger
one is scaled down whole (its direction kept), see :func:`prioritized`."""


def damped_solve(A: np.ndarray, b: np.ndarray, epsilon: float, damping: float) -> np.ndarray:
    r"""``y`` with ``M^T y`` the singularity-robust pseudoinverse solution, ``A = M M^T``.

    Singular-value filtering (Maciejewski and Klein 1988; Chiaverini 1997): with
    ``A = V diag(sigma_i^2) V^T``,

    .. math::

        y = V \operatorname{diag}\big(1 / (\max(\sigma_i^2, \epsilon^2) + \lambda_0^2)\big)
        V^T b,

    so a direction with ``sigma_i >= epsilon`` is solved exactly (the pseudoinverse of
    eq. (10)), and one that loses rank (``sigma_i < epsilon``) contributes
    ``sigma_i / epsilon^2 <= 1 / epsilon`` times its demand instead of ``1 / sigma_i``:
    the joint speed stays bounded through a singularity and vanishes on an exactly
    blocked direction.

    Args:
        A: ``M M^T`` (r, r).
        b: Right-hand side (r,).
        epsilon: Singular value [row unit per rad] below which damping starts.
        damping: ``lambda_0``, the user's constant damping (0: none).
    """
    if not finite(A, b):
        return np.full(b.shape, np.nan)
    w, V = np.linalg.eigh(A)
    np.maximum(w, epsilon * epsilon, out=w)
    w += damping * damping
    if not np.all(w > 0.0):  # exactly singular without damping: drop those directions
        w[w <= 0.0] = np.inf
    return V.dot(V.T.dot(b) / w)


def _within_budget(qdot: np.ndarray, dt: float) -> np.ndarray:
    """``qdot`` scaled down whole so that no joint moves more than ``STEP_BUDGET`` in ``dt``."""
    step = float(np.abs(qdot).max()) * dt if qdot.size else 0.0
    if step > STEP_BUDGET:
        qdot *= STEP_BUDGET / step
    return qdot


def prioritized(
    J: np.ndarray,
    b_task: np.ndarray,
    C: np.ndarray,
    b_constraint: np.ndarray,
    out: np.ndarray,
    damping: float,
    dt: float,
    out_c: np.ndarray | None = None,
    budget_blocks: bool = True,
) -> float:
    r"""Law (10) on the extended task, constraints first and the task in their null space.

    With the active constraint rows ``C`` (v, n) and their demand
    ``b_c = K_c e_c + f_c``, and the task ``J`` (m, n) with ``b = K e + xdot_d``:

    .. math::

        \dot q_c = C^{\#} b_c, \qquad N = I - C^{+} C, \qquad
        \dot q = \dot q_c + (J N)^{\#} (b - J \dot q_c)

    (Siciliano and Slotine 1991; Chiaverini 1997), ``#`` the filtered pseudoinverse of
    :func:`damped_solve`. Where ``(J; C)`` has full rank this is exactly
    ``J_e^+ (K e_e + ydot_d)`` of eq. (10) on the extended task (24)-(25); where the task
    and the constraints conflict (``J N`` loses rank) the constraints still hold and the
    task gives way, with bounded joint speeds, instead of the extended Jacobian's inverse
    swinging the arm.

    Each level is damped below ``epsilon = 0.01 sigma_max(J)`` (singularity-robust), and a
    level whose joint step ``max_i |qdot_i| dt`` would exceed :data:`STEP_BUDGET` is scaled
    down whole, direction kept: a task error that built up while blocked is not caught up
    through a direction that just regained a little rank (the "swing"). In regular
    tracking neither is active and the solution is the exact one; a scaled level leaves
    part of its demand unrealised, which the returned fraction reports (and the deadlock
    check counts).

    Args:
        J: Task rows (m, n).
        b_task: ``K e + xdot_d`` for the task rows (m,).
        C: Active constraint rows (v, n), v >= 0.
        b_constraint: ``K_c e_c + f_c`` (v,).
        out: Joint velocity output (n,) [rad/s].
        damping: The user's constant damping ``lambda_0`` (0: none).
        dt: Sample time [s].
        out_c: Where to write the constraint level's part ``qdot_c`` (n,) (0 without
            constraint rows), for the speed step (:mod:`clik.loop.speed_step`); or None.
        budget_blocks: Whether the task level's step budget counts in the returned
            fraction (False with joint speed limits: a slowed demand is not blocked).

    Returns:
        The part of the task demand the law could not realise, ``|b - J qdot| / |b|``
        (0 when tracked exactly; near 1 when the task is blocked).
    """
    if not finite(J, b_task, C, b_constraint):  # no solver call on inf or NaN
        out[:] = np.nan
        return 0.0
    scale = math.sqrt(float(np.max(np.einsum("ij,ij->i", J, J)))) if J.size else 0.0
    epsilon = CONDITION_RATIO * scale
    if C.shape[0]:
        # One SVD, C = U diag(s) V^T, serves both levels: the filtered inverse of C, and
        # the null-space projection J N = J - (J V_r) V_r^T on its row space V_r.
        U, sv, Vt = np.linalg.svd(C, full_matrices=False)
        gain = sv / (np.maximum(sv * sv, epsilon * epsilon) + damping * damping)
        qdot_c = _within_budget(Vt.T.dot(gain * U.T.dot(b_constraint)), dt)
        rows = Vt[sv > RANK_TOLERANCE * max(scale, 1.0)]  # a duplicated row adds no direction
        JN = J - J.dot(rows.T).dot(rows)
        rest = b_task - J.dot(qdot_c)
        qdot_t = JN.T.dot(damped_solve(JN.dot(JN.T), rest, epsilon, damping))
    else:
        qdot_c = None
        qdot_t = J.T.dot(damped_solve(J.dot(J.T), b_task, epsilon, damping))
    if out_c is not None:
        out_c[:] = 0.0 if qdot_c is None else qdot_c
    blocked = 0.0
    if not budget_blocks:  # measured on the law's own demand, before the budget
        blocked = _unrealised(J, b_task, qdot_t if qdot_c is None else qdot_c + qdot_t)
    _within_budget(qdot_t, dt)
    out[:] = qdot_t if qdot_c is None else qdot_c + qdot_t
    return _unrealised(J, b_task, out) if budget_blocks else blocked


def _unrealised(J: np.ndarray, b: np.ndarray, qdot: np.ndarray) -> float:
    """``|b - J qdot| / |b|``: the part of the task's demand ``qdot`` does not realise."""
    demand = float(np.linalg.norm(b))
    if demand == 0.0:
        return 0.0
    return float(np.linalg.norm(b - J.dot(qdot))) / demand
