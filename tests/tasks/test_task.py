"""Task errors and Jacobians: every task Jacobian matches finite differences (eq. (3))."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik import FrameNotFound, InputError, Task
from clik.tasks.kind import BaseTask
from clik.trajectory import Hold, Line, PoseTrajectory
from tests.tasks.kind_case import Q0, Case, panda, pose_forms, pose_row, twist

FD_STEP = 1e-7
JACOBIAN_ATOL = 1e-6


def finite_difference_jacobian(task: Task, q: np.ndarray) -> np.ndarray:
    """Central differences of the frame's position and orientation (world rotation vector)."""
    robot = task.robot
    cols = []
    for i in range(robot.nv):
        dq = np.zeros(robot.nv)
        dq[i] = FD_STEP
        plus = task.placement(pin.integrate(robot.model, q, dq))
        minus = task.placement(pin.integrate(robot.model, q, -dq))
        lin = (plus.translation - minus.translation) / (2 * FD_STEP)
        ang = pin.log3(plus.rotation @ minus.rotation.T) / (2 * FD_STEP)
        cols.append(np.concatenate([lin, ang]))
    return np.array(cols).T[task.rows]


CASES = [
    ("planar4r", "tip", "position", ["x", "y"]),
    ("planar4r", "tip", "pose", None),
    ("panda", "panda_hand", "pose", None),
    ("panda", "panda_hand", "position", None),
    ("panda", "panda_link5", "orientation", None),
    ("panda", "panda_hand", "pose", ["x", "y", "z", "rz"]),
    ("ur5", "tool0", "pose", None),
    ("ur5", "wrist_2_link", "position", ["x", "z"]),
]


@pytest.mark.parametrize(("robot_name", "frame", "kind", "axes"), CASES)
def test_jacobian_matches_finite_differences(request, robot_name, frame, kind, axes):
    robot = request.getfixturevalue(robot_name)
    task = Task(robot, frame, kind, axes)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = robot.random_configuration(rng)
        np.testing.assert_allclose(
            task.jacobian(q), finite_difference_jacobian(task, q), atol=JACOBIAN_ATOL
        )


def test_error_convention(planar4r):
    task = Task(planar4r, "tip", "pose")
    q = np.radians([180, -30, -90, -30])
    M = task.placement(q)
    R_d = M.rotation @ pin.exp3(np.array([0.0, 0.0, 0.1]))
    e = task.error(q, M.translation + [0.01, -0.02, 0.0], R_d)
    np.testing.assert_allclose(e[:3], [0.01, -0.02, 0.0], atol=1e-12)
    # world-frame rotation vector from R to R_d: R_d R^T = R exp(0.1 z) R^T
    np.testing.assert_allclose(e[3:], M.rotation @ [0.0, 0.0, 0.1], atol=1e-12)


def test_unknown_frame_lists_frames(planar4r):
    with pytest.raises(FrameNotFound) as info:
        Task(planar4r, "flange", "position")
    assert "frame 'flange' not found" in str(info.value)
    assert "'tip'" in str(info.value)


@pytest.mark.parametrize(
    ("kind", "axes", "message"),
    [
        ("velocity", None, "task.kind: expected one of 'position', 'orientation', 'pose'"),
        ("position", ["x", "rz"], "task.axes: expected distinct names among ['x', 'y', 'z']"),
        ("pose", ["x", "x"], "task.axes: expected distinct names"),
        ("position", [], "task.axes: expected a non-empty list"),
    ],
)
def test_bad_task_arguments(planar4r, kind, axes, message):
    with pytest.raises(InputError) as info:
        Task(planar4r, "tip", kind, axes)
    assert message in str(info.value)


def case() -> Case:
    """The frame task: link 4's x, y and yaw, moving 2 cm."""
    robot = panda()
    task: BaseTask = clik.Task(robot, "panda_link4", "pose", ["x", "y", "rz"])
    start = task.placement(Q0)  # type: ignore[attr-defined]
    line = Line(start.translation, start.translation + [0.0, 0.02, 0.0], 0.3)
    traj: Any = PoseTrajectory(line, Hold(rotation=start.rotation))
    table = (
        'kind = "pose"\nframe = "panda_link4"\naxes = ["x", "y", "rz"]\n'
        '[tasks.trajectory]\nkind = "hold"\nduration = 0.3'
    )
    return Case(
        task, traj, table, {"frame": 3, "axes": ["q"]}, pose_forms, twist,
        lambda q: pose_row(task.placement(q)), exact=False,  # type: ignore[attr-defined]
    )  # fmt: skip
