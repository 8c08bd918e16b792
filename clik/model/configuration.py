"""Configurations: joint values converted from what a user writes, and checked.

Configurations are Pinocchio's: ``nq`` values, one per revolute or prismatic
joint [rad or m], two (cos, sin) per continuous joint (then ``nv < nq``), four
``(x, y, cos, sin)`` for a planar base and seven ``(x, y, z, q_x, q_y, q_z, q_w)``
for a floating one (:mod:`clik.model.base`). The functions here take the model and
the robot's name (for messages); :class:`~clik.model.robot.Robot` offers them as
methods.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from clik.errors import InfeasibleError, InputError
from clik.model.base import normalised_rotation, written_base
from clik.model.joints import (
    CONTINUOUS,
    FREE_FLYER,
    PLANAR,
    PRISMATIC,
    REVOLUTE,
    joint_kind,
    unit_scale,
)

BASE_KINDS = (PLANAR, FREE_FLYER)
"""Kinds of a mobile or floating base's joint."""


def float_array(values: object, field: str, expected: str) -> np.ndarray:
    """``values`` as a 1-D (or any shape) float array of finite numbers, else InputError."""
    try:
        array = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, expected, got=values) from None
    if not np.all(np.isfinite(array)):
        raise InputError(field, expected, got=shown(array))
    return array


def shown(array: np.ndarray) -> object:
    """An array as shown in an error message: its values, or its shape when large."""
    return array.tolist() if array.size <= 20 else f"an array of shape {array.shape}"


def configuration(
    model: pin.Model, robot_name: str, values: object, unit: str, field: str
) -> np.ndarray:
    """A configuration from joint values as a user writes them.

    See :meth:`Robot.configuration`.

    Raises:
        InputError: A bad unit, or not ``nq`` (or ``nv``) finite numbers.
    """
    scale = unit_scale(unit, f"{field} unit")
    joints = model.joints[1:]
    kinds = [joint_kind(j) for j in joints]
    angle_form = model.nq != model.nv and all(
        kind in (REVOLUTE, PRISMATIC, CONTINUOUS, *BASE_KINDS) for kind in kinds
    )
    angle_unit = "deg" if unit == "deg" else "rad"
    expected = (
        f"an array of {model.nq} finite joint values [{angle_unit} for revolute joints, "
        f"m for prismatic ones] for {robot_name}"
    )
    if angle_form:
        expected += f" (or {model.nv}, a continuous joint as its angle"
        if PLANAR in kinds:
            expected += f", the planar base as x, y [m], yaw [{angle_unit}]"
        if FREE_FLYER in kinds:
            expected += f", the floating base as x, y, z [m], roll, pitch, yaw [{angle_unit}]"
        expected += ")"
    array = float_array(values, field, expected)
    if array.shape == (model.nq,):
        q = array.copy()
        for joint, kind in zip(joints, kinds, strict=True):
            if kind == REVOLUTE:
                q[joint.idx_q] *= scale
        return unit_rotations(model, q, field)
    if angle_form and array.shape == (model.nv,):
        q = np.empty(model.nq)
        for joint, kind in zip(joints, kinds, strict=True):
            value = float(array[joint.idx_v])
            if kind == CONTINUOUS:
                angle = value * scale
                q[joint.idx_q : joint.idx_q + 2] = (math.cos(angle), math.sin(angle))
            elif kind in BASE_KINDS:
                written = array[joint.idx_v : joint.idx_v + joint.nv]
                base = "planar" if kind == PLANAR else "floating"
                q[joint.idx_q : joint.idx_q + joint.nq] = written_base(base, written, scale)
            else:
                q[joint.idx_q] = value * scale if kind == REVOLUTE else value
        return q
    raise InputError(field, expected, got=shown(array))


def unit_rotations(model: pin.Model, q: np.ndarray, field: str) -> np.ndarray:
    """``q`` with its rotations normalised, in place.

    A continuous joint's or a planar base's (cos, sin), a floating base's quaternion.
    Pinocchio's integration and kinematics assume them unit; a norm within
    :data:`~clik.model.base.QUATERNION_TOLERANCE` of 1 (values written with a few
    digits) is normalised in place.

    Raises:
        InputError: A rotation whose norm is further from 1 (names ``field``).
    """
    for joint in model.joints[1:]:
        kind = joint_kind(joint)
        if kind in (PLANAR, CONTINUOUS):
            i = joint.idx_q + (2 if kind == PLANAR else 0)
            q[i : i + 2] = normalised_rotation(q[i : i + 2], field, "(cos, sin) pair")
        elif kind == FREE_FLYER:
            i = joint.idx_q + 3
            q[i : i + 4] = normalised_rotation(q[i : i + 4], field, "quaternion (x, y, z, w)")
    return q


def check_within_limits(
    model: pin.Model, robot_name: str, q: np.ndarray, field: str, tolerance: float
) -> None:
    """Check that a configuration lies inside the model's joint limits.

    See :meth:`Robot.check_within_limits`.

    Raises:
        InfeasibleError: A joint is beyond one of its limits by more than
            ``tolerance``; the message names every such joint, its value and
            its limits.
    """
    outside = []
    for name, joint in zip(model.names[1:], model.joints[1:], strict=True):
        kind = joint_kind(joint)
        if kind not in (REVOLUTE, PRISMATIC):
            continue  # continuous (cos, sin), spherical, a base: no position limits
        i = joint.idx_q
        low = model.lowerPositionLimit[i]
        high = model.upperPositionLimit[i]
        value = float(q[i])
        if value < low - tolerance or value > high + tolerance:
            text = f"{name!r} = {value:.6g} not in [{low:.6g}, {high:.6g}]"
            if kind == PRISMATIC:
                text += " m"
            else:
                deg = [math.degrees(v) for v in (value, low, high)]
                text += f" rad ({deg[0]:.4g} deg not in [{deg[1]:.4g}, {deg[2]:.4g}] deg)"
            outside.append(text)
    if outside:
        raise InfeasibleError(
            field,
            f"the configuration is outside the joint limits of {robot_name}: {'; '.join(outside)}",
        )


def random_configuration(model: pin.Model, rng: np.random.Generator, margin: float) -> np.ndarray:
    """A configuration drawn uniformly within the joint limits.

    See :meth:`Robot.random_configuration`.

    Raises:
        InputError: ``margin`` is negative or wider than half a joint's range.
    """
    q = pin.neutral(model)
    for joint in model.joints[1:]:
        i = joint.idx_q
        low, high = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        if joint.nq == 2 and joint.nv == 1:
            angle = rng.uniform(-math.pi, math.pi)
            q[i : i + 2] = (math.cos(angle), math.sin(angle))
        elif joint.nq == 1 and math.isfinite(low) and math.isfinite(high):
            if not 0 <= 2 * margin <= high - low:
                expected = "a margin >= 0 [rad or m] smaller than half of every joint range"
                raise InputError("margin", expected, got=margin)
            q[i] = rng.uniform(low + margin, high - margin)
    return q
