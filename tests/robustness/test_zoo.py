"""Every robot of the zoo, pushed into a sphere by its task: completed clean, or deadlock.

(Or ``off_track``, when the run reaches its end with the obstacle's row holding the arm
off the reference before the deadlock window is full: the reason names the row.)

The run of :mod:`zoo_runs` makes the task and the obstacle constraint conflict. Law (10)
with constraints first must keep every constraint and stop with ``deadlock`` (or track to
the end without touching anything); it must never swing the arm (a joint step above
0.05 rad), diverge, or end ``completed`` over a crossed limit.
"""

from __future__ import annotations

import numpy as np
import pytest

import clik
from tests.limits_check import assert_within_limits
from tests.zoo_runs import zoo_run

MAX_STEP = 0.05
"""Largest joint step allowed on the way [rad or m]."""

REFUSED = {"GeometryError", "RobotLoadError", "InfeasibleError"}
"""Refusals a robot may meet before its run (named errors, never a crash)."""


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(clik.Robot.available()))
def test_zoo_obstacle_run(name: str) -> None:
    run = zoo_run(name)
    if run.result is None:
        assert run.status in REFUSED, run.reason
        return
    result = run.result
    if result.status == "violated":  # only a start in collision, recorded at t = 0
        assert all(v["t_first"] == 0.0 for v in result.violations), result.violations
        assert run.setup is not None
        stuck = run.setup.constraints.immovable_pairs
        if result.min_obstacle_distance[-1] < 0.03 - 1e-4:  # not recovered: only when
            # the overlap is on the fixed base, which no motion clears (and the reason says so)
            assert {v["constraint"] for v in result.violations} <= stuck, result.violations
            assert "on a link no joint moves" in result.reason, result.reason
    elif result.status == "off_track":  # the conflict held the arm off, not yet stopped
        assert "held the arm off the reference" in result.reason, result.reason
    else:
        assert result.status in ("completed", "deadlock"), result.reason
    assert run.max_joint_step <= MAX_STEP, f"joint step {run.max_joint_step:.3g}"
    ratio = result.summary()["max_velocity_ratio"]  # the law keeps every joint in its limit
    assert ratio is None or ratio <= 1.0 + 1e-9, f"a joint at {ratio:.4g} x its speed limit"
    bounds = np.array(result.info["joint_speed"]["velocity"])
    assert np.all(np.abs(result.qdot) <= bounds * (1.0 + 1e-9))
    assert np.all(np.isfinite(result.q))
    if result.status == "completed":
        assert run.min_distance >= 0.0
        assert_within_limits(result, result.robot)
    elif result.status == "deadlock":
        assert "in conflict with" in result.reason or "no constraint is active" in result.reason


def test_zoo_mostly_runs() -> None:
    """The refusals above are the exception: the zoo's arms all run."""
    names = ["ur5", "panda", "xarm7", "z1", "talos", "tiago", "solo12", "bolt"]
    statuses = {n: zoo_run(n).status for n in names}
    assert set(statuses.values()) <= {"completed", "deadlock", "off_track"}, statuses
