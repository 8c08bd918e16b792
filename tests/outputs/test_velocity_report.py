"""Joint speeds against the URDF velocity limits: ``max_velocity_ratio`` and ``velocity``.

The expected numbers are computed here from the recorded arrays (``trajectory.npz``)
and the model's ``velocityLimit``, independently of :mod:`clik.outputs.velocity_report`.
The bounds of other sources (a setting, the default, a base's speed):
``test_velocity_bounds.py``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.outputs.result import TrackingResult, write_outputs
from clik.outputs.velocity_report import (
    VelocityLimits,
    model_velocity_limits,
    velocity_names,
    velocity_report,
)
from clik.trajectory import Line
from tests.limits_check import assert_within_limits
from tests.model.test_joint_kinds import CONTINUOUS_BODY
from tests.urdf_snippets import urdf_text

FAST_S = 0.15
"""Duration of the fast Panda line: 0.3 m in 0.15 s, about twice the joint limits [s]."""

SLOW_S = 3.0
"""Duration of the slow Panda line: the same 0.3 m in 3 s [s]."""

RECORD_KEYS = {
    "joint", "max_ratio", "max_velocity", "limit", "source", "t_first", "t_last", "samples",
}  # fmt: skip


def panda_line(panda: clik.Robot, duration: float) -> TrackingResult:
    """The Panda's hand 0.3 m along +y from the ready pose in ``duration`` [s].

    Without the law's joint speed limits: the report is about the URDF limits a law that
    does not keep them goes past.
    """
    task = clik.Task(panda, "panda_hand", "position")
    start = task.placement(panda.q_reference).translation
    line = Line(start, start + [0.0, 0.3, 0.0], duration=duration)
    return clik.track(
        task, line, q0=panda.q_reference, law="pseudoinverse", gain=100.0, dt=1e-3,
        joint_speed=None,
    )  # fmt: skip


def expected_report(
    t: np.ndarray, qdot: np.ndarray, names: list[str], limit: np.ndarray
) -> tuple[float | None, list[dict]]:
    """The ratio and records, from the arrays, joint by joint."""
    best: float | None = None
    records = []
    for i, (name, vmax) in enumerate(zip(names, limit, strict=True)):
        if not (math.isfinite(vmax) and vmax > 0):
            continue
        speed = np.abs(qdot[:, i])
        ratio = speed.max() / vmax
        best = ratio if best is None else max(best, ratio)
        above = t[speed > vmax]
        if above.size:
            records.append(
                {
                    "joint": name,
                    "max_ratio": ratio,
                    "max_velocity": speed.max(),
                    "limit": vmax,
                    "source": "urdf",
                    "t_first": above[0],
                    "t_last": above[-1],
                    "samples": above.size,
                }
            )
    return best, records


def assert_records_equal(got: list[dict], expected: list[dict]) -> None:
    assert [r["joint"] for r in got] == [r["joint"] for r in expected]
    for g, e in zip(got, expected, strict=True):
        assert set(g) == RECORD_KEYS
        assert g["samples"] == e["samples"] and g["source"] == e["source"]
        for key in ("max_ratio", "max_velocity", "limit", "t_first", "t_last"):
            assert g[key] == pytest.approx(e[key], rel=1e-12, abs=1e-9), key


@pytest.fixture(scope="module")
def fast(panda) -> TrackingResult:
    return panda_line(panda, FAST_S)


def test_fast_panda_line_reports_each_joint_over_its_limit(fast, panda, tmp_path):
    assert fast.status == "velocity_limit", fast.reason  # above the URDF's: not completed
    assert_within_limits(fast, panda)
    out = tmp_path / "out"
    out.mkdir()
    summary = write_outputs(fast, out)
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["max_velocity_ratio"] == summary["max_velocity_ratio"]
    assert on_disk["velocity"] == summary["velocity"]
    with np.load(out / "trajectory.npz") as npz:
        t, qdot = npz["t"], npz["qdot"]
    limit = np.array(panda.model.velocityLimit)
    ratio, records = expected_report(t, qdot, panda.joint_names, limit)
    assert ratio is not None and ratio > 1.5
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    top = int(np.argmax(np.abs(qdot).max(axis=0) / limit))
    assert summary["max_velocity_ratio_joint"] == panda.joint_names[top]
    assert summary["max_velocity_ratio_source"] == "urdf"
    assert on_disk["velocity_bounds"] == {
        name: {"bound": v, "source": "urdf"}
        for name, v in zip(panda.joint_names, limit, strict=True)
    }
    assert len(records) >= 2
    assert_records_equal(summary["velocity"], records)
    over = {r["joint"] for r in records}
    for name, i in zip(panda.joint_names, range(panda.nv), strict=True):
        assert (name in over) == (np.abs(qdot[:, i]).max() > limit[i])


def test_a_loaded_result_reports_the_same_speeds(fast, tmp_path):
    back = TrackingResult.load(fast.save(tmp_path / "run.npz"))
    assert back.robot is None
    assert back.summary()["max_velocity_ratio"] == fast.summary()["max_velocity_ratio"]
    assert back.summary()["velocity"] == fast.summary()["velocity"]
    assert back.summary()["velocity_bounds"] == fast.summary()["velocity_bounds"]


def test_existing_summary_keys_are_kept(fast):
    summary = fast.summary()
    for key in ("status", "reason", "steps", "joint_min", "joint_max", "events", "violations"):
        assert key in summary
    assert json.loads(json.dumps(summary, allow_nan=False)) == summary


def test_slow_panda_line_stays_under_its_limits(panda):
    slow = panda_line(panda, SLOW_S)
    assert slow.status == "completed"
    assert_within_limits(slow, panda)
    summary = slow.summary()
    ratio, records = expected_report(
        slow.t, slow.qdot, panda.joint_names, np.array(panda.model.velocityLimit)
    )
    assert records == [] and summary["velocity"] == []
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert 0.0 < summary["max_velocity_ratio"] < 1.0


def test_robot_without_velocity_limits_and_no_law_bound_reports_null(tmp_path):
    """No URDF limit and the law's joint speed limits off: nothing bounds a joint."""
    # j1 continuous with no <limit> (inf), j2 and j3 with velocity="0" (no limit)
    path = tmp_path / "unlimited.urdf"
    path.write_text(urdf_text(CONTINUOUS_BODY.replace('velocity="1"', 'velocity="0"')))
    robot = clik.Robot.load(path)
    assert np.array(robot.model.velocityLimit).tolist() == [math.inf, 0.0, 0.0]
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.array([1.0, 0.0, 0.5, 0.05])
    start = task.placement(q0).translation
    line = Line(start, start + [0.0, 0.05, 0.0], duration=0.1)
    result = clik.track(task, line, q0=q0, joint_speed=None)
    assert result.status == "completed"
    assert_within_limits(result, robot)
    summary = result.summary()
    assert summary["max_velocity_ratio"] is None and summary["velocity"] == []
    assert json.loads(json.dumps(summary))["max_velocity_ratio"] is None
    assert summary["max_velocity_ratio_joint"] is None
    assert summary["velocity_bounds"] == {
        j: {"bound": None, "source": "none"} for j in ("j1", "j2", "j3")
    }


def test_unlimited_coordinates_are_skipped_and_non_finite_speeds_ignored():
    limits = VelocityLimits(["a", "b", "c", "d"], np.array([1.0, math.inf, 0.0, math.nan]))
    assert limits.limited.tolist() == [0]
    t = np.array([0.0, 0.1, 0.2, 0.3])
    qdot = np.array([[0.5, 9, 9, 9], [-1.5, 9, 9, 9], [2.0, 9, 9, 9], [math.nan, 9, 9, 9]])
    report = velocity_report(t, qdot, limits)
    assert report.max_velocity_ratio == 2.0 and report.joint == "a"
    assert [b["source"] for b in report.bounds.values()] == ["urdf", "none", "none", "none"]
    assert report.records == [
        {
            "joint": "a",
            "max_ratio": 2.0,
            "max_velocity": 2.0,
            "limit": 1.0,
            "source": "urdf",
            "t_first": 0.1,
            "t_last": 0.2,
            "samples": 2,
        }
    ]
    exactly = velocity_report(t[:1], np.array([[1.0, 0, 0, 0]]), limits)
    assert exactly.max_velocity_ratio == 1.0 and exactly.records == []  # at the limit: not over


def test_a_joint_with_several_velocities_names_each():
    model = pin.Model()
    ball = model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    model.addJoint(ball, pin.JointModelRZ(), pin.SE3.Identity(), "wrist")
    model.velocityLimit = np.array([1.0, 2.0, 3.0, 4.0])
    assert velocity_names(model) == ["ball[0]", "ball[1]", "ball[2]", "wrist"]
    limits = model_velocity_limits(model)
    np.testing.assert_array_equal(limits.limit, [1.0, 2.0, 3.0, 4.0])
    with pytest.raises(ValueError, match="4 names but limit of shape"):
        VelocityLimits(limits.names, np.ones(3))
