"""clik.model.robot and clik.model.planar_arm: loading, kinematics, lookups and input checks."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

from clik.errors import FrameNotFound, InputError, JointNotFound, RobotLoadError, UnknownRobotError
from clik.model.mimic import MimicJointWarning
from clik.model.planar_arm import planar_arm_urdf, planar_forward_kinematics, write_planar_arm
from clik.model.robot import Robot

POSITION_TOL = 1e-12  # [m], exact kinematics up to rounding
CASE_STUDY_Q0 = np.deg2rad([180.0, -30.0, -90.0, -30.0])


def tip_positions(robot: Robot, qs: np.ndarray, frame: str = "tip") -> np.ndarray:
    frame_id = robot.frame_id(frame)
    points = []
    for q in qs:
        pin.framesForwardKinematics(robot.model, robot.data, np.asarray(q, dtype=float))
        points.append(robot.data.oMf[frame_id].translation.copy())
    return np.array(points)


# --------------------------------------------------------------- the planar arm


def test_planar4r_matches_the_closed_form(planar4r):
    rng = np.random.default_rng(0)
    qs = np.array([planar4r.random_configuration(rng) for _ in range(100)])
    tips = tip_positions(planar4r, qs)
    np.testing.assert_allclose(tips[:, :2], planar_forward_kinematics([0.3] * 4, qs), atol=1e-12)
    np.testing.assert_allclose(tips[:, 2], 0.0, atol=POSITION_TOL)


def test_case_study_start_point(planar4r):
    (tip,) = tip_positions(planar4r, [CASE_STUDY_Q0])
    np.testing.assert_allclose(tip.round(4), [0.5598, -0.15, 0.0])
    np.testing.assert_allclose(planar_forward_kinematics([0.3] * 4, CASE_STUDY_Q0), tip[:2])


def test_planar4r_description(planar4r):
    assert planar4r.name == "planar4r"
    assert (planar4r.nq, planar4r.nv) == (4, 4)
    assert planar4r.joint_names == ["joint1", "joint2", "joint3", "joint4"]
    np.testing.assert_allclose(planar4r.upper, [2 * np.pi, np.pi, np.pi, np.pi])
    np.testing.assert_allclose(planar4r.lower, -planar4r.upper)
    np.testing.assert_array_equal(planar4r.q_reference, np.zeros(4))
    assert planar4r.source_path.name == "planar4r.urdf"
    assert "tip" in planar4r.frame_names


def test_planar4r_collision_capsules_are_the_link_segments(planar4r):
    """Capsule i of radius 0 spans joint i to joint i+1 (the tip for link 4)."""
    pin.framesForwardKinematics(planar4r.model, planar4r.data, CASE_STUDY_Q0)
    pin.updateGeometryPlacements(
        planar4r.model, planar4r.data, planar4r.collision_model, planar4r.collision_data
    )
    joints = [planar4r.data.oMi[i].translation for i in range(1, 5)]
    ends = [*joints[1:], planar4r.data.oMf[planar4r.frame_id("tip")].translation]
    for i, geometry in enumerate(planar4r.collision_model.geometryObjects):
        shape = geometry.geometry
        assert (type(shape).__name__, shape.radius, shape.halfLength) == ("Capsule", 0.0, 0.15)
        placement = planar4r.collision_data.oMg[i]
        half_axis = shape.halfLength * placement.rotation[:, 2]
        np.testing.assert_allclose(placement.translation - half_axis, joints[i], atol=1e-12)
        np.testing.assert_allclose(placement.translation + half_axis, ends[i], atol=1e-12)


def test_planar4r_has_coloured_visuals(planar4r):
    visuals = planar4r.visual_model.geometryObjects
    assert len(visuals) == 10  # base, 4 x (joint ball, link), tip
    # neutral tones: the 3-D view's legend colours stay for states (tests/viz/test_traps_view.py)
    assert {tuple(np.round(g.meshColor, 2)) for g in visuals} >= {(0.72, 0.72, 0.7, 1.0)}


def test_shipped_planar4r_is_the_generator_output(planar4r):
    shipped = planar4r.source_path.read_text(encoding="utf-8")
    assert planar_arm_urdf([0.3] * 4, name="planar4r") == shipped


def test_generator_round_trip(tmp_path, planar4r):
    generated = Robot.load(write_planar_arm(tmp_path / "arm.urdf", [0.3] * 4))
    rng = np.random.default_rng(1)
    qs = np.array([planar4r.random_configuration(rng) for _ in range(20)])
    np.testing.assert_allclose(tip_positions(generated, qs), tip_positions(planar4r, qs), atol=0)
    np.testing.assert_array_equal(generated.lower, planar4r.lower)


def test_generator_other_lengths_limits_and_radius(tmp_path):
    lengths = [0.5, 0.2, 0.4]
    path = write_planar_arm(
        tmp_path / "arm3.urdf", lengths, lower=[-1, -2, -3], upper=[1, 2, 3], capsule_radius=0.02
    )
    arm = Robot.load(path)
    assert (arm.name, arm.nq) == ("arm3", 3)
    np.testing.assert_array_equal(arm.upper, [1, 2, 3])
    assert [g.geometry.radius for g in arm.collision_model.geometryObjects] == [0.02] * 3
    qs = np.array([arm.random_configuration(np.random.default_rng(2)) for _ in range(10)])
    np.testing.assert_allclose(
        tip_positions(arm, qs)[:, :2], planar_forward_kinematics(lengths, qs)
    )


@pytest.mark.parametrize(
    "options, field",
    [
        ({"lengths": [0.3, -0.1]}, "lengths"),
        ({"lengths": [0.3, float("nan")]}, "lengths"),
        ({"lengths": [0.3], "lower": [1.0], "upper": [0.0]}, "lower"),
        ({"lengths": [0.3], "upper": [1.0, 2.0]}, "upper"),
        ({"lengths": [0.3], "capsule_radius": -1.0}, "capsule_radius"),
    ],
)
def test_generator_rejects_bad_input(options, field):
    with pytest.raises(InputError) as caught:
        planar_arm_urdf(**options)
    assert caught.value.field == field


def test_closed_form_shapes():
    assert planar_forward_kinematics([1.0, 1.0], [0.0, 0.0]).tolist() == [0.0, 2.0]
    np.testing.assert_allclose(
        planar_forward_kinematics([1.0, 1.0], [[np.pi / 2, 0.0], [0.0, np.pi / 2]]),
        [[2.0, 0.0], [1.0, 1.0]],
        atol=1e-15,
    )


# ------------------------------------------------------ example-robot-data robots


def test_panda_keeps_its_leader_finger_and_its_ready_pose():
    import example_robot_data

    with pytest.warns(MimicJointWarning, match="panda_finger_joint2"):
        panda8 = Robot.load("panda")  # finger 2 mimics finger 1: locked, see test_joint_kinds
    assert (panda8.nq, panda8.nv) == (8, 8)
    assert panda8.joint_names[-1] == "panda_finger_joint1"
    neutral = pin.neutral(panda8.model)
    assert neutral[3] > panda8.upper[3]  # the reason for a reference pose
    srdf = example_robot_data.load("panda").q0[:8]
    np.testing.assert_array_equal(panda8.q_reference[:7], srdf[:7])
    assert srdf[7] == 0.001 and panda8.q_reference[7] == 0.02  # finger opened: open_fingers


def test_locked_panda_has_seven_dof_and_the_ready_pose(panda):
    assert (panda.nq, panda.nv) == (7, 7)
    assert panda.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    q0 = panda.q_reference
    np.testing.assert_allclose(q0, [0.0, -0.785398, 0.0, -2.35619, 0.0, 1.5707, 0.785398])
    assert np.all((panda.lower <= q0) & (q0 <= panda.upper))
    assert len(panda.visual_model.geometryObjects) == 11  # built on first use, reduced too
    assert "panda_hand" in panda.frame_names


def test_lock_unknown_joint_lists_the_joints():
    with pytest.raises(JointNotFound) as caught:
        Robot.load("planar4r", lock={"joint9": 0.0})
    assert str(caught.value) == (
        "joint 'joint9' not found; available joints: 'joint1', 'joint2', 'joint3', 'joint4'"
    )


def test_lock_value_outside_the_limits():
    with pytest.raises(InputError, match=r"lock\['joint2'\]: expected a value within"):
        Robot.load("planar4r", lock={"joint2": 4.0})


@pytest.mark.parametrize("value", [float("nan"), "abc"])
def test_lock_value_must_be_a_number(value):
    with pytest.raises(InputError, match=r"lock\['joint1'\]: expected a value within"):
        Robot.load("planar4r", lock={"joint1": value})


def test_lock_cannot_take_every_joint():
    with pytest.raises(InputError, match="lock: expected at least one joint left free"):
        Robot.load("planar4r", lock={f"joint{i}": 0.0 for i in range(1, 5)})


def test_lock_planar_joint_reduces_the_arm(planar4r):
    three = Robot.load("planar4r", lock={"joint4": 0.5})
    assert three.joint_names == ["joint1", "joint2", "joint3"]
    q = np.array([0.1, 0.2, 0.3])
    (tip,) = tip_positions(three, [q])
    (expected,) = tip_positions(planar4r, [[0.1, 0.2, 0.3, 0.5]])
    np.testing.assert_allclose(tip, expected, atol=POSITION_TOL)


def test_ur5_loads(ur5):
    assert (ur5.nq, ur5.nv) == (6, 6)
    assert ur5.joint_names[0] == "shoulder_pan_joint"
    np.testing.assert_array_equal(ur5.q_reference, np.zeros(6))
    assert ur5.frame_id("tool0") == ur5.model.getFrameId("tool0")


def test_continuous_joints_use_cos_sin():
    pendulum = Robot.load("double_pendulum_continuous")
    assert (pendulum.nq, pendulum.nv) == (4, 2)
    q = pendulum.random_configuration(np.random.default_rng(3))
    np.testing.assert_allclose(q[0::2] ** 2 + q[1::2] ** 2, 1.0)


def test_robots_reload_independently():
    first, second = Robot.load("planar4r"), Robot.load("planar4r")
    first.model.upperPositionLimit = np.zeros(4)
    assert second.upper[0] == 2 * np.pi


# ----------------------------------------------------------------- names, errors


def test_available_names():
    names = Robot.available()
    assert names["planar4r"] == "clik: planar4r.urdf"
    assert names["panda"] == "example-robot-data: panda_description/panda.urdf"
    assert "ur5" in names


def test_unknown_robot_lists_the_names():
    with pytest.raises(UnknownRobotError) as caught:
        Robot.load("nosuchrobot")
    message = str(caught.value)
    assert message.startswith("cannot load robot nosuchrobot: no such file and no robot")
    assert "'panda'" in message and "'planar4r'" in message


def test_missing_urdf_path():
    with pytest.raises(RobotLoadError, match=r"nothere\.urdf: file not found"):
        Robot.load("nothere.urdf")


def test_invalid_urdf_is_checked_before_pinocchio(tmp_path):
    text = planar_arm_urdf([0.3, 0.3]).replace('child link="link2"', 'child link="link9"')
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(RobotLoadError, match="joint 'joint2' names child link 'link9'"):
        Robot.load(path)


def test_unknown_frame_lists_the_frames(planar4r):
    with pytest.raises(FrameNotFound) as caught:
        planar4r.frame_id("hand")
    assert str(caught.value) == (
        "frame 'hand' not found; available frames: 'universe', 'base', 'joint1', 'link1', "
        "'joint2', 'link2', 'joint3', 'link3', 'joint4', 'link4', 'tip_joint', 'tip'"
    )
    assert planar4r.frame_id("tip") == planar4r.model.nframes - 1


def test_unknown_joint(planar4r):
    assert planar4r.joint_id("joint3") == 3
    with pytest.raises(JointNotFound, match="joint 'tip_joint' not found"):
        planar4r.joint_id("tip_joint")


# ---------------------------------------------------------------- configurations


def test_q_reference_is_a_copy(planar4r):
    planar4r.q_reference[0] = 1.0
    assert planar4r.q_reference[0] == 0.0


def test_random_configuration_respects_limits_and_margin(panda):
    rng = np.random.default_rng(4)
    qs = np.array([panda.random_configuration(rng, margin=0.1) for _ in range(200)])
    assert np.all(qs >= panda.lower + 0.1) and np.all(qs <= panda.upper - 0.1)
    with pytest.raises(InputError, match="margin"):
        panda.random_configuration(rng, margin=2.0)


def test_check_configuration_converts(planar4r):
    q = planar4r.check_configuration([1, 2, 3, 4])
    assert q.dtype == float and q.tolist() == [1.0, 2.0, 3.0, 4.0]


@pytest.mark.parametrize(
    "q, got",
    [([0.0, 0.0, 0.0], "[0.0, 0.0, 0.0]"), ([0.0, np.nan, 0.0, 0.0], "nan"), ("abc", "'abc'")],
)
def test_check_configuration_rejects(planar4r, q, got):
    with pytest.raises(InputError) as caught:
        planar4r.check_configuration(q, field="scenario.q0")
    assert caught.value.field == "scenario.q0"
    assert str(caught.value).startswith(
        "scenario.q0: expected an array of 4 finite joint values [rad or m] for planar4r, got "
    )
    assert got in str(caught.value)


def test_load_warnings_point_at_the_callers_line():
    """Warnings raised deep in loading name the line that called ``Robot.load``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        Robot.load("kinova")  # its reference posture is clipped into its limits
        Robot.load("panda")  # its mimic finger locked, its leader free
    kinds = {w.category.__name__: w for w in caught}
    assert {"ReferenceClippedWarning", "MimicJointWarning"} <= set(kinds)
    for w in caught:
        assert w.filename == __file__, (w.category.__name__, w.filename)


def test_a_continuous_joints_pair_must_be_a_unit_vector(tmp_path):
    """A (cos, sin) pair far from unit would reach Pinocchio and the run diverge: refused;
    one written with few digits is normalised."""
    urdf = tmp_path / "wheel.urdf"
    urdf.write_text(
        '<robot name="wheel"><link name="a"/><link name="b"/>'
        '<joint name="j" type="continuous"><parent link="a"/><child link="b"/>'
        '<axis xyz="0 0 1"/></joint></robot>'
    )
    robot = Robot.load(urdf)
    with pytest.raises(InputError, match=r"q0: .*\(cos, sin\) pair"):
        robot.check_configuration([0.5, 0.5])
    np.testing.assert_allclose(robot.check_configuration([0.7071, 0.7071]), [0.5**0.5] * 2)
