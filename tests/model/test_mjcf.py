"""MJCF models: clik's arm3, Pinocchio's reading checked against MuJoCo, hostile files refused.

MuJoCo (a bench peer, installed with the test extras) is the reference for the
kinematics and the joint ranges; clik never imports it.
"""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from lxml import etree

import clik
from clik.cli import main as clik_main
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.errors import InputError, RobotLoadError
from clik.loop.joint_speed import JointSpeed
from clik.model import mjcf_check, urdf_check
from clik.model.mjcf_check import check_mjcf, is_mjcf
from clik.model.mjcf_root import FreeJointWeldedWarning
from clik.model.sources import our_robots
from clik.trajectory import Line
from tests.limits_check import assert_completed, assert_summary_within_limits

mujoco = pytest.importorskip("mujoco")

ARM3 = our_robots()["arm3"]
FK_TOL = 1e-12
"""Largest difference of a frame's position [m] or rotation entry between Pinocchio and MuJoCo."""

PARITY_TOL = 1e-9
"""Largest difference between the two engines' joint trajectories [rad]."""

SPEED = JointSpeed(velocity={"shoulder_yaw": 2.0, "shoulder_pitch": 2.0, "elbow": 2.0})
"""MJCF gives no velocity limits: the tests give theirs (no SpeedLimitWarning)."""


@pytest.fixture(scope="module")
def arm3() -> clik.Robot:
    return clik.Robot.load("arm3")


def write(folder: Path, text: str, name: str = "model.xml") -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def model(body: str = "", head: str = "", tail: str = "", name: str = "t") -> str:
    """An MJCF model: one root body with a hinge (and ``body`` inside it)."""
    return (
        f'<mujoco model="{name}">{head}<worldbody>'
        '<body name="b1"><joint name="j1" axis="0 0 1" range="-1 1"/>'
        f'<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02"/>{body}</body>'
        f"</worldbody>{tail}</mujoco>"
    )


def refused(path: Path) -> RobotLoadError:
    with pytest.raises(RobotLoadError) as caught:
        clik.Robot.load(path)
    return caught.value


# ------------------------------------------------------------------ clik's arm3


def test_arm3_loads_as_the_file_says(arm3):
    root = etree.parse(str(ARM3)).getroot()
    joints = root.findall(".//worldbody//joint")
    assert arm3.nq == arm3.nv == len(joints) == 3
    assert arm3.joint_names == [j.get("name") for j in joints]
    ranges = np.array([[float(v) for v in j.get("range").split()] for j in joints])
    np.testing.assert_array_equal(arm3.lower, ranges[:, 0])  # compiler angle="radian"
    np.testing.assert_array_equal(arm3.upper, ranges[:, 1])
    home = root.find("keyframe/key[@name='home']").get("qpos")
    np.testing.assert_array_equal(arm3.q_reference, [float(v) for v in home.split()])
    geoms = root.findall(".//worldbody//geom")
    collision = [g.get("name") for g in geoms if g.get("class") != "visual"]
    assert [go.name for go in arm3.collision_model.geometryObjects] == collision
    assert [go.name for go in arm3.visual_model.geometryObjects] == [g.get("name") for g in geoms]
    hand = arm3.collision_model.geometryObjects[collision.index("hand")]
    assert Path(hand.meshPath) == ARM3.parent / "arm3_hand.stl"
    assert "tool" in arm3.frame_names


def test_arm3_is_listed_by_name(capsys):
    assert clik.Robot.available()["arm3"] == "clik: arm3.xml"
    assert clik_main(["robots"]) == 0
    assert "arm3" in capsys.readouterr().out


def test_forward_kinematics_by_hand(arm3):
    """At q = 0 the arm lies along x: column 0.1 + 0.2 m, links 0.3 + 0.28 m, tool 0.08 m."""
    data = arm3.model.createData()
    pin.framesForwardKinematics(arm3.model, data, np.zeros(3))
    tool = data.oMf[arm3.frame_id("tool")]
    np.testing.assert_allclose(tool.translation, [0.66, 0.0, 0.3], atol=FK_TOL)
    q = np.array([np.pi / 2, -np.pi / 2, 0.0])  # yaw to +y, then pitch the arm straight up
    pin.framesForwardKinematics(arm3.model, data, q)
    np.testing.assert_allclose(
        data.oMf[arm3.frame_id("tool")].translation, [0, 0, 0.96], atol=FK_TOL
    )


def test_forward_kinematics_matches_mujoco(arm3):
    peer = mujoco.MjModel.from_xml_path(str(ARM3))
    peer_data = mujoco.MjData(peer)
    data = arm3.model.createData()
    for q in np.random.default_rng(7).uniform(arm3.lower, arm3.upper, size=(20, 3)):
        peer_data.qpos[:] = q
        mujoco.mj_kinematics(peer, peer_data)
        pin.framesForwardKinematics(arm3.model, data, q)
        for body in ("upper_arm", "forearm", "hand"):
            frame = data.oMf[arm3.frame_id(body)]
            np.testing.assert_allclose(frame.translation, peer_data.body(body).xpos, atol=FK_TOL)
            np.testing.assert_allclose(
                frame.rotation.ravel(), peer_data.body(body).xmat, atol=FK_TOL
            )
        tool = data.oMf[arm3.frame_id("tool")].translation
        np.testing.assert_allclose(tool, peer_data.site("tool").xpos, atol=FK_TOL)


def arm3_line(arm3):
    task = clik.Task(arm3, "tool", "position", axes=["x", "y"])
    start = task.placement(arm3.q_reference).translation
    return task, Line(start, start + [0.0, 0.25, -0.05], duration=1.0)


def test_arm3_tracks_past_an_obstacle_in_both_engines(arm3):
    task, line = arm3_line(arm3)
    ball = Obstacle("ball", "sphere", [0.35, 0.12, 0.4], radius=0.03)
    results = {}
    for engine in ("python", "compiled"):
        cset = ConstraintSet(
            arm3, obstacles=[ball], obstacle_threshold=0.05,
            joint_limits=JointLimits(arm3, np.radians(5.0)),
        )  # fmt: skip
        result = clik.track(
            task, line, law="pseudoinverse", constraints=cset, engine=engine, joint_speed=SPEED
        )
        assert_completed(result, arm3)
        assert np.nanmin(result.min_obstacle_distance) >= 0.0
        actions = {(e["constraint"], e["action"]) for e in result.events}
        assert ("obstacle:ball:forearm", "activate") in actions  # the ball was in the way
        results[engine] = result
    np.testing.assert_allclose(
        results["python"].q, results["compiled"].q, rtol=0.0, atol=PARITY_TOL
    )


def test_scenario_with_an_mjcf_path_runs_through_the_cli(tmp_path):
    for name in ("arm3.xml", "arm3_hand.stl"):
        shutil.copy(ARM3.parent / name, tmp_path / name)
    scenario = write(
        tmp_path,
        """
name = "arm3 (MJCF) passes a ball"
[robot]
source = "arm3.xml"
[task]
frame = "tool"
kind = "position"
axes = ["x", "y"]
[trajectory]
kind = "line"
goal = [0.5447, 0.25, 0.0]
duration = 1.0
[solver]
law = "pseudoinverse"
dt = 0.001
[constraints.joint_speed.velocity]
shoulder_yaw = 2.0
shoulder_pitch = 2.0
elbow = 2.0
[[obstacles]]
name = "ball"
shape = "sphere"
position = [0.35, 0.12, 0.4]
radius = 0.03
[constraints.obstacles]
enabled = true
threshold = 0.05
""",
        "arm3_line.toml",
    )
    assert clik_main(["solve", str(scenario), "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "completed"
    robot = clik.Robot.load(tmp_path / "arm3.xml")
    assert robot.source_path == (tmp_path / "arm3.xml").resolve()
    assert_summary_within_limits(summary, robot)
    assert summary["min_obstacle_distance"] >= 0.0


def test_lock_reduces_the_visual_model_too(arm3):
    locked = clik.Robot.load("arm3", lock={"elbow": 0.5})
    assert locked.joint_names == ["shoulder_yaw", "shoulder_pitch"]
    hand = [go for go in locked.visual_model.geometryObjects if go.name == "hand"]
    assert len(hand) == 1 and locked.model.names[hand[0].parentJoint] == "shoulder_pitch"


@pytest.mark.parametrize(
    ("option", "value"), [("xacro_args", {"n": "1"}), ("srdf", "x.srdf"), ("base", "rolling")]
)
def test_options_an_mjcf_model_does_not_take(option, value):
    """No xacro arguments or SRDF for an MJCF model; its bases are a URDF's (test_mjcf_bases)."""
    with pytest.raises(InputError) as caught:
        clik.Robot.load("arm3", **{option: value})
    assert caught.value.field == option


# ------------------------------------------------------------------ Pinocchio's reading


def test_slide_ranges_stay_in_metres_and_hinges_follow_the_angle_unit(tmp_path):
    """Pinocchio 4.1 converts a slide range as degrees; clik keeps MuJoCo's metres."""
    body = (
        '<body name="b2" pos="0.2 0 0"><joint name="s" type="slide" axis="1 0 0" '
        'range="-0.1 0.2"/><geom type="sphere" size="0.02"/></body>'
    )
    path = write(tmp_path, model(body).replace('range="-1 1"', 'range="-90 45"'))
    robot = clik.Robot.load(path)
    peer = mujoco.MjModel.from_xml_path(str(path))
    np.testing.assert_allclose(robot.lower, peer.jnt_range[:, 0], rtol=1e-15)
    np.testing.assert_allclose(robot.upper, peer.jnt_range[:, 1], rtol=1e-15)
    np.testing.assert_allclose(robot.upper, [np.pi / 4, 0.2], rtol=1e-15)


def test_collision_and_visual_geoms_as_pinocchio_reads_them(tmp_path):
    body = (
        '<geom name="look" type="box" size="0.1 0.1 0.1" contype="0" conaffinity="0"/>'
        '<geom name="touch" type="sphere" size="0.05" group="3"/>'
        '<geom name="solid" type="sphere" size="0.05" contype="0"/>'
    )
    path = write(tmp_path, model(body, tail="").replace("<worldbody>", _FLOOR))
    robot = clik.Robot.load(path)
    collision = [go.name for go in robot.collision_model.geometryObjects]
    visual = [go.name for go in robot.visual_model.geometryObjects]
    assert collision == ["b1Geom_0", "touch", "solid"]  # the floor plane is dropped
    assert visual == ["b1Geom_0", "look", "solid"]


_FLOOR = '<worldbody><geom name="floor" type="plane" size="1 1 0.1"/>'


def test_scene_including_its_robot_as_mujoco_reads_it(tmp_path):
    """A Menagerie-style scene: the robot in an include, meshes in meshdir, a floor."""
    (tmp_path / "robot").mkdir()
    for name in ("arm3.xml", "arm3_hand.stl"):
        shutil.copy(ARM3.parent / name, tmp_path / "robot" / name)
    robot_xml = (tmp_path / "robot" / "arm3.xml").read_text()
    robot_xml = robot_xml.replace('autolimits="true"/>', 'autolimits="true" meshdir="robot"/>')
    (tmp_path / "robot" / "arm3.xml").write_text(robot_xml)
    scene = write(
        tmp_path,
        '<mujoco model="scene"><include file="robot/arm3.xml"/>'
        f"{_FLOOR}<light pos='0 0 2'/></worldbody></mujoco>",
        "scene.xml",
    )
    robot = clik.Robot.load(scene)
    document = robot.mjcf
    assert document is not None
    assert document.files == [
        scene.resolve(),
        (tmp_path / "robot" / "arm3.xml").resolve(),
        (tmp_path / "robot" / "arm3_hand.stl").resolve(),
    ]
    arm3 = clik.Robot.load("arm3")
    assert robot.joint_names == arm3.joint_names
    np.testing.assert_array_equal(robot.q_reference, arm3.q_reference)
    names = [go.name for go in robot.collision_model.geometryObjects]
    assert names == [go.name for go in arm3.collision_model.geometryObjects]
    peer = mujoco.MjModel.from_xml_path(str(scene))
    assert peer.nq == robot.nq and peer.ngeom == len(robot.visual_model.geometryObjects) + 1


def test_root_free_joint_is_welded_with_a_warning(tmp_path):
    path = write(
        tmp_path,
        model(
            head='<compiler angle="radian"/>',
            tail='<keyframe><key name="home" qpos="0 0 1 1 0 0 0 0.5"/></keyframe>',
        ).replace('<body name="b1">', '<body name="b1" pos="0 0 1"><freejoint name="root"/>'),
    )
    with pytest.warns(FreeJointWeldedWarning, match="'root' was removed"):
        robot = clik.Robot.load(path)
    assert robot.joint_names == ["j1"]
    np.testing.assert_array_equal(robot.q_reference, [0.5])  # the key without the free joint
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.q_reference)
    np.testing.assert_allclose(data.oMf[robot.frame_id("b1")].translation, [0, 0, 1])


def test_no_home_key_gives_neutral_clipped(tmp_path):
    path = write(tmp_path, model().replace('range="-1 1"', 'range="0.2 1"'), "m.xml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = clik.Robot.load(path)
    np.testing.assert_allclose(robot.q_reference, [np.radians(0.2)])  # degrees by default


def test_a_urdf_named_xml_still_loads_as_urdf(tmp_path):
    from tests.urdf_snippets import urdf_text

    path = write(tmp_path, urdf_text(), "robot.xml")
    assert not is_mjcf(path)
    assert clik.Robot.load(path).mjcf is None


# ------------------------------------------------------------------ hostile models


def test_entity_is_refused(tmp_path):
    path = write(
        tmp_path,
        '<?xml version="1.0"?><!DOCTYPE mujoco [<!ENTITY x "0.1">]>' + model(),
    )
    error = refused(path)
    assert error.source == str(path) and "entities" in error.problem


def test_external_dtd_is_refused(tmp_path):
    path = write(tmp_path, '<!DOCTYPE mujoco SYSTEM "http://example.com/m.dtd">' + model())
    assert "external DTD" in refused(path).problem


def test_include_entity_in_an_included_file_names_that_file(tmp_path):
    inner = write(tmp_path, '<!DOCTYPE mujoco [<!ENTITY x "1">]><mujoco/>', "inner.xml")
    path = write(tmp_path, model(head='<include file="inner.xml"/>'))
    error = refused(path)
    assert error.source == str(inner) and "entities" in error.problem


def test_include_leaving_the_folder_is_refused(tmp_path):
    write(tmp_path, "<mujoco/>", "outside.xml")
    path = write(tmp_path / "robot", model(head='<include file="../outside.xml"/>'))
    error = refused(path)
    assert error.source == str(path) and error.line == 1
    assert "included file '../outside.xml' resolves to" in error.problem
    assert "leaves the model's folder" in error.problem


def test_symlinked_include_leading_out_is_refused(tmp_path):
    write(tmp_path, "<mujoco/>", "outside.xml")
    (tmp_path / "robot").mkdir()
    os.symlink(tmp_path / "outside.xml", tmp_path / "robot" / "parts.xml")
    path = write(tmp_path / "robot", model(head='<include file="parts.xml"/>'))
    assert "'parts.xml' resolves to" in refused(path).problem


def test_include_cycle_and_depth_are_refused(tmp_path, monkeypatch):
    write(tmp_path, '<mujoco><include file="b.xml"/></mujoco>', "a.xml")
    write(tmp_path, '<mujoco><include file="a.xml"/></mujoco>', "b.xml")
    path = write(tmp_path, model(head='<include file="a.xml"/>'))
    assert "included twice (or in a cycle)" in refused(path).problem
    monkeypatch.setattr(mjcf_check, "MAX_INCLUDE_DEPTH", 1)
    write(tmp_path, '<mujoco><include file="c.xml"/></mujoco>', "b.xml")
    write(tmp_path, "<mujoco/>", "c.xml")
    assert "2 levels deep, above the budget of 1" in refused(path).problem


def test_mesh_outside_the_folder_is_refused(tmp_path):
    shutil.copy(ARM3.parent / "arm3_hand.stl", tmp_path / "hand.stl")
    asset = '<asset><mesh name="hand" file="hand.stl"/></asset>'
    body = '<geom type="mesh" mesh="hand"/>'
    for head in (f'<compiler meshdir=".."/>{asset}', asset.replace("hand.stl", "../hand.stl")):
        path = write(tmp_path / "robot", model(body, head=head))
        error = refused(path)
        assert "mesh file" in error.problem and "leaves the model's folder" in error.problem
    os.symlink(tmp_path / "hand.stl", tmp_path / "robot" / "hand.stl")
    path = write(tmp_path / "robot", model(body, head=asset))
    assert "leaves the model's folder" in refused(path).problem


def test_missing_mesh_is_refused_with_its_path(tmp_path):
    path = write(tmp_path, model('<geom type="mesh" mesh="m"/>', head=_mesh("meshes/m.stl")))
    error = refused(path)
    assert "mesh file 'meshes/m.stl'" in error.problem and "not found" in error.problem


def _mesh(file: str) -> str:
    return f'<asset><mesh name="m" file="{file}"/></asset>'


def test_over_budget_file_is_refused(tmp_path, monkeypatch):
    path = write(tmp_path, model())
    monkeypatch.setattr(urdf_check, "MAX_URDF_BYTES", 100)
    error = refused(path)
    assert error.source == str(path) and "174 bytes, above the budget" in error.problem


def test_over_budget_included_file_is_refused(tmp_path, monkeypatch):
    big = write(tmp_path, "<mujoco>" + "<!-- padding -->" * 20 + "</mujoco>", "big.xml")
    path = write(tmp_path, model(head='<include file="big.xml"/>'))
    monkeypatch.setattr(urdf_check, "MAX_URDF_BYTES", len(path.read_bytes()) + 1)
    error = refused(path)
    assert error.source == str(big) and "above the budget" in error.problem


BAD = {
    "not mujoco root": ('<mujoco model="x"/>', None),
    "a second free body": (
        model().replace(
            "</worldbody>", '<body name="b9"><freejoint/><geom size="0.1"/></body></worldbody>'
        ),
        "body 'b9' has a free joint: a second free body is an object",
    ),
    "no joint": (
        model().replace('<joint name="j1" axis="0 0 1" range="-1 1"/>', ""),
        "no movable (hinge or slide) joint",
    ),
    "inverted range": (model().replace('range="-1 1"', 'range="1 -1"'), "lower > upper"),
    "non-finite pos": (model().replace('<body name="b1">', '<body name="b1" pos="0 nan 0">'),
                       "pos='0 nan 0' is not finite"),
    "pos out of range": (model().replace('<body name="b1">', '<body name="b1" pos="0 1e9 0">'),
                         "is out of range"),
    "ball joint": (model().replace('axis="0 0 1"', 'type="ball"'), "is a ball joint"),
    "frame in the world": (
        model().replace("</worldbody>", '<frame pos="1 0 0"><body name="b2"/></frame></worldbody>'),
        "<frame> directly in <worldbody> is refused",
    ),
    "hfield": (model(head='<asset><hfield name="h" file="h.png"/></asset>'), "<hfield> is refused"),
    "skin file": (model(head='<deformable><skin file="s.skn"/></deformable>'),
                  "<skin> names a file, which clik does not read"),
    "capsule without its half-length": (
        model('<geom type="capsule" size="0.02"/>'), "2 number(s) needed"
    ),
    "box without size": (model('<geom type="box"/>'), "size='' (its own or its default class's)"),
    "zero radius": (model('<geom type="sphere" size="0"/>'), "not positive"),
    "autolimits false": (  # MuJoCo's compiler's own message, at the joint's line
        model(head='<compiler autolimits="false"/>'), "joint has `range` but not `limited`"
    ),
    "obj format kept out": (model('<geom type="mesh" mesh="m"/>', head=_mesh("m.msh")), None),
}  # fmt: skip


@pytest.mark.parametrize("case", BAD)
def test_bad_model_is_refused(tmp_path, case):
    text, expected = BAD[case]
    if case == "obj format kept out":
        (tmp_path / "m.msh").write_bytes(b"\0" * 64)
        expected = "has format '.msh'"
    path = write(tmp_path, text)
    if case == "not mujoco root":  # is_mjcf(): a <mujoco> root; the rest is for check_mjcf
        path.write_text("<robot/>")
        with pytest.raises(RobotLoadError, match="expected <mujoco>"):
            check_mjcf(path)
        return
    error = refused(path)
    assert error.source == str(path)
    assert expected in error.problem, error.problem


def test_the_view_draws_every_visual_geom(arm3):
    from clik.viz.robot_layer import drawn_geometry, robot_commands

    _, parts = robot_commands(arm3, drawn_geometry(arm3, "visual"))
    assert sum(len(p) for p in parts.values()) == len(arm3.visual_model.geometryObjects) == 6


def test_geom_sizes_from_default_classes(tmp_path):
    """Sizes a geom takes from its class, its body's childclass, or the top default."""
    head = (
        '<default><geom size="0.03"/><default class="bar"><geom type="box" size="0.1 0.02 0.02"/>'
        '<default class="long"><geom type="capsule" size="0.02 0.2"/></default></default></default>'
    )
    body = (
        '<geom type="box" class="bar"/><geom class="long"/><geom type="sphere"/>'
        '<body name="b2" childclass="long"><joint name="j2"/><geom/></body>'
    )
    robot = clik.Robot.load(write(tmp_path, model(body, head=head)))
    shapes = [go.geometry for go in robot.collision_model.geometryObjects]
    assert [type(g).__name__ for g in shapes] == ["Capsule", "Box", "Capsule", "Sphere", "Capsule"]
    np.testing.assert_allclose(shapes[1].halfSide, [0.1, 0.02, 0.02])
    assert shapes[2].halfLength == shapes[4].halfLength == 0.2 and shapes[3].radius == 0.03


def test_orientations_in_degrees_match_mujoco(tmp_path):
    """Euler angles, axis-angles, quaternions in a degree model; a tilted hinge; a slide."""
    text = """<mujoco model="tilted"><worldbody>
      <body name="a" pos="0 0 0.1" euler="10 20 30">
        <joint name="h1" axis="0.3 0.4 1" range="-100 100"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02"/>
        <body name="b" pos="0.2 0 0" axisangle="1 1 0 40">
          <joint name="s1" type="slide" axis="1 0 0" range="-0.05 0.1"/>
          <geom type="box" size="0.03 0.02 0.01"/>
          <body name="c" pos="0.1 0.05 0" quat="0.9 0.1 0.3 0.2">
            <joint name="h2" axis="0 1 0" range="-45 80" pos="0.01 0 0"/>
            <geom type="sphere" size="0.02"/>
            <site name="tip" pos="0.1 0 0.02" euler="0 90 0"/>
          </body>
        </body>
      </body></worldbody></mujoco>"""
    path = write(tmp_path, text)
    robot = clik.Robot.load(path)
    peer = mujoco.MjModel.from_xml_path(str(path))
    peer_data = mujoco.MjData(peer)
    np.testing.assert_allclose(robot.lower, peer.jnt_range[:, 0], rtol=1e-15)
    np.testing.assert_allclose(robot.upper, peer.jnt_range[:, 1], rtol=1e-15)
    data = robot.model.createData()
    for q in np.random.default_rng(3).uniform(robot.lower, robot.upper, size=(10, 3)):
        peer_data.qpos[:] = q
        mujoco.mj_kinematics(peer, peer_data)
        pin.framesForwardKinematics(robot.model, data, q)
        tip = data.oMf[robot.frame_id("tip")]
        np.testing.assert_allclose(tip.translation, peer_data.site("tip").xpos, atol=FK_TOL)
        np.testing.assert_allclose(tip.rotation.ravel(), peer_data.site("tip").xmat, atol=FK_TOL)


def test_collision_geometry_sits_where_mujoco_puts_it(arm3):
    """Primitive geoms (fromto capsules included): centre and axis as MuJoCo computes them."""
    peer = mujoco.MjModel.from_xml_path(str(ARM3))
    peer_data = mujoco.MjData(peer)
    geometry = arm3.collision_model
    geometry_data = geometry.createData()
    data = arm3.model.createData()
    q = np.array([0.4, -0.3, 0.9])
    peer_data.qpos[:] = q
    mujoco.mj_kinematics(peer, peer_data)
    pin.updateGeometryPlacements(arm3.model, data, geometry, geometry_data, q)
    checked = 0
    for go, placement in zip(geometry.geometryObjects, geometry_data.oMg, strict=True):
        if go.name == "hand":
            continue  # MuJoCo moves a mesh's frame to its centre of mass
        peer_geom = peer_data.geom(go.name)
        np.testing.assert_allclose(placement.translation, peer_geom.xpos, atol=FK_TOL)
        z_axis = peer_geom.xmat.reshape(3, 3)[:, 2]
        alignment = abs(float(placement.rotation[:, 2] @ z_axis))  # the sign is free:
        assert alignment == pytest.approx(1.0, abs=FK_TOL)  # capsules and boxes are symmetric
        checked += 1
    assert checked == 4
