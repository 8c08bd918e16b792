"""The gaze kind: its case for the generic tests, and its example checked by FK.

``panda_look_at``: the Panda's hand holds its position while its z axis points at a point
moving 30 cm, within 1e-3 rad, in both engines, by Pinocchio's forward kinematics on the
written joints, the joint ranges and speeds checked too.
"""

from __future__ import annotations

import numpy as np
import pytest

from clik.tasks.gaze_task import GazeTask
from clik.trajectory import Line
from tests.limits_check import assert_completed
from tests.tasks.kind_case import Q0, Case, linear, panda, point_forms
from tests.tasks.scenario_fk import ENGINES, placements, ran


def case() -> Case:
    """Link 7's y axis on a point 0.5 m ahead moving 5 cm."""
    robot = panda()
    task = GazeTask(robot, "panda_link7", [0.0, 1.0, 0.0])
    p0 = task.ahead(Q0, 0.5)  # type: ignore[attr-defined]
    traj = Line(p0, p0 + [0.05, 0.0, 0.0], 0.3)
    table = 'kind = "gaze"\nframe = "panda_link7"\naxis = [0.0, 1.0, 0.0]'
    return Case(
        task, traj, table, {"axis": [0, 0, 0], "frame": 1.0}, point_forms, linear,
        lambda q: task.ahead(q, 0.5),  # type: ignore[attr-defined]
    )  # fmt: skip


@pytest.mark.parametrize("engine", ENGINES)
def test_a_hand_held_camera_looks_at_a_moving_point(engine: str) -> None:
    run, result = ran("panda_look_at", engine)
    assert_completed(result, run.robot)
    t, q = result.t, result.q
    hand = placements(run, q, ["panda_hand"])["panda_hand"]
    camera = next(g for g in run.goals if g.name == "camera")
    point = camera.trajectory.sample(t).position
    assert np.linalg.norm(point[-1] - point[0]) > 0.29  # the point moved 30 cm
    assert np.allclose(point[-1], [0.307, 0.3, -0.41])
    axis = hand[:, :3, 2]  # the hand's z axis in the world
    to_point = point - hand[:, :3, 3]
    cos = np.einsum("ij,ij->i", axis, to_point) / np.linalg.norm(to_point, axis=1)
    angle = np.arccos(np.clip(cos, -1.0, 1.0))
    assert angle.max() <= 1e-3
    assert np.linalg.norm(hand[:, :3, 3] - hand[0, :3, 3], axis=1).max() <= 1e-4  # held
    turned = np.arccos(np.clip(np.dot(axis[0], axis[-1]), -1.0, 1.0))
    assert turned > 0.25  # it turned to follow the point (atan(0.3 / 1) = 0.29 rad)
    assert result.task_errors["camera"]["error"] == "gaze angle"
