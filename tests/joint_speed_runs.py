"""Runs of issue 23, with and without the law's joint speed limits.

The start inside a threshold: a Panda pose hold for 1 s from its ready pose, a 5 cm ball
2.12 cm from link 4 (threshold 3 cm), law (10) with gain 1000. The fast line: the
Panda's hand 0.3 m along +y in 0.15 s and in 3 s (law (10), gain 100).
``python tests/joint_speed_runs.py`` prints the numbers the README quotes;
:mod:`tests.loop.test_joint_speed` checks them.
"""

from __future__ import annotations

import numpy as np

import clik
from clik.constraints import ConstraintSet, Obstacle
from clik.loop.joint_speed import JointSpeed
from clik.loop.tracker import JOINT_SPEED
from clik.trajectory import Hold, Line

BALL = np.array([-0.16510938736458833, -0.18213995147107204, 0.6147820792812956])
"""The ball's centre [m]: 2.12 cm from the Panda's link 4 at its ready pose."""


def inside_run(
    panda: clik.Robot, engine: str, joint_speed: JointSpeed | None = JOINT_SPEED
) -> clik.TrackingResult:
    """The run, in ``engine``, with ``joint_speed`` (None: no limit in the law)."""
    task = clik.Task(panda, "panda_hand", "pose")
    q0 = panda.q_reference
    P = task.placement(q0)
    cset = ConstraintSet(
        panda, obstacles=[Obstacle("ball", "sphere", position=BALL, radius=0.05)],
        obstacle_threshold=0.03,
    )  # fmt: skip
    tracker = clik.Tracker(
        task, law="pseudoinverse", gain=1000.0, constraints=cset, engine=engine,
        joint_speed=joint_speed,
    )  # fmt: skip
    return tracker.run(Hold(P.translation, P.rotation, 1.0), q0)


def fast_line(
    panda: clik.Robot, duration: float, joint_speed: JointSpeed | None
) -> clik.TrackingResult:
    """The hand 0.3 m along +y from the ready pose in ``duration`` [s], law (10), gain 100."""
    task = clik.Task(panda, "panda_hand", "position")
    start = task.placement(panda.q_reference).translation
    line = Line(start, start + [0.0, 0.3, 0.0], duration=duration)
    tracker = clik.Tracker(task, law="pseudoinverse", gain=100.0, joint_speed=joint_speed)
    return tracker.run(line, panda.q_reference)


if __name__ == "__main__":
    robot = clik.Robot.load("panda")
    for label, speed in (("without", None), ("with", JointSpeed())):
        result = inside_run(robot, "compiled", speed)
        s = result.summary()
        release = [e["t"] for e in s["events"] if e["action"] == "release"]
        peak = np.abs(result.qdot).max(axis=0)
        print(
            f"{label} the limits: {result.status}; max velocity ratio "
            f"{s['max_velocity_ratio']:.3g}; joint 1 peak {peak[0]:.3g} rad/s; released at "
            f"{release[0] if release else None} s; max error {result.max_task_error:.3g} m, "
            f"{s.get('max_orientation_error', 0.0):.3g} rad; min distance at the end "
            f"{result.min_obstacle_distance[-1]:.4f} m"
        )
    for duration in (0.15, 3.0):
        for label, speed in (("without", None), ("with", JointSpeed())):
            result = fast_line(robot, duration, speed)
            print(
                f"fast line in {duration:g} s, {label} the limits: {result.status}; max velocity "
                f"ratio {result.summary()['max_velocity_ratio']:.3g}; max error "
                f"{result.max_task_error:.3g} m, final {result.final_task_error:.3g} m"
            )
