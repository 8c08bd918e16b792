"""MJCF models on planar and floating bases, checked against MuJoCo's forward kinematics.

A small walker of our own (a torso with a ``<freejoint/>``; two legs of four hinges, hip
yaw, roll, pitch and knee, a body each, with foot sites; a three-hinge arm with a hand
site) loads with ``base="floating"`` (the free joint becomes Pinocchio's free-flyer
``root_joint``, the ``home`` key's base pose its reference), ``base="planar"`` (the key's
x, y and yaw) and ``base="fixed"`` (welded at the file's pose, warned). MuJoCo (a bench
peer) is the reference; clik never imports it.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.errors import InputError, RobotLoadError
from clik.loop.joint_speed import JointSpeed, SpeedLimitWarning
from clik.model.base import BASE_JOINT
from clik.model.mjcf_root import FreeJointWeldedWarning
from tests.base_goals import assert_feet_held_hand_tracked, feet_held_hand_line

mujoco = pytest.importorskip("mujoco")

FK_TOL = 1e-9
"""Largest difference of a frame's position [m] or rotation entry between clik and MuJoCo."""
TRACK = 1e-6
"""Largest position error [m] and rotation error [rad] of a run's tasks."""
PARITY = 1e-9
"""Largest difference between the two engines' recorded configurations."""
ENGINES = ("python", "compiled")

HINGES = [
    *(
        f"{side}_{j}"
        for side in ("left", "right")
        for j in ("hip_yaw", "hip_roll", "hip_pitch", "knee")
    ),
    "shoulder_pitch",
    "shoulder_roll",
    "elbow",
]
HOME_BASE = [0.3, -0.2, 0.74, 0.9659258, 0.0, 0.0, 0.2588190]
"""The ``home`` key's free joint: x y z [m] and quaternion w x y z (a 30 degree yaw)."""
HOME_JOINTS = [0.5, 0.3, -0.6, 1.0, -0.5, -0.3, -0.2, 0.6, 0.3, 0.2, -0.9]
"""Legs turned out and one foot ahead: both feet's pose rows (12) independent on the base's 6
and the legs' 8 freedoms (symmetric legs would be singular: parallel hip and knee axes)."""

WALKER = """<mujoco model="walker">
  <compiler angle="radian" autolimits="true"/>
  <default>
    <joint damping="0.1"/>
    <geom type="capsule" size="0.04"/>
  </default>
  <worldbody>
    <body name="torso" pos="0.1 0.2 0.8" quat="0.9961947 0 0.0871557 0">
      <freejoint name="float"/>
      <geom name="torso" type="box" size="0.1 0.15 0.2"/>
      {legs}
      <body name="shoulder" pos="0.05 -0.2 0.15">
        <joint name="shoulder_pitch" axis="0 1 0" range="-2 2"/>
        <geom type="sphere" size="0.04"/>
        <body name="upper_arm">
        <joint name="shoulder_roll" axis="1 0 0" range="-1 1"/>
        <geom fromto="0 0 0 0 0 -0.25"/>
        <body name="forearm" pos="0 0 -0.25" euler="0.1 0 0.2">
          <joint name="elbow" axis="0 1 0" range="-2.3 0.1"/>
          <geom fromto="0 0 0 0.25 0 0" size="0.03"/>
          <site name="hand" pos="0.27 0 0"/>
        </body>
        </body>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="home" qpos="{home}"/>
  </keyframe>
</mujoco>
"""

LEG = """<body name="{side}_hip" pos="0 {y} -0.2">
        <joint name="{side}_hip_yaw" axis="0 0 1" range="-0.8 0.8"/>
        <geom type="sphere" size="0.05"/>
        <body name="{side}_pelvis" pos="0 0 -0.05">
          <joint name="{side}_hip_roll" axis="1 0 0" range="-0.5 0.5"/>
          <geom type="sphere" size="0.04"/>
          <body name="{side}_thigh">
            <joint name="{side}_hip_pitch" axis="0 1 0" range="-1.5 1"/>
            <geom fromto="0 0 0 0 0 -0.3"/>
            <body name="{side}_shin" pos="0 0 -0.3">
              <joint name="{side}_knee" axis="0 1 0" range="0 2.2"/>
              <geom fromto="0 0 0 0 0 -0.3" size="0.035"/>
              <site name="{side}_foot" pos="0.02 0 -0.32" quat="0.9 0 0.1 0"/>
            </body>
          </body>
        </body>
      </body>"""

SPEED = JointSpeed(velocity={name: 3.0 for name in HINGES})
"""MJCF gives no joint velocity limits: the runs give theirs (the base has its own)."""


def walker_text(home: list[float] | None = None) -> str:
    legs = "\n      ".join(LEG.format(side=s, y=y) for s, y in (("left", 0.1), ("right", -0.1)))
    values = HOME_BASE + HOME_JOINTS if home is None else home
    return WALKER.format(legs=legs, home=" ".join(repr(v) for v in values))


@pytest.fixture(scope="module")
def walker_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("walker") / "walker.xml"
    path.write_text(walker_text())
    return path


@pytest.fixture(scope="module")
def floating(walker_path: Path) -> clik.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no FreeJointWeldedWarning: the base stays free
        return clik.Robot.load(walker_path, base="floating")


def mujoco_placements(path: Path, qpos: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every body's and site's world position [m] and rotation (MuJoCo's forward kinematics)."""
    peer = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(peer)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(peer, data)
    out = {peer.body(i).name: (data.xpos[i], data.xmat[i]) for i in range(1, peer.nbody)}
    out.update(
        {peer.site(i).name: (data.site_xpos[i], data.site_xmat[i]) for i in range(peer.nsite)}
    )
    return out


def assert_fk_matches(robot: clik.Robot, q: np.ndarray, path: Path, qpos: np.ndarray) -> None:
    """clik's frames at ``q`` where MuJoCo puts its bodies and sites at ``qpos``."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    expected = mujoco_placements(path, qpos)
    assert len(expected) == 15  # 12 bodies, 3 sites
    for name, (position, rotation) in expected.items():
        placement = data.oMf[robot.frame_id(name)]
        np.testing.assert_allclose(placement.translation, position, atol=FK_TOL, err_msg=name)
        np.testing.assert_allclose(placement.rotation.ravel(), rotation, atol=FK_TOL, err_msg=name)


def mujoco_qpos(q: np.ndarray) -> np.ndarray:
    """MuJoCo's qpos of a floating walker's configuration: the quaternion's w first."""
    x, y, z, qx, qy, qz, qw = q[:7]
    return np.concatenate([[x, y, z, qw, qx, qy, qz], q[7:]])


# ------------------------------------------------------------------ floating


def test_floating_base_is_the_root_joint_at_the_home_key(floating):
    assert floating.base == "floating"
    assert floating.joint_names == [BASE_JOINT, *HINGES]
    assert floating.joint_kinds[BASE_JOINT] == "free-flyer"
    assert floating.nq == 7 + len(HINGES) and floating.nv == 6 + len(HINGES)
    x, y, z, w, qx, qy, qz = HOME_BASE
    norm = np.linalg.norm([w, qx, qy, qz])
    expected = np.array([x, y, z, qx / norm, qy / norm, qz / norm, w / norm, *HOME_JOINTS])
    np.testing.assert_allclose(floating.q_reference, expected, atol=1e-15)


def test_floating_forward_kinematics_match_mujoco(floating, walker_path):
    """At the reference (MuJoCo's home key), then at random base poses and joints."""
    peer = mujoco.MjModel.from_xml_path(str(walker_path))
    assert_fk_matches(floating, floating.q_reference, walker_path, peer.key_qpos[0])
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = pin.randomConfiguration(
            floating.model,
            np.concatenate([[-1.0] * 7, floating.lower[7:]]),
            np.concatenate([[1.0] * 7, floating.upper[7:]]),
        )
        q[7:] = rng.uniform(floating.lower[7:], floating.upper[7:])
        assert_fk_matches(floating, q, walker_path, mujoco_qpos(q))


def test_without_a_key_the_base_starts_where_the_file_puts_the_body(tmp_path):
    path = tmp_path / "walker.xml"
    text = walker_text()
    path.write_text(text[: text.index("<keyframe>")] + "</mujoco>\n")
    robot = clik.Robot.load(path, base="floating")
    peer = mujoco.MjModel.from_xml_path(str(path))
    np.testing.assert_allclose(mujoco_qpos(robot.q_reference), peer.qpos0, atol=1e-7)
    assert_fk_matches(robot, robot.q_reference, path, peer.qpos0)


def test_visual_geometry_sits_where_mujoco_puts_it(floating, walker_path):
    peer = mujoco.MjModel.from_xml_path(str(walker_path))
    peer_data = mujoco.MjData(peer)
    peer_data.qpos[:] = peer.key_qpos[0]
    mujoco.mj_kinematics(peer, peer_data)
    visual = floating.visual_model
    visual_data = visual.createData()
    data = floating.model.createData()
    pin.updateGeometryPlacements(floating.model, data, visual, visual_data, floating.q_reference)
    torso = [k for k, go in enumerate(visual.geometryObjects) if go.name == "torso"]
    assert len(torso) == 1 and len(visual.geometryObjects) == peer.ngeom
    placement = visual_data.oMg[torso[0]]
    np.testing.assert_allclose(placement.translation, peer_data.geom("torso").xpos, atol=FK_TOL)
    np.testing.assert_allclose(
        placement.rotation.ravel(), peer_data.geom("torso").xmat, atol=FK_TOL
    )


def test_base_speed_and_the_joints_velocity_warning(walker_path):
    robot = clik.Robot.load(walker_path, base="floating", base_speed=[0.5, 0.8])
    limits = np.asarray(robot.model.velocityLimit)
    np.testing.assert_array_equal(limits[:6], [0.5, 0.5, 0.5, 0.8, 0.8, 0.8])
    with pytest.warns(SpeedLimitWarning, match="MJCF gives no joint velocity limits") as caught:
        bounds = JointSpeed().bounds(robot)
    assert bounds is not None and sorted(bounds.unlimited) == sorted(HINGES)
    assert BASE_JOINT not in str(caught[0].message)
    speeds = np.array([0.5, 0.5, 0.5, 0.8, 0.8, 0.8]) * bounds.settings.scale
    np.testing.assert_allclose(bounds.velocity[:6], speeds, rtol=1e-15)


def test_lock_keeps_the_base_and_refuses_locking_it(walker_path):
    robot = clik.Robot.load(walker_path, base="floating", lock={"elbow": -0.9})
    assert robot.joint_names == [BASE_JOINT, *HINGES[:-1]]
    peer = mujoco.MjModel.from_xml_path(str(walker_path))
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.q_reference)
    hand = mujoco_placements(walker_path, peer.key_qpos[0])["hand"][0]
    np.testing.assert_allclose(data.oMf[robot.frame_id("hand")].translation, hand, atol=FK_TOL)
    with pytest.raises(InputError) as caught:
        clik.Robot.load(walker_path, base="floating", lock={BASE_JOINT: 0.0})
    assert caught.value.field == f"lock[{BASE_JOINT!r}]"


def test_a_key_without_a_value_per_joint_is_refused(tmp_path):
    path = tmp_path / "walker.xml"
    path.write_text(walker_text(HOME_BASE + HOME_JOINTS[:-1]))
    with pytest.raises(RobotLoadError, match="'home' has 10 qpos values for the joints after"):
        clik.Robot.load(path, base="floating")
    path.write_text(walker_text(HOME_BASE[:5]))
    with pytest.raises(RobotLoadError, match="5 qpos values: the free joint alone needs 7"):
        clik.Robot.load(path, base="floating")


# ------------------------------------------------------------------ planar and fixed


def test_planar_base_keeps_the_keys_x_y_and_yaw(walker_path):
    robot = clik.Robot.load(walker_path, base="planar")
    assert robot.base == "planar" and robot.joint_names == [BASE_JOINT, *HINGES]
    yaw = 2.0 * np.arctan2(HOME_BASE[6], HOME_BASE[3])  # the key's quaternion: about z
    np.testing.assert_allclose(robot.q_reference[:4], [0.3, -0.2, np.cos(yaw), np.sin(yaw)])
    np.testing.assert_allclose(robot.q_reference[4:], HOME_JOINTS)
    peer = mujoco.MjModel.from_xml_path(str(walker_path))
    assert_fk_matches(robot, robot.q_reference, walker_path, peer.key_qpos[0])
    # the base moved in the plane: MuJoCo's free joint at the same x, y, yaw, height kept
    q = robot.q_reference.copy()
    turn = yaw + 0.7
    q[:4] = [1.0, 0.5, np.cos(turn), np.sin(turn)]
    qpos = peer.key_qpos[0].copy()
    qpos[:3] = [1.0, 0.5, HOME_BASE[2]]
    qpos[3:7] = [np.cos(turn / 2), 0.0, 0.0, np.sin(turn / 2)]
    assert_fk_matches(robot, q, walker_path, qpos)


def test_planar_base_with_a_tilted_body_keeps_its_tilt(tmp_path):
    """A key with roll and pitch: they stay between the planar joint and the torso."""
    path = tmp_path / "walker.xml"
    tilted = pin.Quaternion(pin.rpy.rpyToMatrix(0.1, -0.2, 1.1))  # roll, pitch, yaw
    home = [0.4, 0.1, 0.7, tilted.w, tilted.x, tilted.y, tilted.z, *HOME_JOINTS]
    path.write_text(walker_text(home))
    robot = clik.Robot.load(path, base="planar")
    np.testing.assert_allclose(robot.q_reference[:4], [0.4, 0.1, np.cos(1.1), np.sin(1.1)])
    assert_fk_matches(robot, robot.q_reference, path, np.array(home))


def test_fixed_base_welds_the_body_where_the_file_places_it(walker_path):
    with pytest.warns(FreeJointWeldedWarning, match="'float' was removed.*base=\"floating\""):
        robot = clik.Robot.load(walker_path)
    assert robot.base == "fixed" and robot.joint_names == HINGES
    np.testing.assert_allclose(robot.q_reference, HOME_JOINTS)  # the key's base values dropped
    peer = mujoco.MjModel.from_xml_path(str(walker_path))
    qpos = np.concatenate([peer.qpos0[:7], HOME_JOINTS])  # the file's pose of the torso
    assert_fk_matches(robot, robot.q_reference, walker_path, qpos)


def test_fixed_base_without_a_free_joint_keeps_the_root_body_pose(tmp_path):
    """A root body without joints, placed by pos and euler: Pinocchio alone drops its pose."""
    path = tmp_path / "arm.xml"
    text = walker_text().replace('angle="radian"', 'angle="radian" eulerseq="zyx"')
    text = text.replace('<freejoint name="float"/>', "")
    text = text.replace('quat="0.9961947 0 0.0871557 0"', 'euler="0.3 0.2 0.1"')
    path.write_text(text.replace(" ".join(repr(v) for v in HOME_BASE) + " ", ""))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = clik.Robot.load(path)
    peer = mujoco.MjModel.from_xml_path(str(path))
    assert peer.nq == robot.nq
    assert_fk_matches(robot, robot.q_reference, path, peer.key_qpos[0])


# ------------------------------------------------------------------ a run


@pytest.fixture(scope="module")
def runs(floating):
    q0 = floating.q_reference
    goals = feet_held_hand_line(
        floating, q0, ("left_foot", "right_foot"), "hand", [0.05, 0.05, 0.05], 1.0
    )
    results = {
        engine: clik.track(
            tasks=goals, q0=q0, law="pseudoinverse", gain=500, joint_speed=SPEED, engine=engine
        )
        for engine in ENGINES
    }
    return goals, results


@pytest.mark.parametrize("engine", ENGINES)
def test_feet_held_while_the_hand_tracks_a_line(floating, runs, engine):
    goals, results = runs
    result = results[engine]
    assert_feet_held_hand_tracked(result, floating, TRACK, moved=0.01)  # [m]: the torso
    # MuJoCo's forward kinematics of the recorded configurations: the feet never moved
    peer = mujoco.MjModel.from_xml_path(str(floating.source_path))
    data = mujoco.MjData(peer)
    for q in result.q[:: max(1, len(result.q) // 10)]:
        data.qpos[:] = mujoco_qpos(q)
        mujoco.mj_kinematics(peer, data)
        for goal in goals[:2]:
            site = data.site(goal.task.frame)
            hold = goal.trajectory
            assert np.linalg.norm(site.xpos - hold.position) <= TRACK
            rotation = pin.log3(hold.rotation.T @ site.xmat.reshape(3, 3))
            assert np.linalg.norm(rotation) <= TRACK


def test_the_engines_agree(runs):
    _, results = runs
    assert results["python"].status == results["compiled"].status == "completed"
    assert results["python"].q.shape == results["compiled"].q.shape
    assert np.abs(results["python"].q - results["compiled"].q).max() <= PARITY
