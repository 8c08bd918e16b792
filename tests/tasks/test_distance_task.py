"""The distance kind: its case for the generic tests, and its example checked by FK.

``baxter_box_width``: Baxter's hands close to a box's width, 0.30 m, then hold it within
1e-4 m while both move, in both engines, by Pinocchio's forward kinematics on the written
joints, the joint ranges and speeds checked too.
"""

from __future__ import annotations

import numpy as np
import pytest

from clik.tasks.distance_task import DistanceTask
from clik.trajectory import JointPath
from tests.limits_check import assert_completed
from tests.tasks.kind_case import Q0, Case, panda
from tests.tasks.scenario_fk import ENGINES, placements, ran


def case() -> Case:
    """The hand's distance from link 3 shrinking by 2 cm."""
    robot = panda()
    task = DistanceTask(robot, "panda_hand", "panda_link3")
    d0 = task.distance(Q0)  # type: ignore[attr-defined]
    traj = JointPath([[d0], [d0 - 0.02]], duration=0.3)
    table = 'kind = "distance"\nframe = "panda_hand"\nrelative_to = "panda_link3"'
    return Case(
        task, traj, table, {"relative_to": 2, "frame": []},
        lambda r: [float(r[0]), r.copy(), np.float64(r[0]), [float(r[0])]],
        lambda s, k: float(s.qdot[k, 0]), lambda q: np.array([task.distance(q)]),  # type: ignore[attr-defined]
    )  # fmt: skip


@pytest.mark.parametrize("engine", ENGINES)
def test_two_hands_keep_a_box_s_width_while_both_move(engine: str) -> None:
    run, result = ran("baxter_box_width", engine)
    assert_completed(result, run.robot)
    t, q = result.t, result.q
    hands = placements(run, q, ["left_hand_link", "right_hand_link"])
    left, right = hands["left_hand_link"][:, :3, 3], hands["right_hand_link"][:, :3, 3]
    width = np.linalg.norm(left - right, axis=1)
    held = t >= 1.0  # the line to 0.30 m lasts 1 s, then the width is held
    assert np.abs(width[held] - 0.30).max() <= 1e-4
    assert width[0] > 0.7  # it started at the arms' own width
    moved = held & (t >= 1.0)
    assert np.linalg.norm(left[moved][-1] - left[moved][0]) > 0.05  # both hands move on
    assert np.linalg.norm(right[moved][-1] - right[moved][0]) > 0.05
    assert result.task_errors["box_width"]["unit"] == "m"
