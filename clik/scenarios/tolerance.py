"""The ``[solver]`` keys of tracking: ``tolerance`` and ``settling_time``.

``tolerance`` is an inline table ``{ position = 0.01, orientation = 0.05 }`` (position
[m], orientation [rad]; either key may be left out for its default) or a single number,
the position tolerance. ``settling_time`` [s] is how long the task error may stay above
it. Both are :meth:`clik.Tracker.run`'s arguments (:mod:`clik.loop.tracking_status`:
a run past them is ``off_track``).
"""

from __future__ import annotations

from typing import Any

from clik.loop.tracking_status import DEFAULT_SETTLING_TIME, DEFAULT_TOLERANCE
from clik.schema import Table


def read_tolerance(slv: Table) -> dict[str, Any]:
    """``{"tolerance": (position, orientation), "settling_time": ...}`` of ``[solver]``.

    Raises:
        ScenarioError: A value that is not a finite number > 0, naming its key
            (``solver.tolerance.position``, ``solver.tolerance.orientation``,
            ``solver.settling_time``); a tolerance neither a number nor a table; an
            unknown key in the table.
    """
    position, orientation = DEFAULT_TOLERANCE
    raw = slv.raw("tolerance", None)
    if isinstance(raw, dict):
        tol = slv.table("tolerance")
        position = tol.number("position", position, minimum=0.0, strict=True, unit="[m]")
        orientation = tol.number("orientation", orientation, minimum=0.0, strict=True, unit="[rad]")
        tol.done()
    elif raw is not None:
        position = slv.number("tolerance", minimum=0.0, strict=True, unit="[m] (position)")
    settling = slv.number(
        "settling_time", DEFAULT_SETTLING_TIME, minimum=0.0, strict=True, unit="[s]"
    )
    return {"tolerance": (float(position), float(orientation)), "settling_time": float(settling)}
