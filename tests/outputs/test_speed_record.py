"""``speed_limited``, ``speed_limited_time`` and ``max_acceleration_ratio`` of a summary.

Built on hand-made records (the law's bounds in ``info["joint_speed"]``) so each number
is known: a coordinate at its bound on given samples, one just below it.
"""

from __future__ import annotations

import numpy as np
import pytest

from clik.outputs.speed_record import max_acceleration_ratio, speed_limited

T = np.arange(6) * 0.002  # dt 1 ms, record_every 2
NAMES = ["j1", "j2"]


def info(velocity, acceleration=None):
    return {
        "dt": 0.001,
        "record_every": 2,
        "joint_speed": {
            "scale": 1.0,
            "velocity": velocity,
            "acceleration": acceleration,
            "default_velocity": 2.0,
            "unlimited": [],
        },
    }


def test_a_joint_at_its_bound_is_recorded_with_its_times():
    qdot = np.zeros((6, 2))
    qdot[1:4, 0] = [-1.5, 1.5, 1.5 * (1 - 1e-7)]  # at the bound (within 1e-6)
    qdot[:, 1] = 0.999 * 2.0  # below its bound
    records, time = speed_limited(T, qdot, NAMES, info([1.5, 2.0]))
    assert records == [{"joint": "j1", "t_first": 0.002, "t_last": 0.006, "samples": 3}]
    assert time == pytest.approx(3 * 0.002)


def test_no_bound_in_the_law_means_no_record():
    qdot = np.full((6, 2), 10.0)
    assert speed_limited(T, qdot, NAMES, {"dt": 0.001, "record_every": 2}) == ([], 0.0)
    assert speed_limited(T, qdot, NAMES, {"joint_speed": None}) == ([], 0.0)
    assert max_acceleration_ratio(qdot, {"joint_speed": None}) is None


def test_acceleration_ratio_over_the_coordinates_with_a_bound():
    qddot = np.zeros((6, 2))
    qddot[2] = [-30.0, 500.0]
    assert max_acceleration_ratio(qddot, info([1.5, 2.0], [40.0, None])) == pytest.approx(0.75)
    assert max_acceleration_ratio(qddot, info([1.5, 2.0], None)) is None


def test_the_summary_reports_them(planar4r):
    import clik
    from clik.trajectory import Line

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    result = clik.track(task, Line(p0, p0 + [0.05, 0.02, 0.0], 0.5), q0=q0)
    summary = result.summary()
    assert summary["speed_limited"] == [] and summary["speed_limited_time"] == 0.0
    assert summary["max_acceleration_ratio"] is None and summary["recovery"] == []
    bound = np.abs(result.qdot).max(axis=0)  # every coordinate at its bound somewhere
    result.info["joint_speed"] = info(list(np.maximum(bound, 1e-3)))["joint_speed"]
    limited = result.summary()["speed_limited"]
    assert [r["joint"] for r in limited] == planar4r.joint_names
    assert all(r["samples"] >= 1 for r in limited)
    assert result.summary()["speed_limited_time"] >= 0.001
