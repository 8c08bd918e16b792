"""ROS 2 messages read into clik's forms, each checked: a bad one is refused, by name.

Reads duck-typed messages (``geometry_msgs/PoseStamped``, ``PointStamped``,
``TwistStamped``, ``sensor_msgs/JointState``), so that this module imports nothing of
ROS. Every function raises :class:`~clik.errors.InputError` naming the topic and the field
for a value the node must not use: a NaN or an infinity, a quaternion whose norm is not 1
(within :data:`QUATERNION_TOLERANCE`), a ``frame_id`` that is neither the world frame nor
one of the robot's frames, a joint state missing a joint or naming an unknown one.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError

QUATERNION_TOLERANCE = 1e-3
"""How far from 1 a quaternion's norm may be (it is then normalised)."""

Placement = Callable[[str], "pin.SE3 | None"]
"""A frame's placement in the world by name, None for a frame the robot does not have."""


def _finite(values: np.ndarray, topic: str, field: str) -> np.ndarray:
    if not np.all(np.isfinite(values)):
        raise InputError(f"{topic}: {field}", "finite numbers", values.tolist())
    return values


def _vector(v: Any, topic: str, field: str) -> np.ndarray:
    return _finite(np.array([v.x, v.y, v.z], dtype=float), topic, field)


def frame_placement(msg: Any, topic: str, world: str, placement: Placement) -> pin.SE3:
    """The world placement of the message's ``header.frame_id`` (identity for the world)."""
    frame = str(msg.header.frame_id)
    if frame in ("", world):
        return pin.SE3.Identity()
    found = placement(frame)
    if found is None:
        raise InputError(
            f"{topic}: header.frame_id", f"'{world}' (or empty) or a frame of the robot", frame
        )
    return found


def pose(msg: Any, topic: str, world: str, placement: Placement) -> np.ndarray:
    """A ``PoseStamped`` as a 4x4 pose in the world [m]."""
    p = msg.pose
    position = _vector(p.position, topic, "pose.position")
    o = p.orientation
    quat = _finite(np.array([o.x, o.y, o.z, o.w], dtype=float), topic, "pose.orientation")
    norm = float(np.linalg.norm(quat))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise InputError(
            f"{topic}: pose.orientation",
            f"a unit quaternion (norm 1 within {QUATERNION_TOLERANCE:g})",
            f"norm {norm:.6g}",
        )
    x, y, z, w = quat / norm
    local = pin.SE3(pin.Quaternion(w, x, y, z).toRotationMatrix(), position)
    return np.asarray((frame_placement(msg, topic, world, placement) * local).homogeneous)


def point(msg: Any, topic: str, world: str, placement: Placement) -> np.ndarray:
    """A ``PointStamped`` as a position in the world (3,) [m]."""
    local = _vector(msg.point, topic, "point")
    return np.asarray(frame_placement(msg, topic, world, placement).act(local))


def twist(msg: Any, topic: str, world: str, placement: Placement) -> np.ndarray:
    """A ``TwistStamped`` as ``(linear, angular)`` (6,) in the world [m/s, rad/s]."""
    linear = _vector(msg.twist.linear, topic, "twist.linear")
    angular = _vector(msg.twist.angular, topic, "twist.angular")
    rotation = frame_placement(msg, topic, world, placement).rotation
    return np.concatenate([rotation @ linear, rotation @ angular])


def joint_values(
    msg: Any, topic: str, joints: Mapping[str, int], ignored: Collection[str]
) -> np.ndarray:
    """A ``JointState``'s positions in clik's joint order (n,) [rad or m].

    Args:
        msg: The message.
        topic: Its topic (named in errors).
        joints: clik's joints by name: their index.
        ignored: Names of the robot's other joints (locked, fixed): accepted, not read.
    """
    names = [str(n) for n in msg.name]
    position = np.asarray(msg.position, dtype=float)
    if len(position) != len(names):
        raise InputError(f"{topic}: position", f"one value per name ({len(names)})", len(position))
    unknown = [n for n in names if n not in joints and n not in ignored]
    if unknown:
        raise InputError(f"{topic}: name", "joints of the robot", ", ".join(unknown))
    missing = [n for n in joints if n not in names]
    if missing:
        raise InputError(
            f"{topic}: name", "every joint clik moves", f"missing {', '.join(missing)}"
        )
    out = np.empty(len(joints))
    for name, value in zip(names, position, strict=True):
        if name in joints:
            out[joints[name]] = value
    return _finite(out, topic, "position")
