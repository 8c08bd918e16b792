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


def _longest_above(t: np.ndarray, error: np.ndarray, tolerance: float) -> float:
    """Longest time [s] ``error`` stayed above ``tolerance`` on consecutive samples."""
    longest, start = 0.0, None
    for k, above in enumerate(~(np.asarray(error) <= tolerance)):
        if above and start is None:
            start = k
        if start is not None:
            longest = max(longest, float(t[k] - t[start]))
        if not above:
            start = None
    return longest


def assert_completed(result: clik.TrackingResult, robot: clik.Robot | None = None) -> None:
    """``completed`` and the numbers behind it: limits, joint speeds and tracking.

    No violation and every joint within the robot's limits (:func:`assert_within_limits`,
    with ``joint_min``/``joint_max`` too), every recorded speed within its bound (the
    law's, ``info["joint_speed"]``, else the URDF's), and the task error within the run's
    tolerance (``info["tolerance"]``) at the last sample and never above it for longer
    than the settling time.
    """
    assert result.status == "completed", result.reason
    robot = result.robot if robot is None else robot
    assert robot is not None
    assert_within_limits(result, robot)
    assert np.all(result.joint_min >= robot.lower - JOINT_TOL)
    assert np.all(result.joint_max <= robot.upper + JOINT_TOL)
    joint_speed = result.info.get("joint_speed")
    bound = (
        np.asarray(joint_speed["velocity"], dtype=float)
        if joint_speed
        else np.asarray(robot.model.velocityLimit, dtype=float)
    )
    limited = np.isfinite(bound) & (bound > 0.0)
    speed = np.abs(result.qdot[:, limited])
    assert np.all(speed <= bound[limited] * (1.0 + 1e-9)), "a joint above its speed limit"
    tol = result.info["tolerance"]
    errors = [(result.task_error_norm, tol["position"])]
    if result.info.get("task") == "orientation":
        errors = [(result.task_error_norm, tol["orientation"])]
    elif result.orientation_error_norm is not None:
        errors.append((result.orientation_error_norm, tol["orientation"]))
    for error, limit in errors:
        assert error[-1] <= limit, f"final error {error[-1]:.4g} above {limit:g}"
        assert _longest_above(result.t, error, limit) <= tol["settling_time"]
