"""A cloud in the 3-D view: its points (at most 20,000, where the run had them), its rows.

The scene's commands are read without a browser: the ``Points`` object's positions are
decoded from the typed array the viewer receives.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest
import umsgpack

import clik
from clik.clouds.cloud_obstacle import CloudObstacle
from clik.clouds.drawn import MAX_DRAWN_POINTS, drawn_points
from clik.constraints.cloud_avoidance import CloudAvoidance
from clik.constraints.constraint_set import ConstraintSet
from clik.model.robot import PANDA_FINGERS
from clik.outputs.result import TrackingResult
from clik.trajectory import Line
from clik.viz import build_scene, export_html
from tests.viz.test_viz import html_commands

N_POINTS = 50_000
"""More points than a view draws of a cloud."""
SIZE = 0.1
"""The crate's side [m]."""
POSITION = np.array([0.307, 0.15, 0.40])
RPY = np.array([0.0, 0.0, 0.4])
VOXEL = 0.01
PATH = "/meshcat/clouds/crate/points"


def box_surface(n: int, seed: int = 1) -> np.ndarray:
    """``n`` points on the faces of a cube of side :data:`SIZE` about its centre [m]."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-0.5 * SIZE, 0.5 * SIZE, (n, 3))
    axis = rng.integers(0, 3, n)
    points[np.arange(n), axis] = 0.5 * SIZE * rng.choice([-1.0, 1.0], n)
    return points


@pytest.fixture(scope="module")
def crate() -> CloudObstacle:
    return CloudObstacle("crate", box_surface(N_POINTS), VOXEL, POSITION, RPY)


@pytest.fixture(scope="module")
def result(crate: CloudObstacle) -> TrackingResult:
    """The Panda's hand along a line over the crate: its rows activate."""
    robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
    task = clik.Task(robot, "panda_hand", "position")
    q0 = robot.q_reference
    p0 = task.placement(q0).translation
    constraints = ConstraintSet(robot, kinds=[CloudAvoidance([crate], threshold=0.03)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.ClikWarning)
        return clik.track(
            task, Line(p0, p0 + [0.0, 0.3, 0.0], duration=1.0), q0=q0, law="pseudoinverse",
            gain=100.0, constraints=constraints,
        )  # fmt: skip


def cloud_object(commands: list[dict]) -> dict:
    """The one ``set_object`` of the crate's points."""
    (command,) = [c for c in commands if c["type"] == "set_object" and c["path"] == PATH]
    return command["object"]


def positions(obj: dict) -> np.ndarray:
    """The points a ``Points`` object draws (M, 3) [m], decoded as the viewer does."""
    packed = obj["geometries"][0]["data"]["attributes"]["position"]
    assert isinstance(packed["array"], umsgpack.Ext) and packed["type"] == "Float32Array"
    assert packed["itemSize"] == 3
    return np.frombuffer(packed["array"].data, dtype="<f4").reshape(-1, 3)


def test_the_cloud_is_drawn_thinned_where_it_is(result, crate):
    obj = cloud_object(build_scene(result, geometry="collision").commands)
    assert obj["object"]["type"] == "Points"
    material = obj["materials"][0]
    assert material["type"] == "PointsMaterial" and material["size"] == VOXEL
    drawn = positions(obj)
    stride = math.ceil(N_POINTS / MAX_DRAWN_POINTS)
    assert len(drawn) == math.ceil(N_POINTS / stride) <= MAX_DRAWN_POINTS
    np.testing.assert_allclose(drawn, crate.world[::stride], atol=1e-6)  # in the world
    np.testing.assert_allclose(obj["object"]["matrix"], np.eye(4).reshape(-1))  # node: origin
    local = (drawn - POSITION) @ pin.rpy.rpyToMatrix(*RPY)  # back in the crate's frame
    assert np.all(np.abs(local) <= 0.5 * SIZE + 1e-6)
    assert np.all(np.isclose(np.abs(local), 0.5 * SIZE, atol=1e-6).any(axis=1))  # on its faces


def test_the_active_cloud_rows_have_witness_segments(result):
    commands = build_scene(result, geometry="collision").commands
    active = {e["constraint"] for e in result.events if e["action"] == "activate"}
    assert active and all(name.startswith("cloud:crate:") for name in active)
    drawn = {c["path"] for c in commands if c["type"] == "set_object"}
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    tracks = {a["path"]: [t["name"] for t in a["clip"]["tracks"]] for a in animation["animations"]}
    for name in active:
        path = "/meshcat/witness/" + name.replace(":", "-")
        assert path in drawn
        assert ".visible" in tracks[path] and ".position" in tracks[path]


def test_a_saved_run_and_its_page_draw_the_same_points(result, tmp_path):
    drawn = positions(cloud_object(build_scene(result, geometry="collision").commands))
    loaded = TrackingResult.load(result.save(tmp_path / "run.npz"))  # as clik show reads it
    again = build_scene(loaded, robot=result.robot, geometry="collision").commands
    np.testing.assert_array_equal(positions(cloud_object(again)), drawn)
    page = export_html(result, tmp_path / "scene.html", geometry="collision")
    np.testing.assert_array_equal(positions(cloud_object(html_commands(page))), drawn)


def test_a_small_cloud_is_drawn_whole_and_a_run_without_clouds_has_none():
    points = box_surface(1234)
    np.testing.assert_array_equal(drawn_points(points), points.astype(np.float32))
    assert len(drawn_points(box_surface(MAX_DRAWN_POINTS + 1))) == (MAX_DRAWN_POINTS + 2) // 2
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180, -30, -90, -30])
    p0 = task.placement(q0).translation
    plain = clik.track(task, Line(p0, p0 + [0.05, 0.0, 0.0], duration=0.2), q0=q0,
                       law="pseudoinverse", gain=100.0)  # fmt: skip
    commands = build_scene(plain).commands
    assert not [c for c in commands if c.get("path", "").startswith("/meshcat/clouds")]
