r"""Law (10) with priority levels, and the null-space term ``z`` of eq. (5).

docs/method.md, "Several tasks, priority levels and eq. (5)". The task rows of the
extended task are grouped into levels ``1 .. L`` (rows ``ends[l-1] .. ends[l]``); the
active constraint rows ``C`` come first, as in :func:`clik.loop.laws.prioritized`:

.. math::

    \dot q_c = C^{\#} b_c, \qquad
    \dot q_l = (J_l N_{l-1})^{\#} \big(b_l - J_l \textstyle\sum_{k<l} \dot q_k\big),
    \qquad \dot q = \dot q_c + \textstyle\sum_l \dot q_l + \textstyle\sum_o N_{l_o} z_o

(Siciliano and Slotine 1991; Chiaverini 1997), with ``N_{l}`` the projector on the null
space of ``C`` and of levels ``1 .. l`` (``N_0`` that of ``C``), ``#`` the filtered
pseudoinverse of :func:`~clik.loop.laws.damped_solve`, each level damped below
``CONDITION_RATIO`` of its own largest row norm and held to the step budget
(:data:`~clik.loop.laws.STEP_BUDGET`), and ``z_o`` the objectives of eq. (5) (a gradient,
:mod:`clik.objectives`) acting below level ``l_o``. ``N_l`` is kept as an orthonormal
basis ``Z_l`` of the directions it leaves free (``N_l = Z_l Z_l^T``, ``Z_0`` that of
``C``): a level is solved in those coordinates, ``M = J_l Z_{l-1}``,
``qdot_l = Z M^T f(M M^T) rest = Z f(M^T M) M^T rest`` from the smaller Gram matrix,
and ``Z_l = Z_{l-1} W`` with ``W`` the orthogonal complement of the directions the
level keeps (those of ``M M^T``'s eigenpairs above the tolerances, at most as many as
the directions still free): docs/method.md, "In the free directions' coordinates".

With one level and no objective this is exactly :func:`~clik.loop.laws.prioritized`
(one code path is the other's specification: the tracker calls that one then).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from clik.loop.laws import (
    CONDITION_RATIO,
    RANK_TOLERANCE,
    _unrealised,
    _within_budget,
    damped_solve,
    finite,
)


def _scale(J: np.ndarray) -> float:
    """Largest row norm of ``J`` (0 without rows)."""
    return math.sqrt(float(np.max(np.einsum("ij,ij->i", J, J)))) if J.size else 0.0


GRAM_TOLERANCE = 1e-12
"""A level's direction counts when its eigenvalue of ``JN JN^T`` is above this fraction of
the level's squared scale too (its largest squared row norm): rounding leaves about
``1e-16 n |J_l|^2`` on the zero eigenvalues of that product, above the rank tolerance's
square."""


def _kept_directions(M: np.ndarray, scale: float) -> np.ndarray:
    """The directions (k, p) of ``M``'s row space above the tolerances, in Z's coordinates.

    ``M^T V Lambda^{-1/2}`` from the eigenpairs of ``M M^T``, at most k of them (the
    largest: ``M``'s rank is at most k).
    """
    w, V = np.linalg.eigh(M.dot(M.T))  # ascending
    keep = w > max((RANK_TOLERANCE * max(scale, 1.0)) ** 2, GRAM_TOLERANCE * scale * scale)
    keep[: max(0, len(w) - M.shape[1])] = False
    return M.T.dot(V[:, keep]) / np.sqrt(w[keep])


def _without(Z: np.ndarray, P: np.ndarray) -> np.ndarray:
    """What is left free of ``Z`` once ``P``'s columns (k, p, rank p) are removed.

    ``Z W`` with ``W`` (k, k - p) an orthonormal basis of their complement in ``R^k``.
    """
    k, p = P.shape
    if p == 0:
        return Z
    if p >= k:
        return Z[:, :0]
    Q = np.linalg.qr(P, mode="complete")[0]
    return Z.dot(Q[:, p:])


def _level(Jl: np.ndarray, rest: np.ndarray, Z: np.ndarray, damping: float,
           basis: bool) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """One level in the free directions ``Z`` (n, k), law (10) on ``M = J_l Z``.

    Returns its part ``Z f(.) M^T rest`` and, for a basis level, the directions left
    free below it (else ``Z``).
    """
    scale = _scale(Jl)
    epsilon = CONDITION_RATIO * scale
    M = Jl.dot(Z)
    if M.shape[0] <= M.shape[1]:
        x = M.T.dot(damped_solve(M.dot(M.T), rest, epsilon, damping))
    else:  # more rows than free directions: the k x k Gram matrix
        x = damped_solve(M.T.dot(M), M.T.dot(rest), epsilon, damping)
    return Z.dot(x), _without(Z, _kept_directions(M, scale)) if basis else Z


def _project(Z: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``N z = Z Z^T z``: ``z`` in the directions left free."""
    return Z.dot(Z.T.dot(z))


def prioritized_levels(
    J: np.ndarray,
    b_task: np.ndarray,
    ends: Sequence[int],
    C: np.ndarray,
    b_constraint: np.ndarray,
    out: np.ndarray,
    damping: float,
    dt: float,
    parts: np.ndarray,
    objectives: Sequence[tuple[int, np.ndarray]] = (),
    budget_blocks: bool = True,
) -> float:
    """Law (10) with priority levels and eq. (5)'s objectives (the module's equations).

    Args:
        J: Task rows of every level (m, n), level by level.
        b_task: ``K e + xdot_d`` of those rows (m,).
        ends: End row of each level (strictly increasing, the last ``m``).
        C: Active constraint rows (v, n), v >= 0.
        b_constraint: ``K_c e_c + f_c`` (v,).
        out: Joint velocity output (n,) [rad/s].
        damping: The user's constant damping ``lambda_0`` (0: none).
        dt: Sample time [s].
        parts: Output (1 + L, n): the constraint level's part, then each level's (its
            objectives included), for the speed step (:mod:`clik.loop.speed_step`).
        objectives: ``(l, z)`` pairs: the gradient ``z`` (n,) [rad/s] acting in the null
            space of the constraints and levels ``1 .. l`` (``l`` from 1 to L).
        budget_blocks: Whether the first level's step budget counts in the returned
            fraction (False with joint speed limits).

    Returns:
        The part of the first level's demand the law could not realise,
        ``|b_1 - J_1 qdot| / |b_1|`` (lower levels give way by design).
    """
    if not finite(J, b_task, C, b_constraint, *(z for _, z in objectives)):
        out[:] = np.nan
        parts[:] = np.nan
        return 0.0
    n = J.shape[1]
    parts[:] = 0.0
    e1 = ends[0]
    scale1 = _scale(J[:e1])
    Z = np.eye(n)
    if C.shape[0]:
        epsilon = CONDITION_RATIO * scale1
        U, sv, Vt = np.linalg.svd(C, full_matrices=False)
        gain = sv / (np.maximum(sv * sv, epsilon * epsilon) + damping * damping)
        parts[0] = _within_budget(Vt.T.dot(gain * U.T.dot(b_constraint)), dt)
        Z = _without(Z, Vt[sv > RANK_TOLERANCE * max(scale1, 1.0)].T)
    out[:] = parts[0]
    blocked = 0.0
    start = 0
    for level, end in enumerate(ends, start=1):
        Jl, bl = J[start:end], b_task[start:end]
        mine = [z for lo, z in objectives if lo == level]
        part = parts[level]
        part[:], Z = _level(Jl, bl - Jl.dot(out), Z, damping, bool(mine) or level < len(ends))
        if level == 1 and not budget_blocks:  # measured on the law's own demand
            blocked = _unrealised(Jl, bl, out + part)
        _within_budget(part, dt)
        for z in mine:
            part += _within_budget(_project(Z, z), dt)
        out += part
        if level == 1 and budget_blocks:
            blocked = _unrealised(Jl, bl, out)
        start = end
    return blocked
