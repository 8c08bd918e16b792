"""The robot's own points leave the cloud; points away from it stay."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.clouds.self_filter import without_robot
from clik.errors import InputError


@pytest.fixture(scope="module")
def panda() -> clik.Robot:
    with pytest.warns(clik.MimicJointWarning):  # the fingers: not what this file tests
        return clik.Robot.load("panda")


def link_points(robot: clik.Robot, q: np.ndarray, per_shape: int = 50) -> np.ndarray:
    """Points on the links: about ``per_shape`` hull vertices (a mesh) or the shape's centre."""
    data, placed = robot.model.createData(), robot.collision_model.createData()
    pin.updateGeometryPlacements(robot.model, data, robot.collision_model, placed, q)
    found = []
    for go, pose in zip(robot.collision_model.geometryObjects, placed.oMg, strict=True):
        shape = go.geometry
        local = (
            np.asarray(shape.vertices())
            if isinstance(shape, coal.BVHModelBase)
            else np.zeros((1, 3))
        )
        found.append(local[:: max(1, len(local) // per_shape)] @ pose.rotation.T + pose.translation)
    return np.concatenate(found)


def test_points_on_the_arm_go_and_the_others_stay(panda):
    q = panda.q_reference
    on_arm = link_points(panda, q)
    rng = np.random.default_rng(3)
    away = np.column_stack([rng.uniform(0.6, 1.0, 300), rng.uniform(-0.5, 0.5, 300),
                            rng.uniform(0.0, 0.3, 300)])  # fmt: skip
    kept, removed = without_robot(np.vstack([on_arm, away]), panda, q, padding=0.01)
    assert removed == len(on_arm) > 100
    np.testing.assert_array_equal(kept, away)


def test_the_padding_is_the_margin(panda):
    q = panda.q_reference
    tip = link_points(panda, q)[:1]
    data = panda.model.createData()
    pin.framesForwardKinematics(panda.model, data, q)
    outward = tip[0] - data.oMf[panda.frame_id("panda_link0")].translation
    outward /= np.linalg.norm(outward)
    near = tip + 0.005 * outward  # 5 mm off a hull vertex, outward from the base
    assert without_robot(near, panda, q, padding=0.02)[1] == 1
    with pytest.raises(InputError, match="padding"):
        without_robot(near, panda, q, padding=-1.0)
