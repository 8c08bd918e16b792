"""Locked joints: a robot's models reduced to the joints left free.

``Robot.load(..., lock={name: value})`` fixes joints at given values [rad or m]
(the Panda's fingers, say) and reduces the kinematic and geometry models to the
other joints with Pinocchio's ``buildReducedModel``; mimic followers are locked
the same way (see :mod:`clik.model.mimic`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pinocchio as pin

from clik.errors import InputError, JointNotFound
from clik.model.joints import CONTINUOUS, joint_kind, q_slice


def lock_values(model: pin.Model, lock: Mapping[str, float]) -> dict[str, float]:
    """The values of ``lock`` as floats, each checked against its joint.

    Raises:
        JointNotFound: A joint in ``lock`` does not exist.
        InputError: A joint is not one-DOF, or its value is not finite or
            outside the joint's limits (continuous joints have none).
    """
    joint_names = list(model.names[1:])
    values: dict[str, float] = {}
    for joint_name, given in lock.items():
        if joint_name not in joint_names:
            raise JointNotFound(joint_name, joint_names)
        joint = model.joints[model.getJointId(joint_name)]
        low = model.lowerPositionLimit[joint.idx_q]
        high = model.upperPositionLimit[joint.idx_q]
        continuous = joint_kind(joint) == CONTINUOUS
        try:
            value = float(given)
        except (TypeError, ValueError):
            value = math.nan
        if joint.nv != 1 or not (math.isfinite(value) and (continuous or low <= value <= high)):
            expected = f"a value within the joint's limits [{low:g}, {high:g}]"
            raise InputError(f"lock[{joint_name!r}]", expected, got=value)
        values[joint_name] = value
    return values


def set_locked(
    model: pin.Model, q_full: np.ndarray, values: Mapping[str, float], lock: Mapping[str, float]
) -> list[int]:
    """Write the locked joints' values into ``q_full``; their joint ids, sorted.

    Args:
        model: The model before locking.
        q_full: A configuration of ``model``, written in place.
        values: Joint name -> value [rad or m] (a continuous joint's angle).
        lock: The user's ``lock``, named in the error.

    Raises:
        InputError: Every joint would be locked.
    """
    joint_ids: list[int] = []
    for joint_name, value in values.items():
        joint_id = model.getJointId(joint_name)
        continuous = joint_kind(model.joints[joint_id]) == CONTINUOUS
        q_full[q_slice(model, joint_id)] = (
            (math.cos(value), math.sin(value)) if continuous else value
        )
        joint_ids.append(joint_id)
    if len(joint_ids) == model.njoints - 1:
        raise InputError("lock", "at least one joint left free", got=list(lock))
    return sorted(joint_ids)


def reduced(
    model: pin.Model, collision_model: pin.GeometryModel, joint_ids: list[int], q_full: np.ndarray
) -> tuple[pin.Model, pin.GeometryModel, np.ndarray]:
    """The models without the joints ``joint_ids``, and the reference of the joints left.

    Args:
        model: The model before locking.
        collision_model: Its collision geometry.
        joint_ids: The locked joints, sorted.
        q_full: The full configuration, the locked joints at their values.

    Returns:
        The reduced model, its collision model and its reference configuration.
    """
    reduced_model, (reduced_collision,) = pin.buildReducedModel(
        model, [collision_model], joint_ids, q_full
    )
    q_reference = np.concatenate(
        [q_full[q_slice(model, model.getJointId(n))] for n in reduced_model.names[1:]]
    )
    return reduced_model, reduced_collision, q_reference
