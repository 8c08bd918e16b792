"""MJCF as MuJoCo reads it: a corpus of files, each compared with MuJoCo's compiled model.

Each file reproduces a case that clik once read wrong or refused (issue 44): geom
poses and mesh scales inherited from default classes, ``quat="0 0 0 1"`` (a half
turn: MuJoCo writes ``w`` first), a body with several joints, joint ``ref``, an
extrinsic ``eulerseq``, a ``<frame>`` in a body, a ball joint (refused, naming its
body), a missing visual-only mesh (a warning). Every body and site is compared with
MuJoCo's forward kinematics (1e-9 m), every collision geom's placement too (1e-9 m),
and distances from probe spheres with ``mj_geomDistance`` (1e-6 m, through
``benchmarks/mjcf_agreement.py``, which also takes random configurations).
"""

from __future__ import annotations

import struct
import warnings
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest

import clik
from benchmarks.mjcf_agreement import agreement
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.errors import RobotLoadError
from clik.loop.joint_speed import JointSpeed
from clik.model.visual_meshes import MissingVisualMeshWarning
from clik.trajectory import Line
from tests.limits_check import assert_completed

mujoco = pytest.importorskip("mujoco")

FK_TOL = 1e-9
"""Largest position difference [m] (and rotation entry difference) with MuJoCo."""

PROBE_TOL = 1e-6
"""Largest difference [m] between clik's and MuJoCo's probe-sphere distances."""


def stl_box(path: Path, size: tuple[float, float, float], offset: tuple[float, float, float]):
    """A binary STL box of ``size`` (its unit: the file's) centred at ``offset``."""
    c = np.array(offset, dtype=float)
    h = np.array(size, dtype=float) / 2.0
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    v = c + corners * h
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    data = bytearray(b"\0" * 80) + struct.pack("<I", len(faces))
    for a, b, d in faces:
        data += struct.pack("<12fH", 0, 0, 0, *v[a], *v[b], *v[d], 0)
    path.write_bytes(bytes(data))


def mujoco_file(folder: Path, body: str, head: str = "", name: str = "model.xml") -> Path:
    path = folder / name
    path.write_text(f'<mujoco model="corpus">{head}<worldbody>{body}</worldbody></mujoco>')
    return path


CASES = {
    "geom pose from default classes": (
        '<compiler angle="radian"/><default>'
        '<default class="link"><geom type="capsule" size="0.03 0.1" pos="0 0 0.1"'
        ' quat="0.9238795 0.3826834 0 0"/></default>'
        '<default class="foot"><geom type="sphere" size="0.02" pos="0.01 0 -0.2"/></default>'
        "</default>",
        '<body name="b1" childclass="link"><joint name="j1" axis="0 0 1" range="-2 2"/>'
        '<geom name="g1"/><body name="b2" pos="0 0 0.2">'
        '<joint name="j2" axis="0 1 0" range="-2 2"/><geom name="g2"/>'
        '<geom name="foot" class="foot"/><site name="tip" pos="0 0 0.3"/></body></body>',
    ),
    "mesh scale from the default class": (
        '<default><mesh scale="0.001 0.001 0.001"/></default>'
        '<asset><mesh name="block" file="block_mm.stl"/></asset>',
        '<body name="b1"><joint name="j1" axis="0 0 1" range="-2 2"/>'
        '<geom name="block" type="mesh" mesh="block"/><site name="tip" pos="0.1 0 0"/></body>',
    ),
    "w-first half-turn quaternions": (
        "",
        '<body name="b1" pos="0.1 0 0.2" quat="0 0 0 1"><joint name="j1" axis="0 1 0"/>'
        '<geom name="arm" type="box" size="0.1 0.02 0.03" pos="0.1 0 0" quat="0 0 0 1"/>'
        '<body name="b2" pos="0.2 0 0" quat="0 1 0 0"><joint name="j2" axis="0 0 1"/>'
        '<geom name="tip" type="cylinder" size="0.02 0.05" pos="0 0.05 0" quat="0 0 1 0"/>'
        '<site name="tool" pos="0 0 0.1" quat="0 0 0 1"/></body></body>',
    ),
    "a body with several joints": (
        '<compiler angle="radian"/>',
        '<body name="base" pos="0 0 0.1"><joint name="x" type="slide" axis="1 0 0" range="-1 1"/>'
        '<joint name="y" type="slide" axis="0 1 0" range="-1 1" ref="0.2"/>'
        '<joint name="yaw" axis="0 0 1" pos="0.05 0.02 0" range="-3 3" ref="0.4"/>'
        '<geom name="chassis" type="box" size="0.2 0.15 0.05" pos="0.03 0 0"/>'
        '<body name="arm" pos="0.1 0 0.1"><joint name="lift" axis="0 1 0" range="-1 1"/>'
        '<geom name="arm" type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>'
        '<site name="tool" pos="0.3 0 0"/></body></body>',
    ),
    "extrinsic euler, frames and joint ref": (
        '<compiler angle="degree" eulerseq="XYZ"/>',
        '<body name="b1" euler="10 20 30"><joint name="j1" axis="1 1 0" range="-90 90" ref="15"/>'
        '<geom name="g1" type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/>'
        '<frame pos="0 0 0.2" euler="0 40 0"><body name="b2"><joint name="j2" axis="0 0 1"'
        ' type="slide" range="-0.1 0.1"/><geom name="g2" type="ellipsoid" size="0.03 0.02 0.01"/>'
        '<site name="tip" pos="0.05 0 0" euler="90 0 0"/></body></frame></body>',
    ),
    "two arms on the world, a primitive fitted to a mesh": (
        '<asset><mesh name="block" file="block_mm.stl" scale="0.001 0.001 0.001"/></asset>',
        '<body name="left" pos="0 0.3 0"><joint name="l1" axis="0 0 1" range="-2 2"/>'
        '<geom name="left_link" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>'
        '<site name="left_tool" pos="0.3 0 0"/></body>'
        '<body name="right" pos="0 -0.3 0" quat="0 0 0 1"><joint name="r1" axis="0 1 0"/>'
        '<geom name="right_link" type="capsule" mesh="block"/>'
        '<site name="right_tool" pos="0.3 0 0"/></body>'
        '<body name="marker" pos="1 0 0"><site name="marker_point"/></body>',
    ),
}  # fmt: skip
"""Case -> (head: compiler, defaults, assets; the world's bodies)."""


def write_case(folder: Path, case: str) -> Path:
    head, body = CASES[case]
    stl_box(folder / "block_mm.stl", (60.0, 20.0, 40.0), (80.0, 5.0, -10.0))
    return mujoco_file(folder, body, head)


def assert_like_mujoco(robot: clik.Robot, path: Path, q: np.ndarray) -> int:
    """Every body, site and collision geom at MuJoCo's pose for ``q``; geoms compared."""
    peer = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(peer)
    data.qpos[:] = q
    mujoco.mj_kinematics(peer, data)
    pdata = robot.model.createData()
    pin.framesForwardKinematics(robot.model, pdata, q)
    named = [(peer.body(b).name, data.xpos[b], data.xmat[b]) for b in range(1, peer.nbody)]
    named += [(peer.site(s).name, data.site_xpos[s], data.site_xmat[s]) for s in range(peer.nsite)]
    for name, position, rotation in named:
        frame = pdata.oMf[robot.model.getFrameId(name)]
        np.testing.assert_allclose(frame.translation, position, atol=FK_TOL, err_msg=name)
        np.testing.assert_allclose(frame.rotation.ravel(), rotation, atol=FK_TOL, err_msg=name)
    geometry = robot.collision_model
    gdata = geometry.createData()
    pin.updateGeometryPlacements(robot.model, pdata, geometry, gdata, q)
    for go, placement in zip(geometry.geometryObjects, gdata.oMg, strict=True):
        geom = data.geom(go.name)
        np.testing.assert_allclose(placement.translation, geom.xpos, atol=FK_TOL, err_msg=go.name)
        np.testing.assert_allclose(placement.rotation.ravel(), geom.xmat, atol=FK_TOL)
    return len(geometry.geometryObjects)


@pytest.mark.parametrize("case", CASES)
def test_the_corpus_loads_as_mujoco_compiles_it(tmp_path, case):
    path = write_case(tmp_path, case)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about in these files
        robot = clik.Robot.load(path)
    peer = mujoco.MjModel.from_xml_path(str(path))
    assert robot.nq == peer.nq and robot.joint_names == [
        peer.joint(j).name for j in range(peer.njnt)
    ]
    np.testing.assert_allclose(robot.q_reference, np.clip(peer.qpos0, robot.lower, robot.upper))
    rng = np.random.default_rng(44)
    low, high = np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi)
    for q in [robot.q_reference, *rng.uniform(low, high, size=(4, robot.nq))]:
        compared = assert_like_mujoco(robot, path, q)
    assert compared == sum(
        1 for g in range(peer.ngeom) if peer.geom_contype[g] or peer.geom_conaffinity[g]
    )
    found = agreement(path, "fixed")
    assert found["clik"] == "ok" and found["mujoco"] == "ok", found
    assert found["fk_position_m"] <= FK_TOL and found["fk_rotation_rad"] <= FK_TOL, found
    assert found["geoms_compared"] == compared, found["notes"]
    assert found["geom_placement_m"] <= FK_TOL, found
    if found["probes"]:  # ellipsoids have no convex shape in clik's scene: no probe
        assert found["probe_distance_m"] <= PROBE_TOL, found


def test_mesh_scale_from_the_default_class_is_applied(tmp_path):
    """A 60 x 20 x 40 mm box in a file in millimetres, scaled by the default class."""
    robot = clik.Robot.load(write_case(tmp_path, "mesh scale from the default class"))
    block = robot.collision_model.geometryObjects[0]
    vertices = np.asarray(block.geometry.vertices())
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    np.testing.assert_allclose(np.sort(extent), [0.02, 0.04, 0.06], atol=1e-12)
    centre = block.placement.act(vertices.mean(axis=0))  # in the body's frame
    np.testing.assert_allclose(centre, [0.08, 0.005, -0.01], atol=1e-12)


def test_a_half_turn_quaternion_is_not_zero(tmp_path):
    robot = clik.Robot.load(write_case(tmp_path, "w-first half-turn quaternions"))
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, np.zeros(2))
    b1 = data.oMf[robot.model.getFrameId("b1")]
    np.testing.assert_allclose(b1.rotation, np.diag([-1.0, -1.0, 1.0]), atol=1e-15)


def test_a_quaternion_of_zeros_is_refused(tmp_path):
    path = mujoco_file(
        tmp_path, '<body name="b1" quat="0 0 0 0"><joint name="j1"/><geom size="0.1"/></body>'
    )
    with pytest.raises(RobotLoadError, match=r"quat=\[0.0, 0.0, 0.0, 0.0\] is zero") as caught:
        clik.Robot.load(path)
    assert caught.value.line == 1


def test_a_body_with_several_joints_is_a_chain(tmp_path):
    robot = clik.Robot.load(write_case(tmp_path, "a body with several joints"))
    assert robot.joint_names == ["x", "y", "yaw", "lift"]
    kinds = [j.shortname() for j in robot.model.joints[1:]]
    assert kinds == ["JointModelPX", "JointModelPY", "JointModelRZ", "JointModelRY"]
    np.testing.assert_allclose(robot.q_reference, [0.0, 0.2, 0.4, 0.0])  # MuJoCo's qpos0


def test_two_arms_need_a_fixed_base(tmp_path):
    path = write_case(tmp_path, "two arms on the world, a primitive fitted to a mesh")
    fitted = clik.Robot.load(path).collision_model.geometryObjects[1].geometry
    assert isinstance(fitted, coal.Capsule) and fitted.radius > 0.005  # MuJoCo's fit
    with pytest.raises(RobotLoadError, match="a floating base moves one root body"):
        clik.Robot.load(path, base="floating")


def test_a_ball_joint_is_refused_naming_its_body(tmp_path):
    body = (
        '<body name="b1"><joint name="j1" axis="0 0 1"/><geom size="0.1"/>'
        '<body name="wrist" pos="0 0 0.2">\n<joint name="w" type="ball"/><geom size="0.05"/>'
        "</body></body>"
    )
    with pytest.raises(RobotLoadError) as caught:
        clik.Robot.load(mujoco_file(tmp_path, body))
    error = caught.value
    assert "<joint> 'w' of body 'wrist' is a ball joint" in error.problem
    assert "three hinges" in error.problem and error.line == 2


def test_a_missing_visual_mesh_is_a_warning(tmp_path):
    stl_box(tmp_path / "block.stl", (0.06, 0.02, 0.04), (0.0, 0.0, 0.0))
    head = (
        '<asset><mesh name="block" file="block.stl"/><mesh name="shell" file="shell.stl"/></asset>'
    )
    body = (
        '<body name="b1"><joint name="j1" axis="0 0 1"/>'
        '<geom name="block" type="mesh" mesh="block"/>'
        '<geom name="shell" type="mesh" mesh="shell" contype="0" conaffinity="0"/></body>'
    )
    path = mujoco_file(tmp_path, body, head)
    with pytest.warns(
        MissingVisualMeshWarning, match=r"body 'b1': visual mesh 'shell.stl' not found"
    ):
        robot = clik.Robot.load(path)
    assert [go.name for go in robot.visual_model.geometryObjects] == ["block"]
    assert [go.name for go in robot.collision_model.geometryObjects] == ["block"]
    touching = path.read_text().replace(' contype="0" conaffinity="0"', "")
    path.write_text(touching)  # the same mesh, now one that can touch: refused
    with pytest.raises(RobotLoadError, match=r"shell\.stl.*not found.*a geom that can touch"):
        clik.Robot.load(path)


def test_a_compiler_refusal_names_the_users_file_and_line(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "arm.xml").write_text(
        '<mujoco>\n<worldbody>\n<body name="b1">\n<joint name="j1" axis="0 0 1"/>\n'
        '<geom type="mesh" mesh="nothing"/>\n</body>\n</worldbody>\n</mujoco>'
    )
    path = tmp_path / "scene.xml"
    path.write_text('<mujoco>\n\n<include file="parts/arm.xml"/>\n</mujoco>')
    with pytest.raises(RobotLoadError) as caught:
        clik.Robot.load(path)
    assert caught.value.source == str(tmp_path / "parts" / "arm.xml")
    assert caught.value.line == 5 and "MuJoCo's compiler refuses" in caught.value.problem


SPEED = JointSpeed(velocity={"x": 0.5, "y": 0.5, "yaw": 2.0, "lift": 2.0})
"""MJCF gives no velocity limits: the test gives one (no SpeedLimitWarning)."""


def test_the_several_joints_body_tracks_past_an_obstacle_in_both_engines(tmp_path):
    robot = clik.Robot.load(write_case(tmp_path, "a body with several joints"))
    task = clik.Task(robot, "tool", "position")
    start = task.placement(robot.q_reference).translation
    line = Line(start, start + np.array([0.3, 0.2, 0.05]), duration=2.0)
    post = Obstacle("post", "sphere", [0.35, 0.3, 0.2], radius=0.04)
    results = {}
    for engine in ("python", "compiled"):
        cset = ConstraintSet(
            robot, obstacles=[post], obstacle_threshold=0.05,
            joint_limits=JointLimits(robot, 0.05),
        )  # fmt: skip
        result = clik.track(task, line, constraints=cset, engine=engine, joint_speed=SPEED)
        assert_completed(result, robot)
        assert np.nanmin(result.min_obstacle_distance) >= 0.0
        actions = {(e["constraint"], e["action"]) for e in result.events}
        assert ("obstacle:post:base", "activate") in actions, actions  # the chassis met it
        results[engine] = result
    np.testing.assert_allclose(results["python"].q, results["compiled"].q, atol=1e-9)


def test_equality_constraints_are_named_as_not_applied(tmp_path):
    body = (
        '<body name="b1"><joint name="j1" axis="0 0 1"/><geom size="0.1"/>'
        '<body name="b2" pos="0 0 0.2"><joint name="j2" axis="0 1 0"/><geom size="0.05"/>'
        "</body></body>"
    )
    tail = (
        '<equality><joint joint1="j1" joint2="j2"/>'
        '<connect body1="b1" body2="b2" anchor="0 0 0.1"/></equality>'
    )
    path = tmp_path / "coupled.xml"
    path.write_text(f'<mujoco model="c"><worldbody>{body}</worldbody>{tail}</mujoco>')
    with pytest.warns(
        clik.EqualityIgnoredWarning, match=r"2 <equality> constraint\(s\) \(1 joint, 1 connect\)"
    ):
        robot = clik.Robot.load(path)
    assert robot.joint_names == ["j1", "j2"]  # still two independent joints


def test_a_site_named_like_its_body_is_its_own_frame(tmp_path):
    body = (
        '<body name="b1"><joint name="j1"/><geom size="0.1"/>'
        '<body name="tip" pos="0.2 0 0"><site name="tip" pos="0.1 0 0"/></body></body>'
    )
    robot = clik.Robot.load(mujoco_file(tmp_path, body))
    tip = clik.Task(robot, "tip", "position").placement(robot.q_reference).translation
    site = clik.Task(robot, "tip_site", "position").placement(robot.q_reference).translation
    np.testing.assert_allclose(tip, [0.2, 0.0, 0.0], atol=1e-15)  # the body keeps the name
    np.testing.assert_allclose(site, [0.3, 0.0, 0.0], atol=1e-15)
