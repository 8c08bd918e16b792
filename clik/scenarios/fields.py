"""Fields that several scenario tables share: units, strings, gains and trajectories.

``[trajectory]`` and each ``[tasks.trajectory]`` are read by :func:`trajectory_table`; a
gain [1/s] (``[solver]``, a constraint table's, a task's) by :func:`gain_value`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from clik.bounds import SCALE_RANGE
from clik.schema import MAX_ANGLE, MAX_GAIN_DT, MAX_LENGTH, MAX_SPEED, MIN_DURATION, Table

TRAJECTORY_KINDS = ("line", "circle", "waypoints", "hold")
UNITS = ("rad", "deg")


def angle_scale(table: Table) -> float:
    """Factor from the table's ``unit`` (``"rad"``, default, or ``"deg"``) to radians."""
    return math.pi / 180.0 if table.string("unit", "rad", UNITS) == "deg" else 1.0


def gain_value(table: Table, name: str, dt: float, default: Any = None) -> Any:
    """A gain [1/s] (> 0), a number or (``per_row``) a list, with ``gain * dt <= MAX_GAIN_DT``."""
    value = table.raw(name, default)
    if isinstance(value, list):
        gains = table.vector(name)
        if any(g <= 0 for g in gains):
            raise table.error(name, "positive numbers [1/s]", gains)
    else:
        gains = table.number(name, default, minimum=0.0, strict=True, unit="[1/s]")
        if gains is None:
            return None
    if max(gains if isinstance(gains, list) else [gains]) * dt > MAX_GAIN_DT:
        raise table.error(
            name,
            f"a gain [1/s] with gain * solver.dt <= {MAX_GAIN_DT:g} (solver.dt = {dt:g} s; "
            "law (10) is stable only for gain * dt < 2)",
            value,
        )
    return gains


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
