"""Law (10) with a posture below the hands: the compiled engine's form without a basis of
the free directions (docs/method.md, "A posture below the hands") against the Python
engine's general form, on each of its cases and on those it leaves to the general form.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import clik
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.joint_limits import JointLimits
from clik.trajectory import Hold, JointPath, Line, PoseTrajectory

DURATION = 0.3
LEFT_ARM = [f"left_{j}" for j in ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]


@pytest.fixture(scope="module")
def baxter() -> clik.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ClikWarning)
        return clik.Robot.load(
            "baxter", lock={"l_gripper_l_finger_joint": 0.0, "r_gripper_l_finger_joint": 0.0}
        )


def start(robot: clik.Robot) -> np.ndarray:
    q0 = robot.q_reference.copy()
    for side in ("left", "right"):
        for joint, value in {"s1": -0.6, "e1": 1.2, "w1": 0.9}.items():
            q0[robot.model.joints[robot.joint_id(f"{side}_{joint}")].idx_q] = value
    return q0


def run(
    robot: clik.Robot, q0: np.ndarray, joints: list[str] | None, damping: float, engine: str
) -> clik.TrackingResult:
    goals = []
    for side in ("left", "right"):
        hand = clik.Task(robot, f"{side}_hand_link", "pose")
        p = hand.placement(q0)
        line = Line(p.translation, p.translation + np.array([0.0, 0.05, 0.05]), DURATION)
        goals.append(clik.Goal(hand, PoseTrajectory(line, Hold(rotation=p.rotation)), name=side))
    posture = clik.PostureTask(robot, joints)
    target = posture.angles(q0) + 0.2  # a pull the hands' null space takes in part
    goals.append(clik.Goal(posture, JointPath(target), name="posture", priority=2, gain=10.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ClikWarning)
        return clik.track(
            tasks=goals, q0=q0, law="pseudoinverse", gain=100.0, damping=damping,
            constraints=ConstraintSet(robot, joint_limits=JointLimits(robot)), engine=engine,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("joints", "damping"),
    [
        (None, 0.0),  # every joint: no free joint left out of the posture
        (None, 0.05),  # damped
        (LEFT_ARM, 0.0),  # 7 rows, 3 directions: the right arm and the head left out
        (LEFT_ARM[:2], 0.0),  # 2 rows, 3 directions: the general form
    ],
)
def test_the_engines_agree(baxter: clik.Robot, joints: list[str] | None, damping: float) -> None:
    q0 = start(baxter)
    compiled = run(baxter, q0, joints, damping, "compiled")
    python = run(baxter, q0, joints, damping, "python")
    assert compiled.status == python.status == "completed"
    np.testing.assert_allclose(compiled.q, python.q, rtol=0, atol=1e-9)
    moved = np.abs(compiled.q[-1] - q0).max()
    assert moved > 1e-3  # the run went somewhere


def test_a_joint_held_by_its_range(baxter: clik.Robot) -> None:
    """A joint started on its range: its row holds it (a unit row), the engines agree."""
    q0 = start(baxter)
    joint = baxter.model.joints[baxter.joint_id("left_e1")]
    q0[joint.idx_q] = baxter.model.upperPositionLimit[joint.idx_q] - 1e-3
    compiled = run(baxter, q0, None, 0.0, "compiled")
    python = run(baxter, q0, None, 0.0, "python")
    assert compiled.events and compiled.events == python.events
    np.testing.assert_allclose(compiled.q, python.q, rtol=0, atol=1e-9)
    assert compiled.q[:, joint.idx_q].max() <= baxter.model.upperPositionLimit[joint.idx_q]
