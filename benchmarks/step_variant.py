"""One line of the step benchmark, and the clik line: whole runs of :meth:`clik.Tracker.run`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

import clik
from clik.trajectory import Trajectory

RunOutcome = tuple[int, float, dict[str, Any]]
"""What one whole run of a line returns: (steps, wall time [s], run info)."""


@dataclass
class Variant:
    """One line of the step benchmark.

    Attributes:
        name: Key of the line in ``bench.json``.
        description: One sentence for ``bench.md``.
        run: Runs the whole reference once; returns (steps, wall [s], run info).
    """

    name: str
    description: str
    run: Callable[[], RunOutcome]


def clik_variant(
    name: str, description: str, tracker: clik.Tracker, trajectory: Trajectory, q0: np.ndarray
) -> Variant:
    """A line that times clik's own loop: ``tracker.run(trajectory, q0)``, wall time of the run.

    The wall time is the run's ``wall_time_s``: the samples only (in the tracker's
    engine), not the reference sampling, checks and allocations before them nor the
    result built after them.

    Args:
        name: Key of the line.
        description: One sentence for ``bench.md``.
        tracker: The preallocated tracker (law, gains, constraints).
        trajectory: The reference.
        q0: Start configuration.
    """

    def run() -> RunOutcome:
        result = tracker.run(trajectory, q0)
        info: dict[str, Any] = {
            "status": result.status,
            "violations": len(result.violations),
            "max_task_error": float(result.max_task_error),
            "law": tracker.law,
            "engine": tracker.engine,
        }
        if result.active_count is not None:
            info["active_rows_mean"] = float(np.mean(result.active_count))
            info["events"] = len(result.events)
            summary = result.summary()
            info["min_obstacle_distance_m"] = summary.get("min_obstacle_distance")
        return result.steps, result.wall_time_s, info

    return Variant(name, description, run)
