"""The distance and gaze kinds on the shipped examples, checked by forward kinematics.

``baxter_box_width``: Baxter's hands close to a box's width, 0.30 m, then hold it within
1e-4 m while both move. ``panda_look_at``: the Panda's hand holds its position while its
z axis points at a point moving 30 cm, within 1e-3 rad. Both in both engines, with
Pinocchio's forward kinematics on the written joints (not clik's own numbers), the joint
ranges and speeds checked too.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

from clik.scenarios import scenario_path
from clik.scenarios.runner import Run, build
from tests.limits_check import assert_completed

ENGINES = ("python", "compiled")


def ran(name: str, engine: str) -> tuple[Run, object]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Baxter's SRDF names prefixed joints
        run = build(scenario_path(name))
    run.tracker.engine = engine
    return run, run.execute()


def placements(run: Run, q: np.ndarray, frames: list[str]) -> dict[str, np.ndarray]:
    """Each frame's world placement (N, 4, 4) at the written joints (Pinocchio's FK)."""
    model = run.robot.model
    data = model.createData()
    ids = {f: model.getFrameId(f) for f in frames}
    out: dict[str, list[np.ndarray]] = {f: [] for f in frames}
    for qk in q:
        pin.framesForwardKinematics(model, data, qk)
        for f, i in ids.items():
            out[f].append(data.oMf[i].homogeneous.copy())
    return {f: np.array(v) for f, v in out.items()}


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
