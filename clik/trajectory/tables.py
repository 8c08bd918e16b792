"""Trajectories as scenario tables describe them: a ``[trajectory]`` table, read and built.

A ``[trajectory]`` (or ``[tasks.trajectory]``) table is a position path (``kind``:
``"line"``, ``"circle"``, ``"waypoints"``, ``"hold"``), its timing (``duration`` [s] or
``cruise_speed`` [m/s]) and an optional orientation goal (``goal_rpy``, ``unit``).
:func:`trajectory_table` reads one (checked, as plain values) and
:func:`build_trajectory` builds the trajectory from where its frame is at the start.
The scenarios and the task kinds that read such tables share them.
"""

from __future__ import annotations

import math
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from clik.bounds import SCALE_RANGE
from clik.errors import InputError
from clik.schema import MAX_ANGLE, MAX_JOINT_VALUE, MAX_LENGTH, MAX_SPEED, MIN_DURATION, Table
from clik.trajectory.base import Trajectory
from clik.trajectory.circle import Circle
from clik.trajectory.hold import Hold
from clik.trajectory.joint_path import JointPath
from clik.trajectory.line import Line
from clik.trajectory.pose import PoseTrajectory
from clik.trajectory.slerp import Slerp
from clik.trajectory.waypoints import Waypoints

TRAJECTORY_KINDS = ("line", "circle", "waypoints", "hold")
"""``[trajectory] kind``."""
UNITS = ("rad", "deg")
"""Angle units a table may give (``unit``)."""
JOINT_TRAJECTORY_KINDS = ("hold", "waypoints")
"""``[tasks.trajectory] kind`` of a joint-space trajectory (a posture's)."""


def angle_scale(table: Table) -> float:
    """Factor from the table's ``unit`` (``"rad"``, default, or ``"deg"``) to radians."""
    return math.pi / 180.0 if table.string("unit", "rad", UNITS) == "deg" else 1.0


def strings(table: Table, name: str) -> list[str]:
    """A list of strings (empty when absent)."""
    value = table.raw(name, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise table.error(name, "a list of strings", value)
    return value


def trajectory_table(tr: Table, folder: Path, has_orientation: bool = True) -> dict[str, Any]:
    """A ``[trajectory]`` table: a position path, its timing and an optional ``goal_rpy``."""
    kind = tr.string("kind", choices=TRAJECTORY_KINDS)
    scale = angle_scale(tr)
    out: dict[str, Any] = {"kind": kind}
    out["start"] = tr.vector("start", 3, None, "[m]", MAX_LENGTH)
    if kind in ("line", "hold"):
        out["goal"] = tr.vector("goal", 3, None if kind == "hold" else ..., "[m]", MAX_LENGTH)
        if out["goal"] is ...:
            raise tr.error("goal", "a list of 3 numbers [m]")
    if kind == "circle":
        out["center"] = tr.vector("center", 3, unit="[m]", bound=MAX_LENGTH)
        out["normal"] = tr.vector("normal", 3, [0.0, 0.0, 1.0], bound=SCALE_RANGE[1])
        if np.linalg.norm(out["normal"]) == 0.0:
            raise tr.error("normal", "a non-zero vector", out["normal"])
        angle = tr.number("angle", None, bound=MAX_ANGLE / scale)
        out["angle"] = 2.0 * math.pi if angle is None else angle * scale
        if out["angle"] == 0.0:
            raise tr.error("angle", "a non-zero angle", angle)
    if kind == "waypoints":
        out["points"] = tr.matrix("points", 3, unit="[m]", bound=MAX_LENGTH)
        out["blend_radius"] = tr.number(
            "blend_radius", 0.0, minimum=0.0, unit="[m]", bound=MAX_LENGTH
        )
    if kind == "hold":
        out["duration"] = tr.number("duration", None, minimum=0.0, unit="[s]")
    else:
        out["duration"] = tr.number("duration", None, minimum=0.0, strict=True, unit="[s]")
        if out["duration"] is not None and out["duration"] < MIN_DURATION:
            raise tr.error("duration", f"a number >= {MIN_DURATION:g} [s]", out["duration"])
        out["cruise_speed"] = tr.number(
            "cruise_speed", None, minimum=0.0, strict=True, unit="[m/s]", bound=MAX_SPEED
        )
    if kind == "hold" and out["duration"] is None:
        raise tr.error("duration", "a number >= 0 [s]")
    if kind != "hold" and out["duration"] is None and out.get("cruise_speed") is None:
        raise tr.error("duration", "a duration [s] or a cruise_speed")
    rpy = tr.vector("goal_rpy", 3, None, bound=MAX_ANGLE / scale)
    if rpy is not None and not has_orientation:
        raise tr.error("goal_rpy", "no goal_rpy: the task has no orientation rows", rpy)
    out["goal_rpy"] = None if rpy is None else [v * scale for v in rpy]
    tr.done()
    return out


def build_trajectory(
    spec: dict[str, Any], start: pin.SE3, has_position: bool = True, has_orientation: bool = True
) -> Trajectory:
    """The trajectory of a ``[trajectory]`` table (:func:`trajectory_table`), from ``start``.

    A position path (its ``start`` defaults to ``start``'s translation), with a held or
    slerped orientation (``goal_rpy``) from ``start``'s rotation when ``has_orientation``;
    the orientation alone without ``has_position``.
    """
    p0 = start.translation.copy() if spec["start"] is None else np.asarray(spec["start"])
    kind, duration, speed = spec["kind"], spec["duration"], spec.get("cruise_speed")
    position: Trajectory
    if kind == "line":
        position = Line(p0, spec["goal"], duration=duration, cruise_speed=speed)
    elif kind == "circle":
        position = Circle.through(
            p0, spec["center"], spec["normal"], spec["angle"], duration=duration, cruise_speed=speed
        )
    elif kind == "waypoints":
        points = np.vstack([p0, np.asarray(spec["points"])])
        position = Waypoints(
            points, duration=duration, cruise_speed=speed, blend_radius=spec["blend_radius"]
        )
    else:
        goal = p0 if spec["goal"] is None else np.asarray(spec["goal"])
        position = Hold(position=goal, duration=duration)
    if not has_orientation:
        return position
    R0 = start.rotation.copy()
    rpy = spec["goal_rpy"]
    if rpy is None:
        orientation: Trajectory = Hold(rotation=R0, duration=position.duration)
    else:
        orientation = Slerp(R0, pin.rpy.rpyToMatrix(*rpy), duration=position.duration)
    if not has_position:
        return orientation
    return PoseTrajectory(position, orientation)


def joint_trajectory_table(tr: Table) -> dict[str, Any]:
    """A joint-space ``[tasks.trajectory]`` (a posture's; an empty table: hold the start).

    Values are kept as written, with ``unit`` (revolute joints; prismatic ones in
    metres): the robot converts them.
    """
    if not tr.data:
        return {"kind": "hold", "values": None, "waypoints": None, "duration": 0.0,
                "times": None, "unit": "rad"}  # fmt: skip
    kind = tr.string("kind", choices=JOINT_TRAJECTORY_KINDS)
    unit = tr.string("unit", "rad", UNITS)
    bound = MAX_JOINT_VALUE / angle_scale(tr)
    out: dict[str, Any] = {"kind": kind, "unit": unit, "values": None, "waypoints": None}
    if kind == "hold":
        out["values"] = tr.vector("values", None, None, bound=bound)
        out["duration"] = tr.number("duration", 0.0, minimum=0.0, unit="[s]")
        out["times"] = None
    else:
        out["waypoints"] = _rows(tr, "waypoints", bound)
        _timing(tr, out)
    tr.done()
    return out


def _rows(tr: Table, name: str, bound: float) -> list[list[float]]:
    """A non-empty list of joint vectors, all of one length."""
    value = tr.raw(name)
    if not isinstance(value, list) or not value or not isinstance(value[0], list):
        raise tr.error(name, "a non-empty list of joint vectors [[...], ...]", value)
    size = len(value[0])
    rows = Table({f"{name}[{i}]": row for i, row in enumerate(value)}, tr.file, tr.path)
    return [rows.vector(f"{name}[{i}]", size, bound=bound) for i in range(len(value))]


def _timing(tr: Table, out: dict[str, Any]) -> None:
    """``duration`` or ``times`` of posture waypoints (the start at t = 0)."""
    k = len(out["waypoints"])
    if tr.has("times") == tr.has("duration"):
        raise tr.error("duration", "a duration [s] or times (one per waypoint), not both")
    if tr.has("times"):
        times = tr.vector("times", k, unit="[s]")
        if times[0] < MIN_DURATION or any(b <= a for a, b in pairwise(times)):
            raise tr.error("times", f"{k} increasing times > 0 [s] (the start is at t = 0)", times)
        out["times"], out["duration"] = times, times[-1]
    else:
        out["duration"] = tr.number("duration", minimum=MIN_DURATION, unit="[s]")
        out["times"] = None


def joint_path(
    spec: dict[str, Any], start: np.ndarray, scale: np.ndarray, names: list[str]
) -> JointPath:
    """The joint path of a :func:`joint_trajectory_table`: a hold, or waypoints from ``start``.

    A hold keeps ``values`` (default: ``start``).

    Args:
        spec: The table's values.
        start: The values at the start (n,) [rad or m].
        scale: Per value, the factor from its written unit to [rad] or [m] (n,).
        names: What the values are (the message's, when their count is wrong).

    Raises:
        InputError: Values of the wrong length (field ``values`` or ``waypoints``).
    """
    duration = float(spec["duration"])
    if spec["kind"] == "hold":
        held = start if spec["values"] is None else _values(spec["values"], names, scale, "values")
        return JointPath([held, held], duration=duration) if duration > 0 else JointPath(held)
    rows = [
        _values(row, names, scale, f"waypoints[{k}]") for k, row in enumerate(spec["waypoints"])
    ]
    if spec["times"] is not None:
        return JointPath([start, *rows], times=[0.0, *spec["times"]])
    return JointPath([start, *rows], duration=duration)


def _values(values: list[float], names: list[str], scale: np.ndarray, field: str) -> np.ndarray:
    if len(values) != len(names):
        raise InputError(
            field, f"{len(names)} values, one per joint of the posture task ({', '.join(names)})",
            f"{len(values)} values",
        )  # fmt: skip
    return np.asarray(values, dtype=float) * scale
