r"""The dexterity row: the task's manipulability above a threshold (docs/method.md, "Dexterity").

The paper names constraints on the manipulator's dexterity as the next one to
add; clik's row follows the pattern of the others. With ``J`` the task Jacobian
(m, n) of eq. (3) (``LOCAL_WORLD_ALIGNED``, masked to the task's rows) and
``w = sqrt(det(J J^T))`` (D1) (:func:`clik.manipulability.manipulability`), the
threshold ``w_min`` gives

- the error ``e_w = w_min - w`` (D2), positive when ``w`` is below the threshold
  (as ``e_q = d_q - d`` (17));
- the row ``j_w = grad_q w`` (D3) with ``edot_w = -j_w qdot`` and no feed-forward,
  the sign convention of every row here (the joint row (19) is ``+1`` for a
  lower limit, where ``d = q - q_min`` grows with ``q``): ``de_w/dq = -grad w``;

.. math::

    \frac{\partial w}{\partial q_k} = w \sum_{ij} [(J J^T)^{-1} J]_{ij}
        \frac{\partial J_{ij}}{\partial q_k}

with ``dJ/dq_k`` from Pinocchio's kinematic Hessian of the task frame
(``computeJointKinematicHessians`` on the joint Jacobians the loop computed, then
``getFrameKinematicHessian(..., LOCAL_WORLD_ALIGNED)``, which accounts for the
frame's placement on its joint); ``q_k`` is a velocity coordinate (the
derivative along ``pin.integrate``). Where ``J J^T`` is singular (``w = 0``) the
row is the gradient of ``sqrt(det(J J^T + mu I))``, ``mu`` :data:`SINGULAR_DAMPING`
times the mean eigenvalue, so that it still points away from the singularity.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.manipulability import manipulability

DEXTERITY_KEY = "dexterity"
"""The row's constraint name (events, records)."""

SINGULAR_DAMPING = 1e-9
"""``mu`` of the row at a singular ``J J^T``, relative to its mean eigenvalue."""


class Dexterity:
    """The dexterity constraint: ``w(q) >= w_min`` on the task's manipulability.

    Args:
        threshold: ``w_min`` [m^p, p the task's position rows: m^2 for the case
            study's (x, y) task, m^3 for a position or pose task].

    Raises:
        InputError: A threshold that is not a positive finite number.
    """

    def __init__(self, threshold: float) -> None:
        try:
            value = float(threshold)
        except (TypeError, ValueError):
            value = math.nan
        if isinstance(threshold, bool) or not (math.isfinite(value) and value > 0.0):
            raise InputError(
                "constraints.dexterity.threshold", "a positive manipulability [m^p]", threshold
            )
        self.threshold = value

    def __repr__(self) -> str:
        return f"Dexterity(threshold={self.threshold!r})"

    def error(self, J: np.ndarray) -> tuple[float, float]:
        """The error ``e_w = w_min - w`` (D2) of the task Jacobian ``J`` (m, nv), and ``w``."""
        w = manipulability(J)
        return self.threshold - w, w


def dexterity_row(
    model: pin.Model,
    data: pin.Data,
    frame_id: int,
    rows: np.ndarray,
    J: np.ndarray,
    out: np.ndarray,
) -> float:
    """The row ``j_w = grad_q w`` (D3) into ``out`` (nv,); returns ``w`` (D1).

    Args:
        model: The robot's model.
        data: Its data, with ``computeJointJacobians`` done at the configuration.
        frame_id: The task's frame.
        rows: The task's rows among ``(x, y, z, rx, ry, rz)``.
        J: The task Jacobian (m, nv) at the configuration (those rows, world-aligned).
        out: Row output (nv,) [m^p / rad or m^p / m].
    """
    G = J @ J.T
    try:
        L = np.linalg.cholesky(G)
        w = float(np.prod(np.diagonal(L)))
        scale = w
    except np.linalg.LinAlgError:  # singular: the damped measure's gradient
        mu = SINGULAR_DAMPING * max(float(np.trace(G)) / len(rows), 1e-300)
        L = np.linalg.cholesky(G + mu * np.eye(len(rows)))
        w, scale = 0.0, float(np.prod(np.diagonal(L)))
    A = np.linalg.solve(L.T, np.linalg.solve(L, J))  # (J J^T)^{-1} J
    pin.computeJointKinematicHessians(model, data)
    H = frame_hessian(model, data, frame_id)[rows]  # H[a, i, k] = dJ[a, i] / dq_k
    np.multiply(np.einsum("ai,aik->k", A, H), scale, out=out)
    return w


def frame_hessian(model: pin.Model, data: pin.Data, frame_id: int) -> np.ndarray:
    """``dJ/dq`` (6, nv, nv) of the frame's world-aligned Jacobian: ``[a, i, k] = dJ_ai / dq_k``.

    Needs ``computeJointKinematicHessians``. Pinocchio 4.1's binding hands back the
    column-major tensor with row-major strides; its memory order is read as Fortran
    order (right also once the strides are fixed).
    """
    H = pin.getFrameKinematicHessian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
    return np.asarray(H).ravel(order="K").reshape((6, model.nv, model.nv), order="F")
