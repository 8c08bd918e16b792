"""The solver-independent check of a reached pose: position and orientation errors."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

POSITION_TOLERANCE = 1e-4
"""Single-pose solve: position tolerance [m]."""
ORIENTATION_TOLERANCE = 1e-3
"""Single-pose solve: orientation tolerance [rad]."""


def pose_errors(
    model: pin.Model, data: pin.Data, fid: int, q: np.ndarray, target: pin.SE3
) -> tuple[float, float]:
    """Position [m] and orientation [rad] errors of frame ``fid`` at ``q`` against ``target``.

    Args:
        model: The robot model.
        data: Scratch data of ``model`` (overwritten).
        fid: Frame index.
        q: Configuration.
        target: Desired placement of the frame.

    Returns:
        ``(|p_d - p|, |log3(R_d R^T)|)``.
    """
    pin.framesForwardKinematics(model, data, q)
    placement = data.oMf[fid]
    dp = target.translation - placement.translation
    rot = pin.log3(target.rotation @ placement.rotation.T)
    return math.sqrt(float(dp @ dp)), math.sqrt(float(rot @ rot))


def within_tolerance(errors: tuple[float, float]) -> bool:
    """Whether ``(position, orientation)`` errors are both within the solve tolerances.

    Args:
        errors: As returned by :func:`pose_errors`.
    """
    return errors[0] <= POSITION_TOLERANCE and errors[1] <= ORIENTATION_TOLERANCE
