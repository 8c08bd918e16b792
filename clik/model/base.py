"""Mobile and floating bases: a root joint between the world and the robot's root link.

A fixed-base robot is welded to the world. A *planar* base (a mobile manipulator on the
floor) adds Pinocchio's ``JointModelPlanar`` as the model's first joint: configuration
``(x, y, cos theta, sin theta)`` [m, m, -, -], velocity ``(v_x, v_y, omega_z)`` [m/s,
m/s, rad/s] in the base's own frame (nq 4, nv 3). A *floating* base (a humanoid, a
legged robot) adds ``JointModelFreeFlyer``: configuration ``(x, y, z, q_x, q_y, q_z,
q_w)`` [m, m, m, unit quaternion], velocity ``(v, omega)`` [m/s, rad/s] in the base's
own frame (nq 7, nv 6). The root joint is named :data:`BASE_JOINT`.

The base moves like any other joint: its velocity is the first ``nv`` entries of
``qdot``, its columns are the first of every Jacobian, its configuration is integrated on
its manifold by ``pin.integrate``. Its position is unlimited (no joint-range rows); its
speed is bounded like a joint's, through ``model.velocityLimit``
(:data:`DEFAULT_LINEAR_SPEED`, :data:`DEFAULT_ANGULAR_SPEED`, or ``base_speed``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pinocchio as pin

from clik.errors import InputError

FIXED = "fixed"
"""The robot's root link is welded to the world (no base joint)."""
PLANAR = "planar"
"""A planar root joint: x, y [m] and a rotation about the world's z axis."""
FLOATING = "floating"
"""A free-flyer root joint: a position [m] and an orientation (a unit quaternion)."""
BASES = (FIXED, PLANAR, FLOATING)
"""The bases :meth:`Robot.load` accepts (``base=``, a scenario's ``[robot] base``)."""

BASE_JOINT = "root_joint"
"""Name of the root joint of a planar or floating base (``robot.joint_names[0]``): Pinocchio's
default, the name example-robot-data's SRDF postures give the base's values under."""

DEFAULT_LINEAR_SPEED = 1.0
"""Default largest speed of each of the base's translation coordinates [m/s]."""
DEFAULT_ANGULAR_SPEED = 1.0
"""Default largest speed of each of the base's rotation coordinates [rad/s]."""

QUATERNION_TOLERANCE = 1e-3
"""A written quaternion (or cos, sin pair) whose norm is off 1 by more than this is refused;
a smaller deviation is normalised."""


def check_base(base: object, field: str = "base") -> str:
    """``base`` if it is one of :data:`BASES`.

    Raises:
        InputError: Anything else (names ``field`` and the three choices).
    """
    if not isinstance(base, str) or base not in BASES:
        raise InputError(field, "one of 'fixed', 'planar', 'floating'", got=base)
    return base


def check_base_speed(speed: object, field: str = "base_speed") -> tuple[float, float]:
    """The base's speed limits ``(linear [m/s], angular [rad/s])``, checked.

    Args:
        speed: Two positive finite numbers, or None for the defaults
            (:data:`DEFAULT_LINEAR_SPEED`, :data:`DEFAULT_ANGULAR_SPEED`).
        field: Name of the input, used in the error message.

    Raises:
        InputError: Not two positive finite numbers.
    """
    if speed is None:
        return DEFAULT_LINEAR_SPEED, DEFAULT_ANGULAR_SPEED
    expected = "two positive finite speeds [linear m/s, angular rad/s]"
    if isinstance(speed, str | bytes) or not hasattr(speed, "__len__") or len(speed) != 2:
        raise InputError(field, expected, got=speed)
    values: list[float] = []
    for value in speed:  # type: ignore[attr-defined]
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
            raise InputError(field, expected, got=speed)
        if not (math.isfinite(float(value)) and float(value) > 0.0):
            raise InputError(field, expected, got=speed)
        values.append(float(value))
    return values[0], values[1]


def check_base_options(
    base: object, speed: object, lock: Mapping[str, float] | None
) -> tuple[float, float]:
    """Check :meth:`Robot.load`'s ``base`` and ``base_speed`` (and its ``lock``).

    Returns:
        The base's speed limits ``(linear [m/s], angular [rad/s])``.

    Raises:
        InputError: An unknown ``base``; a bad ``base_speed``, or one for a fixed base;
            the base joint in ``lock`` (a base is fixed by ``base="fixed"``).
    """
    check_base(base)
    checked = check_base_speed(speed)
    if speed is not None and base == FIXED:
        raise InputError("base_speed", "a planar or floating base (base is 'fixed')", speed)
    if base != FIXED and lock and BASE_JOINT in lock:
        raise InputError(f"lock[{BASE_JOINT!r}]", "a joint other than the base", lock[BASE_JOINT])
    return checked


def root_joint(base: str) -> pin.JointModel | None:
    """Pinocchio's root joint of a base: None (fixed), planar or free-flyer."""
    if base == PLANAR:
        return pin.JointModelPlanar()
    if base == FLOATING:
        return pin.JointModelFreeFlyer()
    return None


def base_kind(model: pin.Model) -> str:
    """The base of a model: planar, floating, or fixed.

    :data:`PLANAR` or :data:`FLOATING` when its first joint is the base joint
    (:data:`BASE_JOINT`) of that kind, else :data:`FIXED`.
    """
    if model.njoints < 2 or model.names[1] != BASE_JOINT:
        return FIXED
    name = model.joints[1].shortname()
    if name == "JointModelPlanar":
        return PLANAR
    if name == "JointModelFreeFlyer":
        return FLOATING
    return FIXED


def set_base_speed(model: pin.Model, speed: tuple[float, float]) -> None:
    """Write the base's speed limits into ``model.velocityLimit`` (what the speed laws read).

    Planar: ``(v_x, v_y)`` get ``speed[0]`` [m/s], ``omega_z`` gets ``speed[1]`` [rad/s];
    floating: the three linear entries ``speed[0]``, the three angular ones ``speed[1]``.
    Nothing for a fixed base.
    """
    kind = base_kind(model)
    if kind == FIXED:
        return
    n_linear = 2 if kind == PLANAR else 3
    n_angular = 1 if kind == PLANAR else 3
    start = model.joints[1].idx_v
    linear = slice(start, start + n_linear)
    angular = slice(start + n_linear, start + n_linear + n_angular)
    # velocityLimit is upperVelocityLimit; Pinocchio's URDF reader writes the same speed
    # into lowerVelocityLimit, and buildReducedModel refuses a lower above the upper
    for name in ("upperVelocityLimit", "lowerVelocityLimit"):
        limits = np.array(getattr(model, name), dtype=float)
        limits[linear], limits[angular] = speed
        setattr(model, name, limits)


def base_speed(model: pin.Model) -> tuple[float, float] | None:
    """The base's speed limits ``(linear [m/s], angular [rad/s])``, None for a fixed base."""
    kind = base_kind(model)
    if kind == FIXED:
        return None
    start = model.joints[1].idx_v
    n_linear = 2 if kind == PLANAR else 3
    return float(model.velocityLimit[start]), float(model.velocityLimit[start + n_linear])


def normalised_rotation(values: np.ndarray, field: str, what: str) -> np.ndarray:
    """``values`` (a (cos, sin) pair or a quaternion) divided by its norm.

    Raises:
        InputError: Its norm is off 1 by more than :data:`QUATERNION_TOLERANCE`.
    """
    norm = float(np.linalg.norm(values))
    if not abs(norm - 1.0) <= QUATERNION_TOLERANCE:
        raise InputError(field, f"the base's {what} with norm 1", got=values.tolist())
    return values / norm


def written_base(kind: str, values: np.ndarray, scale: float) -> np.ndarray:
    """A base's configuration from its values in the angle form.

    Args:
        kind: :data:`PLANAR` (``x, y, yaw``) or :data:`FLOATING` (``x, y, z, roll,
            pitch, yaw``, the URDF's fixed-axis convention ``R = Rz(yaw) Ry(pitch)
            Rx(roll)``).
        values: The values, positions [m] and angles [``scale`` to rad].
        scale: Factor from the written angle unit to radians.

    Returns:
        Pinocchio's configuration of the base (4 or 7 values).
    """
    if kind == PLANAR:
        yaw = float(values[2]) * scale
        return np.array([values[0], values[1], math.cos(yaw), math.sin(yaw)], dtype=float)
    rpy = np.asarray(values[3:6], dtype=float) * scale
    quaternion = pin.Quaternion(pin.rpy.rpyToMatrix(rpy)).coeffs()  # (x, y, z, w)
    return np.concatenate([np.asarray(values[:3], dtype=float), quaternion])


def planar_from_free_flyer(values: np.ndarray) -> np.ndarray:
    """A planar base's ``(x, y, cos, sin)`` from a free-flyer's 7 values.

    For an SRDF group state written for a floating base (example-robot-data's
    ``root_joint`` entries) read by a planar one: x and y kept, the yaw of the
    quaternion ``(q_x, q_y, q_z, q_w)`` kept, z, roll and pitch dropped.
    """
    x, y, _, qx, qy, qz, qw = (float(v) for v in values)
    yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return np.array([x, y, math.cos(yaw), math.sin(yaw)])
