"""The robot-zoo obstacle run: every robot clik knows, a 5 cm line toward a 3 cm sphere.

For each robot: a position task on the last frame of the deepest chain, a 5 cm line over
1 s from the reference configuration, law (10) with the default gain, a sphere of radius
3 cm whose centre is 10 cm ahead along the line (threshold ``d_o`` = 3 cm) and joint-range
rows at 2 deg. The line ends 1 cm inside the threshold: the task and the obstacle
constraint conflict, the paper's deadlock case.

This module is the run's one definition: the zoo test (``tests/zoo_runs.py``) runs it
and checks every outcome; the bench (:mod:`benchmarks.step_zoo`) times it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import clik
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.trajectory import Line

DIRECTION = np.array([1.0, 0.0, 0.0])
"""The line's direction in the world frame."""
LINE_LENGTH = 0.05
"""Length of the line [m]."""
LINE_DURATION = 1.0
"""Duration of the line [s]."""
SPHERE_AHEAD = 0.10
"""Distance of the sphere's centre from the line's start, along the line [m]."""
SPHERE_RADIUS = 0.03
"""Radius of the sphere [m]."""
THRESHOLD = 0.03
"""Obstacle threshold ``d_o`` [m]."""
JOINT_MARGIN_DEG = 2.0
"""Margin of the joint-range rows [deg]."""


def deepest_frame(robot: clik.Robot) -> str:
    """The last frame (in model order) among those on the deepest joint chain.

    Args:
        robot: The robot.
    """
    model = robot.model
    depth = [0] * model.njoints
    for j in range(1, model.njoints):
        depth[j] = depth[model.parents[j]] + 1
    best = max(range(len(model.frames)), key=lambda i: (depth[model.frames[i].parentJoint], i))
    return model.frames[best].name


@dataclass(frozen=True)
class ZooSetup:
    """One robot's obstacle run, built and not yet run.

    Attributes:
        robot: The robot.
        task: Position task of :func:`deepest_frame`.
        q0: Start configuration (the robot's reference configuration).
        constraints: The sphere and the joint-range rows.
        line: The reference.
    """

    robot: clik.Robot
    task: clik.Task
    q0: np.ndarray
    constraints: ConstraintSet
    line: Line

    def tracker(self, engine: str = "compiled") -> clik.Tracker:
        """The run's tracker: law (10), default gain and sample time.

        Args:
            engine: ``"compiled"`` or ``"python"``.
        """
        return clik.Tracker(
            self.task, law="pseudoinverse", constraints=self.constraints, engine=engine
        )


def zoo_setup(name: str, direction: np.ndarray = DIRECTION) -> ZooSetup:
    """Load robot ``name`` and build its obstacle run (warnings are the caller's).

    Args:
        name: A robot of :meth:`clik.Robot.available`.
        direction: The line's direction in the world frame.

    Raises:
        ClikError: The robot, its task or its constraints are refused.
    """
    robot = clik.Robot.load(name)
    task = clik.Task(robot, deepest_frame(robot), "position")
    q0 = robot.q_reference
    p0 = task.placement(q0).translation.copy()
    u = direction / np.linalg.norm(direction)
    ball = Obstacle("ball", "sphere", p0 + SPHERE_AHEAD * u, radius=SPHERE_RADIUS)
    limits = JointLimits(robot, np.radians(JOINT_MARGIN_DEG))
    constraints = ConstraintSet(
        robot, obstacles=[ball], obstacle_threshold=THRESHOLD, joint_limits=limits
    )
    line = Line(p0, p0 + LINE_LENGTH * u, duration=LINE_DURATION)
    return ZooSetup(robot, task, q0, constraints, line)
