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
basis ``B`` of the rows it removes (``N_l z = z - B^T B z``): the constraints' right
singular vectors, then each level's own directions ``Lambda^{-1/2} V^T (J_l N_{l-1})``
from the eigenpairs of ``J_l N_{l-1} (J_l N_{l-1})^T`` above the rank tolerance.

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


def _level_basis(JN: np.ndarray, scale: float) -> np.ndarray:
    """Orthonormal rows spanning ``JN``'s row space (its directions above the rank tolerance)."""
    w, V = np.linalg.eigh(JN.dot(JN.T))
    keep = w > (RANK_TOLERANCE * max(scale, 1.0)) ** 2
    return (V[:, keep].T.dot(JN)) / np.sqrt(w[keep])[:, None]


def _project(B: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``N z = z - B^T B z``: ``z`` with the directions of ``B``'s rows removed."""
    return z - B.T.dot(B.dot(z)) if B.shape[0] else z.copy()


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
    B = np.zeros((0, n))
    if C.shape[0]:
        epsilon = CONDITION_RATIO * scale1
        U, sv, Vt = np.linalg.svd(C, full_matrices=False)
        gain = sv / (np.maximum(sv * sv, epsilon * epsilon) + damping * damping)
        parts[0] = _within_budget(Vt.T.dot(gain * U.T.dot(b_constraint)), dt)
        B = Vt[sv > RANK_TOLERANCE * max(scale1, 1.0)]
    out[:] = parts[0]
    blocked = 0.0
    start = 0
    for level, end in enumerate(ends, start=1):
        Jl, bl = J[start:end], b_task[start:end]
        scale = _scale(Jl)
        epsilon = CONDITION_RATIO * scale
        JN = Jl - Jl.dot(B.T).dot(B) if B.shape[0] else Jl
        rest = bl - Jl.dot(out)
        part = parts[level]
        part[:] = JN.T.dot(damped_solve(JN.dot(JN.T), rest, epsilon, damping))
        if level == 1 and not budget_blocks:  # measured on the law's own demand
            blocked = _unrealised(Jl, bl, out + part)
        _within_budget(part, dt)
        last = level == len(ends)
        mine = [z for lo, z in objectives if lo == level]
        if mine or not last:
            B = np.vstack([B, _level_basis(JN, scale)])
        for z in mine:
            part += _within_budget(_project(B, z), dt)
        out += part
        if level == 1 and budget_blocks:
            blocked = _unrealised(Jl, bl, out)
        start = end
    return blocked
