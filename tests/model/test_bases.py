"""Mobile and floating bases (issue 26, part 3): loading, configurations, limits.

A planar base (tiago, arm and torso only) and a floating base (talos) as the first
joint of the model: sizes, names, units, speed limits, the SRDF posture, user values,
joint ranges, the scenario keys and the export's refusal.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.constraints.joint_limits import JointLimits
from clik.errors import ExportError, InputError, ScenarioError
from clik.model.base import (
    BASE_JOINT,
    DEFAULT_ANGULAR_SPEED,
    DEFAULT_LINEAR_SPEED,
    base_speed,
    check_base_speed,
    planar_from_free_flyer,
)
from clik.outputs.export import check_exportable
from clik.scenarios.scenario import parse_scenario
from clik.viz.timeline import joint_placements

TIAGO_ARM = {"torso_lift_joint"} | {f"arm_{i}_joint" for i in range(1, 8)}


def tiago_lock() -> dict[str, float]:
    """Every tiago joint but the torso and the arm, locked at 0."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        names = clik.Robot.load("tiago").joint_names
    return {n: 0.0 for n in names if n not in TIAGO_ARM}


@pytest.fixture(scope="module")
def lock() -> dict[str, float]:
    return tiago_lock()


@pytest.fixture(scope="module")
def tiago(lock: dict[str, float]) -> clik.Robot:
    return clik.Robot.load("tiago", lock=lock, base="planar")


@pytest.fixture(scope="module")
def tiago_fixed(lock: dict[str, float]) -> clik.Robot:
    return clik.Robot.load("tiago", lock=lock)


@pytest.fixture(scope="module")
def talos() -> clik.Robot:
    return clik.Robot.load("talos", base="floating")


@pytest.fixture(scope="module")
def talos_fixed() -> clik.Robot:
    return clik.Robot.load("talos")


def test_planar_base_is_the_first_joint(tiago: clik.Robot, tiago_fixed: clik.Robot) -> None:
    assert tiago.base == "planar" and tiago_fixed.base == "fixed"
    assert tiago.joint_names == [BASE_JOINT, *tiago_fixed.joint_names]
    assert (tiago.nq, tiago.nv) == (tiago_fixed.nq + 4, tiago_fixed.nv + 3)
    assert tiago.joint_kinds[BASE_JOINT] == "planar"
    assert tiago.q_units[:5] == ["m", "m", "", "", "m"]  # x, y, cos, sin, then the torso
    assert tiago.q_joint_names[:4] == [BASE_JOINT] * 4
    np.testing.assert_array_equal(tiago.q_reference[:4], [0.0, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(tiago.q_reference[4:], tiago_fixed.q_reference)
    # the collision model is built on the model with the base: the same geometry, the root
    # link's now carried by the base joint instead of the world
    assert tiago.collision_model.ngeoms == tiago_fixed.collision_model.ngeoms
    on_world = [g.name for g in tiago_fixed.collision_model.geometryObjects if g.parentJoint == 0]
    assert on_world
    by_name = {g.name: g for g in tiago.collision_model.geometryObjects}
    assert all(by_name[name].parentJoint == 1 for name in on_world)


def test_base_speed_limits_default_and_given(tiago: clik.Robot, lock: dict[str, float]) -> None:
    vmax = np.asarray(tiago.model.velocityLimit)
    np.testing.assert_array_equal(vmax[:3], [DEFAULT_LINEAR_SPEED] * 2 + [DEFAULT_ANGULAR_SPEED])
    assert base_speed(tiago.model) == (1.0, 1.0)
    slow = clik.Robot.load("tiago", lock=lock, base="planar", base_speed=[0.4, 0.25])
    np.testing.assert_array_equal(np.asarray(slow.model.velocityLimit)[:3], [0.4, 0.4, 0.25])
    np.testing.assert_array_equal(slow.model.velocityLimit[3:], tiago.model.velocityLimit[3:])
    speeds = clik.JointSpeed().bounds(slow, warn=False)
    assert speeds is not None
    np.testing.assert_array_equal(speeds.velocity[:3], [0.4, 0.4, 0.25])
    assert speeds.names[:3] == [f"{BASE_JOINT}[{k}]" for k in range(3)]


def test_floating_base_and_the_srdf_posture(talos: clik.Robot, talos_fixed: clik.Robot) -> None:
    assert talos.base == "floating" and talos.joint_kinds[BASE_JOINT] == "free-flyer"
    assert (talos.nq, talos.nv) == (talos_fixed.nq + 7, talos_fixed.nv + 6)
    assert talos.q_units[:8] == ["m", "m", "m", "", "", "", "", "rad"]
    # the SRDF's half_sitting gives the free-flyer's 7 values: taken whole when floating,
    # the joints' part when fixed
    np.testing.assert_allclose(talos.q_reference[:7], [0, 0, 1.01927, 0, 0, 0, 1], atol=1e-12)
    np.testing.assert_array_equal(talos.q_reference[7:], talos_fixed.q_reference)
    np.testing.assert_array_equal(
        np.asarray(talos.model.velocityLimit)[:6], [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]
    )
    # the feet stand on the floor at the reference (z ~ 0): the base's height is used
    data = talos.model.createData()
    pin.framesForwardKinematics(talos.model, data, talos.q_reference)
    sole = data.oMf[talos.frame_id("left_sole_link")].translation
    assert abs(sole[2]) <= 1e-3


def test_bad_base_arguments_are_refused(lock: dict[str, float]) -> None:
    with pytest.raises(InputError, match=r"^base: expected one of 'fixed', 'planar', 'floating'"):
        clik.Robot.load("tiago", lock=lock, base="wheeled")
    with pytest.raises(InputError, match=r"^base_speed: expected a planar or floating base"):
        clik.Robot.load("tiago", lock=lock, base_speed=[1.0, 1.0])
    for bad in ([1.0], [1.0, 0.0], [1.0, math.inf], "fast", [True, 1.0]):
        with pytest.raises(InputError, match=r"^base_speed: expected two positive finite speeds"):
            check_base_speed(bad)
    with pytest.raises(InputError, match=r"^lock\['root_joint'\]: expected a joint other than"):
        clik.Robot.load("tiago", lock={**lock, BASE_JOINT: 0.0}, base="planar")


def test_configuration_from_user_values(tiago: clik.Robot, talos: clik.Robot) -> None:
    arm = [0.1, 20.0, 0.0, -30.0, 45.0, 0.0, 0.0, 10.0]  # torso [m], then angles [deg]
    q = tiago.configuration([1.0, -2.0, 90.0, *arm], unit="deg")  # angle form: nv values
    np.testing.assert_allclose(q[:4], [1.0, -2.0, 0.0, 1.0], atol=1e-15)
    assert q[4] == 0.1 and q[5] == pytest.approx(math.radians(20.0))
    # Pinocchio's form (nq values): (cos, sin) kept, normalised when nearly unit
    q = tiago.configuration([1.0, -2.0, 0.70711, 0.70711, *arm], unit="deg")
    assert np.hypot(q[2], q[3]) == pytest.approx(1.0, abs=1e-15)
    with pytest.raises(InputError, match=r"initial.q: expected the base's \(cos, sin\) pair"):
        tiago.configuration([1.0, -2.0, 0.5, 0.5, *arm], field="initial.q")
    with pytest.raises(InputError, match=r"q0: expected the base's quaternion"):
        bad = talos.q_reference
        bad[3:7] = [0.0, 0.0, 0.0, 2.0]
        talos.check_configuration(bad)
    # floating: x, y, z [m], roll, pitch, yaw [unit] in the angle form
    joints = np.zeros(talos.nv - 6)
    q = talos.configuration([0.1, 0.2, 1.0, 0.0, 0.0, 90.0, *joints], unit="deg")
    expected = pin.Quaternion(pin.rpy.rpyToMatrix(0.0, 0.0, math.pi / 2)).coeffs()
    np.testing.assert_allclose(q[3:7], expected, atol=1e-15)
    np.testing.assert_array_equal(q[:3], [0.1, 0.2, 1.0])
    with pytest.raises(InputError, match=r"the floating base as x, y, z \[m\], roll, pitch, yaw"):
        talos.configuration([0.0] * 5)


def test_the_base_has_no_range_rows_and_no_position_check(tiago: clik.Robot) -> None:
    limits = JointLimits(tiago)
    assert BASE_JOINT not in limits.joint_names
    assert set(limits.q_index.tolist()).isdisjoint(range(4))
    assert set(limits.v_index.tolist()).isdisjoint(range(3))
    assert limits.joint_names == [n for n in tiago.joint_names if n != BASE_JOINT]
    far = tiago.q_reference
    far[:4] = [1e6, -1e6, -1.0, 0.0]  # far away, turned round: no limit on a base
    tiago.check_within_limits(far)
    far[4] = -0.5  # the torso below its lower limit is still refused
    with pytest.raises(clik.InfeasibleError, match="torso_lift_joint"):
        tiago.check_within_limits(far)
    with pytest.raises(InputError, match=r"a continuous joint or a base has no range"):
        JointLimits(tiago, override={BASE_JOINT: {"lower": 0.0}})


def test_placements_follow_the_base(tiago: clik.Robot, tiago_fixed: clik.Robot) -> None:
    """The 3-D view's placements (forward kinematics of the full q) move with the base."""
    q = np.tile(tiago.q_reference, (3, 1))
    q[1, :4] = [1.0, 0.5, 1.0, 0.0]
    q[2, :4] = [-0.3, 2.0, 0.0, 1.0]  # turned by 90 deg
    placements = joint_placements(tiago.model, q)
    np.testing.assert_allclose(placements[:, 1, :2, 3], q[:, :2], atol=1e-15)
    arm = joint_placements(tiago_fixed.model, q[:1, 4:])[0]
    for k in range(3):
        base = np.eye(4)
        c, s = q[k, 2], q[k, 3]
        base[:2, :2] = [[c, -s], [s, c]]
        base[:2, 3] = q[k, :2]
        np.testing.assert_allclose(placements[k, 2:], base @ arm[1:], atol=1e-12)


def test_export_refuses_a_base_by_name(tiago: clik.Robot) -> None:
    with pytest.raises(ExportError, match=r"joint 'root_joint' is the robot's planar base"):
        check_exportable(tiago.model)


def scenario(robot: dict[str, object]) -> dict[str, object]:
    return {
        "name": "base",
        "robot": {"source": "planar4r", **robot},
        "task": {"frame": "tip", "kind": "position"},
        "trajectory": {"kind": "line", "goal": [1.0, 0.0, 0.0], "duration": 1.0},
    }


def test_scenario_base_keys(tmp_path) -> None:
    parsed = parse_scenario(scenario({"base": "planar", "base_speed": [0.5, 2]}), tmp_path / "s")
    assert parsed.robot["base"] == "planar" and parsed.robot["base_speed"] == [0.5, 2.0]
    assert parse_scenario(scenario({}), tmp_path / "s").robot["base"] == "fixed"
    with pytest.raises(ScenarioError, match=r"robot.base.*one of 'fixed', 'planar', 'floating'"):
        parse_scenario(scenario({"base": "mobile"}), tmp_path / "s")
    with pytest.raises(ScenarioError, match=r"robot.base_speed.*two positive speeds"):
        parse_scenario(scenario({"base": "planar", "base_speed": [0.5, 0.0]}), tmp_path / "s")
    with pytest.raises(ScenarioError, match=r"robot.base_speed.*robot.base is 'fixed'"):
        parse_scenario(scenario({"base_speed": [0.5, 1.0]}), tmp_path / "s")


def test_planar_from_a_free_flyer_pose() -> None:
    """An SRDF state written for a free flyer, read by a planar base: x, y and yaw kept."""
    rotation = pin.rpy.rpyToMatrix(0.1, -0.2, 0.7)
    values = np.r_[1.0, 2.0, 0.55, pin.Quaternion(rotation).coeffs()]
    np.testing.assert_allclose(
        planar_from_free_flyer(values), [1.0, 2.0, math.cos(0.7), math.sin(0.7)], atol=1e-15
    )
