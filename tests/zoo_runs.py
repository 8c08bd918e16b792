"""The robot-zoo run: every robot clik knows, a 5 cm line toward a 3 cm sphere.

For each robot: a position task on the last frame of the deepest chain, a 5 cm line over
1 s from the reference configuration, law (10) with the default gain, a sphere of radius
3 cm whose centre is 10 cm ahead along the line (threshold ``d_o`` = 3 cm) and joint-range
rows at 2 deg. The line ends 1 cm inside the threshold: the task and the obstacle
constraint conflict, the paper's deadlock case. ``python tests/zoo_runs.py`` prints the
table of the closing note.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

import clik
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.trajectory import Line

DIRECTION = np.array([1.0, 0.0, 0.0])
"""The line's direction in the world frame."""


@dataclass
class ZooRun:
    """One robot's run, or why it did not run."""

    name: str
    status: str  # a run status, or the ClikError class name when refused
    reason: str
    min_distance: float = float("nan")
    max_joint_step: float = float("nan")
    result: clik.TrackingResult | None = None


def deepest_frame(robot: clik.Robot) -> str:
    """The last frame (in model order) among those on the deepest joint chain."""
    model = robot.model
    depth = [0] * model.njoints
    for j in range(1, model.njoints):
        depth[j] = depth[model.parents[j]] + 1
    best = max(range(len(model.frames)), key=lambda i: (depth[model.frames[i].parentJoint], i))
    return model.frames[best].name


def zoo_run(name: str, direction: np.ndarray = DIRECTION) -> ZooRun:
    """The obstacle run of one robot (a refused run keeps its ClikError's name)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot = clik.Robot.load(name)
            task = clik.Task(robot, deepest_frame(robot), "position")
            q0 = robot.q_reference
            p0 = task.placement(q0).translation.copy()
            u = direction / np.linalg.norm(direction)
            ball = Obstacle("ball", "sphere", p0 + 0.10 * u, radius=0.03)
            limits = JointLimits(robot, np.radians(2.0))
            constraints = ConstraintSet(
                robot, obstacles=[ball], obstacle_threshold=0.03, joint_limits=limits
            )
            line = Line(p0, p0 + 0.05 * u, duration=1.0)
            result = clik.track(task, line, q0=q0, law="pseudoinverse", constraints=constraints)
    except clik.ClikError as exc:
        return ZooRun(name, type(exc).__name__, str(exc).splitlines()[0][:200])
    dq = np.abs(np.diff(result.q, axis=0)).max() if len(result.q) > 1 else 0.0
    md = result.summary()["min_obstacle_distance"]
    return ZooRun(name, result.status, result.reason, float(md), float(dq), result)


if __name__ == "__main__":
    print("| robot | status | min distance [m] | max joint step [rad] |")
    print("|---|---|---|---|")
    for name in sorted(clik.Robot.available()):
        run = zoo_run(name)
        if run.result is None:
            print(f"| {name} | not run: {run.status} | - | - |")
        else:
            print(f"| {name} | {run.status} | {run.min_distance:.4f} | {run.max_joint_step:.4f} |")
