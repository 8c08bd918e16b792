"""``recovery``: a run that starts inside a constraint's threshold, and how long it took out.

A joint-range row whose threshold the case-study start lies inside: ``joint3`` at -90
deg, its upper limit moved to -85 deg with a 0.1 rad threshold (depth 0.1 - 5 deg).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import clik
from clik.constraints import ConstraintSet, JointLimits
from clik.constraints.recovery import check_name, recovery_clause
from clik.trajectory import Hold
from tests.limits_check import assert_completed

Q0 = np.radians([180.0, -30.0, -90.0, -30.0])
DEPTH = 0.1 - math.radians(5.0)


def run(robot, engine, constraints=True):
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    jl = JointLimits(robot, threshold=0.1, override={"joint3": {"upper": math.radians(-85.0)}})
    cset = ConstraintSet(robot, joint_limits=jl) if constraints else None
    hold = Hold(position=task.placement(Q0).translation, duration=0.5)
    tracker = clik.Tracker(task, law="pseudoinverse", gain=100.0, constraints=cset, engine=engine)
    return tracker.run(hold, Q0)


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_a_start_past_a_joint_range_threshold_is_recorded_and_recovered(planar4r, engine):
    result = run(planar4r, engine)
    assert_completed(result)
    (record,) = result.summary()["recovery"]
    assert record["constraint"] == "joint:joint3:upper"
    assert record["depth"] == pytest.approx(DEPTH, rel=1e-9)
    assert record["t_start"] == 0.0 and record["recovered"]
    assert record["duration"] == pytest.approx(0.132)  # measured; the row released at 0.228 s
    q3 = result.q[result.t < record["t_end"], 2]
    assert np.all(q3 > math.radians(-85.0) - 0.1 + 1e-9)  # inside the threshold until t_end
    assert result.reason.endswith(
        "; started inside the threshold of joint:joint3:upper (depth 0.01273), recovered in 0.132 s"
    )


def test_both_engines_give_the_same_records(planar4r):
    a, b = (run(planar4r, e).summary()["recovery"] for e in ("compiled", "python"))
    assert a == b and len(a) == 1


def test_a_run_without_constraints_has_none(planar4r):
    result = run(planar4r, "compiled", constraints=False)
    assert result.summary()["recovery"] == []
    assert "started inside" not in result.reason


def test_row_keys_name_the_pose_check():
    assert check_name("obstacle:ball:panda_link4") == "obstacle 'ball'"
    assert check_name("joint:panda_joint2:lower") == "joint range of panda_joint2"
    assert check_name("self:link1:link5") == "link pair link1-link5"
    assert check_name("cone:up") == "cone 'up'"
    assert check_name("workspace:box:x:upper") == "workspace 'box'"
    assert check_name("dexterity") == "dexterity"


def test_a_record_never_recovered_says_so():
    record = {"constraint": "obstacle:ball:link3", "depth": 0.0088, "recovered": False,
              "duration": None}  # fmt: skip
    clause = recovery_clause([record])
    assert clause == (
        "; started inside the threshold of obstacle:ball:link3 (depth 8.8 mm), "
        "not back outside it by the end of the run"
    )
