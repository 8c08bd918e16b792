"""Traps of a newcomer's first hour (issue 27): thresholds in degrees, fingers, poor starts.

Each test gives the message or behaviour the user now gets.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.joint_limits import JointLimits
from clik.constraints.joint_thresholds import ThresholdCapWarning
from clik.errors import InputError, ScenarioError
from clik.loop.start_checks import StartWarning, limit_message, singular_message, warn_start
from clik.model.robot import Robot
from clik.scenarios.runner import build
from tests.limits_check import assert_within_limits

PLANAR = """
[robot]
source = "planar4r"

[initial]
q = [180.0, -30.0, -90.0, -30.0]
unit = "deg"

[task]
frame = "tip"
kind = "position"
axes = ["x", "y"]

[trajectory]
kind = "line"
goal = [-1.2, 0.5, 0.0]
duration = 0.2

[solver]
law = "pseudoinverse"
gain = 200.0

[constraints.joint_limits]
enabled = true
"""


@pytest.fixture(scope="module")
def panda8() -> Robot:
    """The Panda as ``Robot.load("panda")`` gives it: 7 arm joints and finger 1 free."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # finger 2 mimics finger 1: locked, said elsewhere
        return Robot.load("panda")


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


# -- (a) a joint-range threshold in degrees read as radians ---------------------------------


def test_unitless_threshold_wider_than_a_joint_range_is_refused(tmp_path, panda8):
    path = write(
        tmp_path,
        PLANAR.replace('source = "planar4r"', 'source = "panda"')
        .replace('[initial]\nq = [180.0, -30.0, -90.0, -30.0]\nunit = "deg"\n', "")
        .replace('frame = "tip"', 'frame = "panda_hand"')
        .replace('axes = ["x", "y"]\n', "")
        .replace("goal = [-1.2, 0.5, 0.0]", "goal = [0.35, 0.05, 0.5]")
        + "threshold = 5.0\n",
    )
    with pytest.raises(ScenarioError) as info:
        build(path, panda8)
    message = str(info.value)
    assert info.value.key == "constraints.joint_limits.threshold"
    assert "panda_joint2's range (3.526 rad)" in message
    assert 'write unit = "deg"' in message


def test_unitless_threshold_above_two_pi_is_refused(planar4r):
    with pytest.raises(InputError, match=r"threshold: expected an angle \[rad\] of at most 2 pi"):
        JointLimits(planar4r, 7.0)


def test_capped_threshold_is_said_with_joints_asked_and_applied(tmp_path, planar4r):
    # planar4r: joint 1 in [-2 pi, 2 pi], joints 2-4 in [-pi, pi]: 5 rad fits no quarter
    path = write(tmp_path, PLANAR + "threshold = 5.0\n")
    with pytest.warns(ThresholdCapWarning) as caught:
        build(path, planar4r)
    message = str(caught[0].message)
    assert message.startswith("constraints.joint_limits.threshold: capped at a quarter")
    assert "joint1 5 -> 3.142 rad" in message
    assert "joint4 5 -> 1.571 rad" in message
    assert 'write unit = "deg"' in message


def test_threshold_in_degrees_is_neither_capped_nor_refused(tmp_path, planar4r):
    path = write(tmp_path, PLANAR + 'threshold = 5.0\nunit = "deg"\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error", ThresholdCapWarning)
        run = build(path, planar4r)
    np.testing.assert_allclose(run.tracker.constraints.joint_limits.threshold, np.radians(5.0))


# -- (b) the Panda's fingers start outside their threshold band -----------------------------


def test_panda_reference_opens_the_finger_to_mid_range(panda8):
    q = panda8.q_reference
    assert panda8.joint_names[7] == "panda_finger_joint1"
    assert q[7] == pytest.approx(0.02)  # SRDF's 0.001 m is inside the 0.005 m band
    assert panda8.locked["panda_finger_joint2"] == pytest.approx(0.02)  # the mimic follows


def test_panda_run_from_reference_activates_no_finger_row_and_keeps_speeds(tmp_path, panda8):
    text = (
        PLANAR.replace('source = "planar4r"', 'source = "panda"')
        .replace('[initial]\nq = [180.0, -30.0, -90.0, -30.0]\nunit = "deg"', "[initial]")
        .replace('frame = "tip"', 'frame = "panda_hand"')
        .replace('axes = ["x", "y"]\n', "")
        .replace("goal = [-1.2, 0.5, 0.0]", "goal = [0.35, 0.05, 0.5]")
        .replace("duration = 0.2", "duration = 0.3")
    )
    run = build(write(tmp_path, text), panda8)
    assert run.tracker.constraints.joint_limits.threshold[7] == 0.005  # the default [m]
    with warnings.catch_warnings():
        warnings.simplefilter("error", StartWarning)
        result = run.execute()
    assert result.status == "completed"
    assert [e for e in result.events if "finger" in e["constraint"]] == []
    assert result.summary()["max_velocity_ratio"] <= 1.0 + 1e-9
    assert_within_limits(result, panda8)


# -- (d) a start singular for the task, or on a joint limit ---------------------------------


def test_ur5_reference_is_singular_and_a_better_start_is_named(ur5):
    task = clik.Task(ur5, "tool0", "pose")
    message = singular_message(task, ur5.q_reference)
    assert message.startswith("q0 ([initial] q): the start is singular for the task")
    assert "start elsewhere, e.g. with wrist_2_joint = -0.3491 rad, elbow_joint = -0.3491 rad" in (
        message
    )
    better = ur5.q_reference
    better[[2, 4]] = -0.3491
    assert singular_message(task, better) == ""


def test_joint_on_its_limit_is_named(panda):
    task = clik.Task(panda, "panda_hand", "pose")
    q = panda.q_reference
    q[3] = panda.model.upperPositionLimit[3]
    message = limit_message(task, q)
    assert "panda_joint4 = -0.0698 rad is within 0.00873 rad of its upper limit -0.0698 rad" in (
        message
    )
    assert message.endswith("it can move one way")
    assert limit_message(task, panda.q_reference) == ""


def test_start_inside_a_joint_range_band_is_named(panda):
    task = clik.Task(panda, "panda_hand", "pose")
    cs = ConstraintSet(panda, joint_limits=JointLimits(panda, np.radians(10.0)))
    q = panda.q_reference
    q[0] = panda.model.lowerPositionLimit[0] + 0.1  # 5.7 deg from the limit
    message = limit_message(task, q, cs)
    assert (
        "panda_joint1 = -2.797 rad is within 0.175 rad (its joint-range threshold) of its lower "
        "limit -2.897 rad; try -2.318 rad"
    ) in message
    assert message.endswith("its joint-range row is active from t = 0")


def test_warned_once_before_the_run_from_track(planar4r):
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    line = clik.trajectory.Line([1.2, 0.0, 0.0], [1.1, 0.2, 0.0], 0.05)
    with pytest.warns(StartWarning) as caught:
        clik.track(task, line, law="pseudoinverse", gain=100.0)  # q0: stretched, singular
    starts = [w for w in caught if w.category is StartWarning]
    assert len(starts) == 1
    assert "e.g. with joint" in str(starts[0].message)


def test_a_fine_start_is_not_warned(planar4r):
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", StartWarning)
        warn_start(task, np.radians([180.0, -30.0, -90.0, -30.0]))


def test_start_beyond_an_override_is_named(panda):
    task = clik.Task(panda, "panda_hand", "pose")
    override = {"panda_joint1": {"lower": -0.1, "upper": 2.0}}
    cs = ConstraintSet(panda, joint_limits=JointLimits(panda, override=override))
    q = panda.q_reference
    q[0] = -0.4
    assert "panda_joint1 = -0.4 rad is beyond its lower limit -0.1 rad; try 0.11 rad" in (
        limit_message(task, q, cs)
    )


UR5 = """
[robot]
source = "ur5"

[task]
frame = "tool0"
kind = "pose"

[trajectory]
kind = "hold"
duration = 0.05

[solver]
law = "pseudoinverse"
gain = 100.0
"""


def test_warned_once_before_the_run_from_a_scenario(tmp_path, ur5):
    run = build(write(tmp_path, UR5), ur5)  # [initial] q absent: the reference, all zeros
    with pytest.warns(StartWarning) as caught:
        run.execute()
    starts = [str(w.message) for w in caught if w.category is StartWarning]
    assert len(starts) == 1
    assert "elbow_joint = -0.3491 rad" in starts[0]
