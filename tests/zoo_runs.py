"""The robot-zoo run: every robot clik knows, a 5 cm line toward a 3 cm sphere.

For each robot: a position task on the last frame of the deepest chain, a 5 cm line over
1 s from the reference configuration, law (10) with the default gain, a sphere of radius
3 cm whose centre is 10 cm ahead along the line (threshold ``d_o`` = 3 cm) and joint-range
rows at 2 deg. The line ends 1 cm inside the threshold: the task and the obstacle
constraint conflict, the paper's deadlock case. The run is defined once, in
:mod:`benchmarks.zoo` (the bench times it too). ``python -m tests.zoo_runs``, from the
checkout's root, prints the table of the closing note.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

import clik
from benchmarks.zoo import DIRECTION, ZooSetup, zoo_setup


@dataclass
class ZooRun:
    """One robot's run, or why it did not run."""

    name: str
    status: str  # a run status, or the ClikError class name when refused
    reason: str
    min_distance: float = float("nan")
    max_joint_step: float = float("nan")
    result: clik.TrackingResult | None = None
    setup: ZooSetup | None = None


def zoo_run(name: str, direction: np.ndarray = DIRECTION) -> ZooRun:
    """The obstacle run of one robot (a refused run keeps its ClikError's name)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            setup = zoo_setup(name, direction)
            result = setup.tracker().run(setup.line, setup.q0)
    except clik.ClikError as exc:
        return ZooRun(name, type(exc).__name__, str(exc).splitlines()[0][:200])
    dq = np.abs(np.diff(result.q, axis=0)).max() if len(result.q) > 1 else 0.0
    md = result.summary()["min_obstacle_distance"]
    return ZooRun(name, result.status, result.reason, float(md), float(dq), result, setup)


if __name__ == "__main__":
    print(
        "| robot | status | max velocity ratio | max task error [m] | min distance [m] "
        "| max joint step [rad] |"
    )
    print("|---|---|---|---|---|---|")
    for name in sorted(clik.Robot.available()):
        run = zoo_run(name)
        if run.result is None:
            print(f"| {name} | not run: {run.status} | - | - | - | - |")
        else:
            ratio = run.result.summary()["max_velocity_ratio"]
            shown = "no limits" if ratio is None else f"{ratio:.4f}"
            print(
                f"| {name} | {run.status} | {shown} | {run.result.max_task_error:.4g} "
                f"| {run.min_distance:.4f} | {run.max_joint_step:.4f} |"
            )
