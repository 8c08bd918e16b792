"""Gripper fingers in a robot's reference configuration: in the middle of their range.

A finger at its closed limit (the Panda's SRDF posture holds it 0.001 m from its lower
limit) sits inside its joint-range threshold band, so its row is active from the first
sample and drives it out at up to its speed limit. :func:`open_fingers`, applied by
:class:`~clik.model.robot.Robot` to every reference, starts each finger in the middle of
its range instead: outside every band, as a threshold is at most a quarter of its range
(:data:`~clik.constraints.joint_limits.RANGE_FRACTION`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from clik.model.joints import PRISMATIC, joint_kind

FINGER_WORDS = ("finger", "gripper", "jaw")
"""A prismatic joint whose name holds one of these (any case) and that ends its chain is a
gripper's finger (:func:`open_fingers`)."""


def open_fingers(model: pin.Model, q_reference: np.ndarray) -> np.ndarray:
    """The reference with each gripper finger in the middle of its range.

    A finger is a prismatic joint that ends its chain (no joint after it), has a joint
    before it and a name holding one of :data:`FINGER_WORDS`. A finger within a quarter
    of its range of a limit (the Panda's SRDF posture: 0.001 m of [0, 0.04] m) would sit
    inside its joint-range threshold band (at most a quarter of the range) and its row
    would be active from t = 0; in the middle of its range it is outside every band.

    Args:
        model: The robot's model.
        q_reference: A configuration (nq,) [rad or m].

    Returns:
        A copy of ``q_reference`` with the fingers moved (the others unchanged).
    """
    q = np.array(q_reference, dtype=float)
    parents = set(model.parents[1:])
    for jid in range(1, model.njoints):
        joint, name = model.joints[jid], model.names[jid]
        if (
            joint_kind(joint) != PRISMATIC
            or jid in parents
            or model.parents[jid] == 0
            or not any(word in name.lower() for word in FINGER_WORDS)
        ):
            continue
        i = joint.idx_q
        lower, upper = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        span = upper - lower
        if np.isfinite(span) and span > 0 and min(q[i] - lower, upper - q[i]) < 0.25 * span:
            q[i] = 0.5 * (lower + upper)
    return q
