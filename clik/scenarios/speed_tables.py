"""The scenario's speed tables: ``[constraints.joint_speed]`` and ``[constraints.velocity_limits]``.

``joint_speed`` sets the limits the law keeps at every sample
(:class:`~clik.loop.joint_speed.JointSpeed`, docs/method.md "Joint speed limits
in the law"); ``velocity_limits`` the offline re-timing of the reference
(:class:`~clik.speed.speed_limits.SpeedLimits`).
"""

from __future__ import annotations

from typing import Any

from clik.loop.joint_speed import MAX_SPEED_BOUND
from clik.schema import Table
from clik.speed.speed_limits import MAX_PASSES, MAX_SCALE

SPEED_UNIT = "[rad/s or m/s]"
ACCEL_UNIT = "[rad/s^2 or m/s^2]"


def joint_speed_table(js: Table) -> dict[str, Any]:
    """``[constraints.joint_speed]``: the joint speed limits the law keeps (on by default).

    Keys: ``enabled`` (default true), ``scale`` (fraction of each joint's velocity limit,
    ``0 < scale <= 10``, default 1), ``velocity`` (a table joint -> limit [rad/s or m/s]
    replacing the URDF's), ``default_velocity`` (the limit of a joint whose URDF gives
    none, default 2), ``acceleration`` (one limit for every joint or a table joint ->
    limit [rad/s^2 or m/s^2]; default none). Checked whether enabled or not; joint
    names are checked against the robot when the scenario is built.
    """
    scale = js.number("scale", 1.0, minimum=0.0, strict=True)
    if scale > MAX_SCALE:
        raise js.error("scale", f"a number > 0 and <= {MAX_SCALE:g} (of the URDF limit)", scale)
    default = js.number(
        "default_velocity", 2.0, minimum=0.0, strict=True, unit=SPEED_UNIT, bound=MAX_SPEED_BOUND
    )
    out = {
        "enabled": js.boolean("enabled", True),
        "scale": float(scale),
        "velocity": _limits(js, "velocity", SPEED_UNIT) if "velocity" in js.data else None,
        "default_velocity": float(default),
        "acceleration": _acceleration(js),
    }
    js.done()
    return out


def _limits(table: Table, name: str, unit: str) -> dict[str, float]:
    """A table joint name -> bound (> 0, at most ``MAX_SPEED_BOUND``)."""
    return table.mapping(
        name,
        lambda t, k: float(t.number(k, minimum=0.0, strict=True, unit=unit, bound=MAX_SPEED_BOUND)),
    )


def _acceleration(table: Table) -> float | dict[str, float] | None:
    """``acceleration``: none, one number for every joint, or a table joint -> limit."""
    value = table.raw("acceleration", None)
    if isinstance(value, dict):
        return _limits(table, "acceleration", ACCEL_UNIT)
    if value is None:
        return None
    return float(
        table.number(
            "acceleration", minimum=0.0, strict=True, unit=ACCEL_UNIT, bound=MAX_SPEED_BOUND
        )
    )


def velocity_limits_table(vl: Table) -> dict[str, Any]:
    """``[constraints.velocity_limits]``: respect the URDF joint speed limits (time scaling).

    Keys: ``enabled`` (default false), ``scale`` (fraction of the URDF velocity limit,
    ``0 < scale <= 10``, default 1), ``acceleration`` (one limit for every joint or a
    table joint -> limit [rad/s^2 or m/s^2]; default none), ``margin`` (in [0, 1],
    default 0.05), ``max_passes`` (1..20, default 6), ``window`` ([s], default 0.05).
    Checked whether enabled or not.
    """
    accel_unit = ACCEL_UNIT
    scale = vl.number("scale", 1.0, minimum=0.0, strict=True)
    if scale > MAX_SCALE:
        raise vl.error("scale", f"a number > 0 and <= {MAX_SCALE:g} (of the URDF limit)", scale)
    acceleration = vl.raw("acceleration", None)
    if isinstance(acceleration, dict):
        acceleration = vl.mapping(
            "acceleration",
            lambda t, k: float(t.number(k, minimum=0.0, strict=True, unit=accel_unit)),
        )
    elif acceleration is not None:
        acceleration = float(vl.number("acceleration", minimum=0.0, strict=True, unit=accel_unit))
    margin = vl.number("margin", 0.05, minimum=0.0)
    if margin > 1.0:
        raise vl.error("margin", "a number in [0, 1]", margin)
    passes = vl.number("max_passes", 6, minimum=1, integer=True)
    if passes > MAX_PASSES:
        raise vl.error("max_passes", f"an integer in 1..{MAX_PASSES}", passes)
    out = {
        "enabled": vl.boolean("enabled", False),
        "scale": float(scale),
        "acceleration": acceleration,
        "margin": float(margin),
        "max_passes": int(passes),
        "window": float(vl.number("window", 0.05, minimum=0.0, strict=True, unit="[s]")),
    }
    vl.done()
    return out
