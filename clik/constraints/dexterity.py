r"""The dexterity row: the task's manipulability above a threshold (docs/method.md, "Dexterity").

The paper names constraints on the manipulator's dexterity as the next one to
add; clik's row follows the pattern of the others. With ``J`` the task Jacobian
(m, n) of eq. (3) (``LOCAL_WORLD_ALIGNED``, masked to the task's rows) and
``w = sqrt(det(J J^T))`` (D1) (:func:`clik.tasks.manipulability.manipulability`), the
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
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.kind import (
    CHECK_TOLERANCE,
    Candidate,
    ConstraintKind,
    KindRun,
    PoseCheck,
    RunSetup,
    Sample,
    Violation,
)
from clik.constraints.words import AS_IS
from clik.errors import InputError
from clik.tasks.manipulability import manipulability

if TYPE_CHECKING:
    from clik.outputs.result import TrackingResult

DEXTERITY_KEY = "dexterity"
"""The row's constraint name (events, records)."""

SINGULAR_DAMPING = 1e-9
"""``mu`` of the row at a singular ``J J^T``, relative to its mean eigenvalue."""


class Dexterity(ConstraintKind):
    """The dexterity constraint: ``w(q) >= w_min`` on the task's manipulability.

    Args:
        threshold: ``w_min`` [m^p, p the task's position rows: m^2 for the case
            study's (x, y) task, m^3 for a position or pose task].
        gain: The row's gain [1/s]; None: the law's default.

    Raises:
        InputError: A threshold that is not a positive finite number.
    """

    name = "dexterity"
    depth_measure = AS_IS
    """A depth in manipulability [m^p]."""
    limit_words = None
    """No limit: below the threshold is allowed (the row pushes back), and nothing crosses."""

    def __init__(self, threshold: float, gain: float | None = None) -> None:
        try:
            value = float(threshold)
        except (TypeError, ValueError):
            value = math.nan
        if isinstance(threshold, bool) or not (math.isfinite(value) and value > 0.0):
            raise InputError(
                "constraints.dexterity.threshold", "a positive manipulability [m^p]", threshold
            )
        self.threshold = value
        self.gain = gain

    @classmethod
    def check_name(cls, key: str) -> str:
        """``dexterity`` (its one row's key and its check's name)."""
        return key

    def __repr__(self) -> str:
        return f"Dexterity(threshold={self.threshold!r})"

    def error(self, J: np.ndarray) -> tuple[float, float]:
        """The error ``e_w = w_min - w`` (D2) of the task Jacobian ``J`` (m, nv), and ``w``."""
        w = manipulability(J)
        return self.threshold - w, w

    def start(self, setup: RunSetup) -> DexterityRun:
        """The row's state for one run (the task's frame and rows).

        Raises:
            InputError: No task frame given.
        """
        if setup.frame_id < 0:
            raise InputError("constraints.dexterity", "the task's frame and rows for the row")
        return DexterityRun(self, setup)

    def engine_config(self) -> Any:
        """``_engine.DexterityConfig``."""
        from clik.engine import load

        return load().DexterityConfig(threshold=self.threshold, gain=self.gain)

    def finish(
        self, result: TrackingResult, records: dict[str, Any], n_rec: int, extra: dict[str, Any]
    ) -> None:
        """The row's settings as ``dexterity_used``."""
        extra["dexterity_used"] = {"threshold": self.threshold, "gain": self.gain}

    def check(self, checker: PoseCheck, q: np.ndarray) -> list[Violation]:
        """``w(q) < w_min`` (D1)-(D2) on the task rows."""
        J = checker.task_jacobian(q)
        if J is None:
            return []
        error, w = self.error(J)
        if error <= CHECK_TOLERANCE * self.threshold:
            return []
        detail = f"manipulability w = {w:.4g} < threshold {self.threshold:.4g}"
        return [Violation(self.check_name(DEXTERITY_KEY), detail, error)]

    def with_margin(self, margin: float) -> Dexterity:
        """The threshold ``margin`` larger (solve mode)."""
        return Dexterity(self.threshold + margin, self.gain)

    def fingerprint(self) -> tuple[Any, ...]:
        """Threshold and gain."""
        return (self.threshold, self.gain)


class DexterityRun(KindRun):
    """The dexterity row in one run: ``w`` every sample, its gradient while active.

    Attributes:
        manipulability: This sample's ``w`` (D1) [m^p].
    """

    def __init__(self, kind: Dexterity, setup: RunSetup) -> None:
        super().__init__(kind)
        self.kind: Dexterity = kind
        self.frame_id = setup.frame_id
        self.task_rows = setup.task_rows
        self.manipulability = math.nan

    def evaluate(self, s: Sample, out: list[Candidate]) -> None:
        """The error (D2) of the task rows: a candidate when positive or active.

        Only ``w`` (D1) is evaluated here (a Cholesky factor of the m x m ``J J^T``); the
        row's gradient (D3), which needs the kinematic Hessian, only while it is active.
        """
        error, self.manipulability = self.kind.error(s.J_task)
        if error > 0.0 or DEXTERITY_KEY in s.active_keys:
            thr = self.kind.threshold
            out.append(Candidate(DEXTERITY_KEY, self, 0, error, thr, thr))

    def row(self, s: Sample, c: Candidate, out: np.ndarray) -> None:
        """The gradient (D3), no feed-forward."""
        dexterity_row(s.model, s.data, self.frame_id, self.task_rows, s.J_task, out)
        c.feed = 0.0


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
