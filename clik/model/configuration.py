"""Configurations: joint values converted from what a user writes, and checked.

Configurations are Pinocchio's: ``nq`` values, one per revolute or prismatic
joint [rad or m], two (cos, sin) per continuous joint (then ``nv < nq``). The
functions here take the model and the robot's name (for messages);
:class:`~clik.model.robot.Robot` offers them as methods.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from clik.errors import InfeasibleError, InputError
from clik.model.joints import CONTINUOUS, PRISMATIC, REVOLUTE, joint_kind, unit_scale


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
    angle_form = model.nq != model.nv and all(
        joint_kind(j) in (REVOLUTE, PRISMATIC, CONTINUOUS) for j in joints
    )
    angle_unit = "deg" if unit == "deg" else "rad"
    expected = (
        f"an array of {model.nq} finite joint values [{angle_unit} for revolute joints, "
        f"m for prismatic ones] for {robot_name}"
    )
    if angle_form:
        expected += f" (or {model.nv}, a continuous joint as its angle)"
    array = float_array(values, field, expected)
    if array.shape == (model.nq,):
        q = array.copy()
        for joint in joints:
            if joint_kind(joint) == REVOLUTE:
                q[joint.idx_q] *= scale
        return q
    if angle_form and array.shape == (model.nv,):
        q = np.empty(model.nq)
        for joint in joints:
            value = float(array[joint.idx_v])
            kind = joint_kind(joint)
            if kind == CONTINUOUS:
                angle = value * scale
                q[joint.idx_q : joint.idx_q + 2] = (math.cos(angle), math.sin(angle))
            else:
                q[joint.idx_q] = value * scale if kind == REVOLUTE else value
        return q
    raise InputError(field, expected, got=shown(array))


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
            continue  # continuous (cos, sin), spherical, free: no position limits
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
