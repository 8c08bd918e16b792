"""Goals of a robot on a floating base: both feet held where they start, a hand on a line."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

import clik
from clik.trajectory import Hold, Line
from tests.limits_check import assert_completed


def feet_held_hand_line(
    robot: clik.Robot,
    q0: np.ndarray,
    feet: Sequence[str],
    hand: str,
    offset: Sequence[float],
    duration: float,
) -> list[clik.Goal]:
    """Pose goals holding each foot frame at its start (named ``left_foot``, ``right_foot``
    for the frames in that order), then a position goal ``hand`` moving by ``offset`` [m]
    in ``duration`` [s]."""
    goals = []
    for side, frame in zip(("left", "right"), feet, strict=True):
        foot = clik.Task(robot, frame, "pose")
        start = foot.placement(q0)
        hold = Hold(position=start.translation, rotation=start.rotation)
        goals.append(clik.Goal(foot, hold, name=f"{side}_foot"))
    task = clik.Task(robot, hand, "position")
    start = task.placement(q0).translation
    goals.append(clik.Goal(task, Line(start, start + np.asarray(offset), duration), name="hand"))
    return goals


def assert_feet_held_hand_tracked(
    result: clik.TrackingResult, robot: clik.Robot, track: float, moved: float
) -> None:
    """The run of :func:`feet_held_hand_line`: completed within every limit, feet and hand
    within ``track`` [m, rad], the base within its default speeds (1 m/s, 1 rad/s), its
    position moved by at least ``moved`` [m], its quaternion unit."""
    assert_completed(result, robot)  # joint ranges, speeds (the base's too), tracking
    errors = result.task_errors
    for foot in ("left_foot", "right_foot"):
        assert errors[foot]["max"] <= track
        assert errors[foot]["max_orientation"] <= track
    assert errors["hand"]["max"] <= track
    assert np.abs(result.qdot[:, :6]).max() <= 1.0 + 1e-9
    assert np.linalg.norm(result.q[-1, :3] - result.q[0, :3]) >= moved
    assert np.allclose(np.linalg.norm(result.q[:, 3:7], axis=1), 1.0, atol=1e-12)
