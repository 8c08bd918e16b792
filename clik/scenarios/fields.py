"""Fields that several scenario tables share: gains.

A gain [1/s] (``[solver]``, a constraint table's, a task's) is read by
:func:`gain_value`; trajectories' tables by :mod:`clik.trajectory.tables`.
"""

from __future__ import annotations

from typing import Any

from clik.schema import MAX_GAIN_DT, Table


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
