"""The three closed-loop laws of METHOD.md, as functions on preallocated arrays.

Each law maps the (possibly extended) task Jacobian ``J`` (r, n), the error
``e`` (r,), per-row gains ``K`` (r,) and the reference velocity ``xdot_d``
(r,) to joint velocities ``qdot`` (n,), written into ``out``. With constraint
rows appended, ``J`` is ``J_e`` of eq. (24) and ``e`` is ``e_e`` of eq. (25).

- ``"transpose"``, eq. (9) / (23): ``qdot = J^T K e``.
- ``"nonlinear"``, eq. (8): ``qdot = J^T K e + beta J^T e`` with
  ``beta = (e^T xdot_d) / (e^T J J^T e)``; for a scalar gain ``K = alpha I``
  this is ``gamma J^T e``, ``gamma = alpha + beta``.
- ``"pseudoinverse"``, eq. (10): ``qdot = J^T (J J^T + lambda^2 I)^{-1} (K e + xdot_d)``,
  the damped pseudoinverse (``lambda = 0``: the Moore-Penrose one).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from clik.errors import InputError

LawName = Literal["transpose", "nonlinear", "pseudoinverse"]
LAWS: tuple[str, ...] = ("transpose", "nonlinear", "pseudoinverse")


def check_law(law: str) -> LawName:
    """Return ``law`` if it is a known law name, else raise :class:`InputError`."""
    if law not in LAWS:
        raise InputError("law", "one of 'transpose', 'nonlinear', 'pseudoinverse'", law)
    return law  # type: ignore[return-value]


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
    clipped to ``|beta| <= beta_max`` [1/s] (METHOD.md: "filter it").

    Args:
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


def pseudoinverse(
    J: np.ndarray,
    e: np.ndarray,
    K: np.ndarray,
    xdot_d: np.ndarray,
    out: np.ndarray,
    work: np.ndarray,
    damping: float,
) -> np.ndarray:
    """Pseudoinverse law with feed-forward, eq. (10): ``qdot = J^+ (K e + xdot_d)``.

    Solves the small (r, r) system ``(J J^T + lambda^2 I) y = K e + xdot_d``
    and returns ``J^T y``; a singular system without damping falls back to
    the SVD pseudoinverse.

    Args:
        damping: ``lambda`` [same unit as J's rows]; 0 for the exact pseudoinverse.
    """
    np.multiply(K, e, out=work)
    work += xdot_d
    A = J.dot(J.T)
    if damping > 0.0:
        A.flat[:: A.shape[0] + 1] += damping * damping
    return J.T.dot(solve_small(A, work), out=out)


def solve_small(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A^-1 b`` for a small square ``A``; the SVD pseudoinverse when ``A`` is singular.

    Calls LAPACK's ``gesv`` through numpy's gufunc directly: ``np.linalg.solve``'s
    Python-side checks cost three times the solve itself for a 6x6 system.
    """
    y = _solve1(A, b)  # hot loops run under np.errstate(invalid="ignore")
    if math.isfinite(y.dot(y)):
        return y
    return np.linalg.pinv(A).dot(b)  # singular A: gesv gave NaN


def _numpy_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.solve(A, b)


try:  # numpy's private gufunc: checked once here, with a public fallback
    from numpy.linalg import _umath_linalg

    _solve1 = _umath_linalg.solve1
    _solve1(np.eye(2), np.ones(2))
except (ImportError, AttributeError, TypeError):  # pragma: no cover - other numpy builds
    _solve1 = _numpy_solve
