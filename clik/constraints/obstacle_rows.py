r"""Obstacle rows, eqs. (13)-(15) of docs/method.md, from coal's witness points.

With ``p_o`` the witness point on the link, ``c`` the one on the obstacle,
``d = p_o - c`` and threshold ``d_o``:

- ``"squared"`` (the paper's form): ``e_o = 1/2 (d_o^2 - d^T d)`` (13), row
  ``j_o^T = d^T J_po`` (15), feed-forward ``d_o ddot_o + d^T cdot`` (14).
- ``"normalized"``: ``e_o = d_o - |d|``, row ``n^T J_po``, feed-forward
  ``n^T cdot``, with ``n = d / |d|``: the same direction, a row whose size
  does not shrink with ``|d|`` (docs/method.md, "Implementation notes").

``J_po`` is the Jacobian of ``p_o`` fixed on its link at that instant
(``LOCAL_WORLD_ALIGNED``). When the link touches or penetrates the obstacle
(signed distance ``<= 0``), ``n`` is taken along coal's contact normal, so the
row still pushes the link out; the squared form then uses ``e_o = 1/2 (d_o^2 - s|s|)``
with ``s`` the signed distance, which stays monotonic inside the obstacle.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

FORMS = ("normalized", "squared")

CONTACT_DISTANCE = 1e-9
"""At or below this distance [m] (or witness points this close) the row's direction is
coal's contact normal, not the witness points' difference."""
MIN_WITNESS_GAP = 1e-12
"""Witness points closer than this [m] give no direction of their own."""


def point_jacobian(
    model: pin.Model,
    data: pin.Data,
    joint: int,
    point: np.ndarray,
    local: pin.SE3 | None = None,
) -> np.ndarray:
    """Linear Jacobian (3, nv) of a point fixed on joint ``joint``'s body, world-aligned.

    Needs ``computeJointJacobians`` at the current configuration.

    Args:
        model: The robot's model.
        data: The data holding the kinematics.
        joint: The joint whose body carries the point.
        point: The point in the world frame [m].
        local: An ``SE3`` this call may overwrite with the point's placement in the
            joint's frame (a run keeps one: building an ``SE3`` costs 2-3 us); None: a new one.
    """
    placement = pin.SE3.Identity() if local is None else local
    placement.translation = data.oMi[joint].actInv(point)
    return pin.getFrameJacobian(model, data, joint, placement, pin.LOCAL_WORLD_ALIGNED)[:3]


def obstacle_row(
    form: str,
    threshold: float,
    distance: float,
    p_link: np.ndarray,
    p_obstacle: np.ndarray,
    normal: np.ndarray,
    J_point: np.ndarray,
    obstacle_velocity: np.ndarray,
    out: np.ndarray,
) -> tuple[float, float]:
    """Fill the row ``j_o`` (nv,) into ``out``; return the error ``e_o`` and feed-forward.

    Args:
        form: ``"normalized"`` or ``"squared"``.
        threshold: ``d_o`` [m].
        distance: Signed link-obstacle distance [m] (negative in penetration).
        p_link: Witness point on the link [m].
        p_obstacle: Witness point on the obstacle [m].
        normal: coal's unit normal from the link toward the obstacle.
        J_point: Linear Jacobian of ``p_link`` (3, nv).
        obstacle_velocity: ``cdot`` [m/s].
        out: Row output (nv,).
    """
    d = p_link - p_obstacle
    norm = math.sqrt(d.dot(d))
    if distance > CONTACT_DISTANCE and norm > MIN_WITNESS_GAP:
        n = d / norm
    else:  # contact or penetration: push out along the contact normal
        n = -np.asarray(normal, dtype=float)
    error, _ = obstacle_error(form, threshold, distance)
    np.dot(n, J_point, out=out)
    if form == "normalized":
        return error, float(n.dot(obstacle_velocity))
    scale = abs(distance)  # d(|d|^2 / 2) = |d| n^T dd (15); feed-forward |d| n^T cdot (14)
    out *= scale
    return error, scale * float(n @ obstacle_velocity)


def obstacle_error(form: str, threshold: float, distance: float) -> tuple[float, float]:
    """Error ``e_o`` of a link at signed ``distance`` [m] from an obstacle, and its scale.

    ``"normalized"``: ``e_o = d_o - s`` [m], scale ``d_o``. ``"squared"``, the
    paper's (13) with the sign of the signed distance ``s`` kept so that it stays
    monotonic inside the obstacle: ``e_o = 1/2 (d_o^2 - s |s|)`` [m^2], scale
    ``d_o^2 / 2``. The scale makes errors of both forms comparable (hysteresis).

    Args:
        form: ``"normalized"`` or ``"squared"``.
        threshold: ``d_o`` [m].
        distance: Signed link-obstacle distance ``s`` [m] (negative in penetration).
    """
    if form == "normalized":
        return threshold - distance, threshold
    return 0.5 * (threshold * threshold - distance * abs(distance)), 0.5 * threshold * threshold
