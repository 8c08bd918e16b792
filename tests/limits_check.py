"""What a test that accepts ``completed`` checks besides the status: the limits themselves.

A status is clik's own word; these helpers look at the numbers: every recorded joint
value inside the robot's limits (and a joint-range constraint's, when given), every
recorded obstacle distance at or above a floor, and no violation recorded.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import clik

JOINT_TOL = 1e-9
"""Rounding allowed past a joint limit [rad or m]."""


def assert_within_limits(
    result: clik.TrackingResult,
    robot: clik.Robot,
    obstacle_floor: float = 0.0,
    limits: tuple[np.ndarray, np.ndarray] | None = None,
) -> None:
    """``result`` crossed no limit: joints in range, links at or beyond ``obstacle_floor`` [m].

    Args:
        result: The run.
        robot: Its robot (the URDF limits).
        obstacle_floor: Smallest allowed recorded obstacle distance [m].
        limits: Stricter ``(lower, upper)`` per configuration entry, e.g. a constraint's.
    """
    assert result.violations == [], result.violations
    low, high = (robot.lower, robot.upper) if limits is None else limits
    assert np.all(result.q >= low - JOINT_TOL), "a joint below its lower limit"
    assert np.all(result.q <= high + JOINT_TOL), "a joint above its upper limit"
    if result.min_obstacle_distance is not None:
        assert np.nanmin(result.min_obstacle_distance) >= obstacle_floor


def assert_summary_within_limits(
    summary: dict[str, Any], robot: clik.Robot, obstacle_floor: float = 0.0
) -> None:
    """The same checks on a ``summary.json`` (its joint extremes and minimum distance)."""
    assert summary["violations"] == [], summary["violations"]
    assert np.all(np.asarray(summary["joint_min"]) >= robot.lower - JOINT_TOL)
    assert np.all(np.asarray(summary["joint_max"]) <= robot.upper + JOINT_TOL)
    if summary.get("min_obstacle_distance") is not None:
        assert summary["min_obstacle_distance"] >= obstacle_floor
