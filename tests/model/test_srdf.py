"""SRDF files: disabled collision pairs skipped by self-collision rows, group states as starts."""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import clik
from clik.constraints import ConstraintSet
from clik.errors import InputError, RobotLoadError, ScenarioError
from clik.model.robot import PANDA_FINGERS, Robot
from clik.model.srdf import SrdfWarning, read_srdf
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario
from tests.limits_check import assert_completed

PLANAR_SRDF = """<?xml version="1.0"?>
<robot name="planar4r">
  <group name="arm">
    <chain base_link="base" tip_link="tip"/>
  </group>
  <group_state name="bent" group="arm">
    <joint name="joint1" value="0.5"/>
    <joint name="joint3" value="-1.0"/>
  </group_state>
  <group_state name="home" group="arm">
    <joint name="joint2" value="0.25"/>
  </group_state>
  <disable_collisions link1="link3" link2="link1" reason="Never"/>
</robot>
"""
"""planar4r: the pair link1-link3 disabled (written in reverse order), two states."""


def srdf_pairs(path) -> set[tuple[str, str]]:
    """The file's disabled pairs, read with the standard library (not clik's reader)."""
    root = ET.parse(path).getroot()
    return {
        tuple(sorted((e.get("link1"), e.get("link2")))) for e in root.iter("disable_collisions")
    }


def link_pairs(cset: ConstraintSet) -> list[tuple[str, str]]:
    scene = cset.scene
    assert scene is not None
    names = scene.link_names
    return [tuple(sorted((names[a], names[b]))) for _, a, b in scene.self_pairs]


@pytest.fixture(scope="module")
def planar_srdf(tmp_path_factory):
    path = tmp_path_factory.mktemp("srdf") / "planar4r.srdf"
    path.write_text(PLANAR_SRDF)
    return path


@pytest.fixture(scope="module")
def planar(planar_srdf) -> Robot:
    return Robot.load("planar4r", srdf=planar_srdf)


# -- the zoo robots' own SRDF: the self-collision rows skip its pairs ------------------


@pytest.mark.parametrize(
    ("name", "lock"), [("panda", PANDA_FINGERS), ("panda", None), ("ur5", None)]
)
def test_own_srdf_pairs_are_skipped(name, lock):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's free finger leader (mimic)
        robot = Robot.load(name, lock=lock)
        bare = Robot.load(name, lock=lock, srdf=False)
    assert robot.srdf_path is not None and robot.srdf_path.name == f"{name}.srdf"
    assert bare.srdf_path is None and bare.disabled_collision_pairs == frozenset()
    listed = srdf_pairs(robot.srdf_path)
    assert robot.disabled_collision_pairs == listed  # every listed link exists

    without = link_pairs(ConstraintSet(bare, self_collision=True))
    candidates = [pair for pair in without if pair in listed]
    cset = ConstraintSet(robot, self_collision=True)
    kept = link_pairs(cset)
    assert len(candidates) > 0
    assert len(kept) == len(without) - len(candidates)
    assert cset.srdf_skipped_pairs == len(candidates)
    assert cset.scene is not None and cset.scene.srdf_skipped_pairs == len(candidates)
    assert not set(kept) & listed
    assert sorted(kept) == sorted(pair for pair in without if pair not in listed)


def test_panda_counts():
    """The numbers themselves, for the Panda with its fingers locked (the fixture's robot)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = Robot.load("panda", lock=PANDA_FINGERS)
    assert len(robot.disabled_collision_pairs) == 35
    cset = ConstraintSet(robot, self_collision=True)
    assert (len(cset.scene.self_pairs), cset.srdf_skipped_pairs) == (44, 31)
    assert ConstraintSet(robot).srdf_skipped_pairs == 0  # no self-collision: no scene


def test_a_file_has_no_srdf_unless_given(planar4r, planar, planar_srdf):
    assert planar4r.srdf_path is None and planar4r.group_states == {}
    assert planar.srdf_path == planar_srdf.resolve()
    assert planar.disabled_collision_pairs == {("link1", "link3")}
    without = link_pairs(ConstraintSet(planar4r, self_collision=True))
    with_srdf = ConstraintSet(planar, self_collision=True)
    assert sorted(without) == [("link1", "link3"), ("link1", "link4"), ("link2", "link4")]
    assert link_pairs(with_srdf) == [("link1", "link4"), ("link2", "link4")]
    assert with_srdf.srdf_skipped_pairs == 1


def test_locking_keeps_the_srdf(planar, planar_srdf):
    locked = Robot.load("planar4r", srdf=planar_srdf, lock={"joint4": 0.2})
    assert locked.nq == 3
    assert locked.srdf_path == planar.srdf_path
    assert locked.disabled_collision_pairs == planar.disabled_collision_pairs
    assert set(locked.group_states) == {"bent", "home"}
    np.testing.assert_array_equal(locked.group_state("bent"), [0.5, 0.0, -1.0])


def test_bad_srdf_argument_is_refused():
    with pytest.raises(InputError, match=r"^srdf: expected an SRDF file path, None"):
        Robot.load("planar4r", srdf=True)


# -- strict reading ------------------------------------------------------------------------


def test_hostile_srdf_is_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("not for the robot")
    hostile = tmp_path / "hostile.srdf"
    hostile.write_text(
        f'<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file://{secret}">]>\n'
        '<robot name="r"><disable_collisions link1="&x;" link2="link1"/></robot>\n'
    )
    with pytest.raises(RobotLoadError, match="line 2: the DOCTYPE declares XML entities"):
        Robot.load("planar4r", srdf=hostile)
    dtd = tmp_path / "dtd.srdf"
    dtd.write_text('<?xml version="1.0"?>\n<!DOCTYPE robot SYSTEM "robot.dtd">\n<robot/>\n')
    with pytest.raises(RobotLoadError, match="external DTD"):
        read_srdf(dtd, ["link1"])


@pytest.mark.parametrize(
    ("body", "problem"),
    [
        ('<disable_collisions link1="link1"/>', "line 2: <disable_collisions> needs a 'link2'"),
        ('<group_state group="arm"/>', "line 2: <group_state> needs a 'name'"),
        (
            '<group_state name="s"><joint name="joint1" value="up"/></group_state>',
            "line 2: joint 'joint1': expected a value of 1 to 16 finite numbers",
        ),
        (
            '<group_state name="s"><joint name="joint1" value="nan"/></group_state>',
            "joint 'joint1': expected a value",
        ),
        (
            '<group_state name="s"><joint name="joint1" value="1e9"/></group_state>',
            "of magnitude at most 1000",
        ),
        (
            '<group_state name="s" group="a"><joint name="joint1" value="1"/></group_state>\n'
            '<group_state name="s" group="b"><joint name="joint1" value="2"/></group_state>',
            "line 3: group state 's' gives joint 'joint1' two values",
        ),
        ("<group_state", "malformed XML"),
    ],
)
def test_malformed_srdf_names_the_line(tmp_path, body, problem):
    path = tmp_path / "bad.srdf"
    path.write_text(f'<robot name="r">\n{body}\n</robot>\n')
    with pytest.raises(RobotLoadError, match=problem):
        read_srdf(path, ["link1", "link2"])


def test_not_an_srdf(tmp_path):
    path = tmp_path / "x.srdf"
    path.write_text("<mujoco/>")
    with pytest.raises(RobotLoadError, match="root element is <robot>, got <'mujoco'>"):
        read_srdf(path, [])
    with pytest.raises(RobotLoadError, match="file not found"):
        read_srdf(tmp_path / "missing.srdf", [])


def test_stale_links_warn_and_are_left_out(tmp_path):
    path = tmp_path / "stale.srdf"
    path.write_text(
        '<robot name="planar4r">\n'
        '<disable_collisions link1="link1" link2="link3"/>\n'
        '<disable_collisions link1="old_link" link2="link3"/>\n'
        '<disable_collisions link1="link2" link2="gripper"/>\n'
        '<disable_collisions link1="link2" link2="link2"/>\n'
        "</robot>\n"
    )
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        robot = Robot.load("planar4r", srdf=path)
    assert [type(r.message) for r in record] == [SrdfWarning]  # one line, not one per link
    assert "2 of its 4 <disable_collisions> pairs name links the robot does not have (2:" in str(
        record[0].message
    )
    assert record[0].message.names == ["old_link", "gripper"]
    assert "'old_link', 'gripper'" in str(record[0].message)
    assert robot.disabled_collision_pairs == {("link1", "link3")}


# -- group states --------------------------------------------------------------------------


def test_group_state_keeps_unlisted_joints_at_the_reference(planar):
    np.testing.assert_array_equal(planar.group_state("bent"), [0.5, 0.0, -1.0, 0.0])
    np.testing.assert_array_equal(planar.group_state("home"), [0.0, 0.25, 0.0, 0.0])
    np.testing.assert_array_equal(planar.check_configuration("srdf:bent"), [0.5, 0, -1, 0])
    assert planar.group_states["bent"].groups == ("arm",)


def test_panda_default_state_is_its_srdf_values():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = Robot.load("panda", lock=PANDA_FINGERS)
    root = ET.parse(robot.srdf_path).getroot()
    written = {
        j.get("name"): float(j.get("value"))
        for s in root.iter("group_state")
        if s.get("name") == "default"
        for j in s.iter("joint")
    }
    q = robot.group_state("default")
    expected = [written[name] for name in robot.joint_names]
    np.testing.assert_array_equal(q, expected)  # the finger's 0.001 is locked out
    assert clik.Task(robot, "panda_hand").placement(q).translation[2] > 0.3


def test_unknown_group_state_lists_the_names(planar, planar4r):
    with pytest.raises(InputError) as info:
        planar.group_state("ready")
    message = str(info.value)
    assert message == (
        f"group_state: expected the name of a group state of {planar.srdf_path} "
        "('bent', 'home'), got 'ready'"
    )
    with pytest.raises(InputError, match=r"^q0: expected the name .*\('bent', 'home'\)"):
        planar.check_configuration("srdf:ready", "q0")
    with pytest.raises(InputError, match=r"planar4r has no SRDF \(srdf=PATH\), got 'ready'"):
        planar4r.group_state("ready")


def test_group_state_with_other_joints(tmp_path):
    path = tmp_path / "states.srdf"
    path.write_text(
        '<robot name="planar4r">\n'
        '<group_state name="wide"><joint name="joint1" value="0.1"/>'
        '<joint name="gone_joint" value="3"/></group_state>\n'
        '<group_state name="two"><joint name="joint2" value="0.1 0.2"/></group_state>\n'
        "</robot>\n"
    )
    robot = Robot.load("planar4r", srdf=path)
    with pytest.warns(SrdfWarning, match="'gone_joint'"):
        q = robot.group_state("wide")
    np.testing.assert_array_equal(q, [0.1, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=r"group state 'two': 1 values for joint 'joint2'"):
        robot.group_state("two")


def test_continuous_joint_takes_an_angle(tmp_path):
    from clik.model.planar_arm import planar_arm_urdf

    urdf = tmp_path / "wheel.urdf"
    urdf.write_text(planar_arm_urdf([0.3, 0.3]).replace('type="revolute"', 'type="continuous"', 1))
    srdf = tmp_path / "wheel.srdf"
    srdf.write_text(
        '<robot name="wheel"><group_state name="s">'
        '<joint name="joint1" value="0.5"/></group_state></robot>'
    )
    robot = Robot.load(urdf, srdf=srdf)
    assert robot.nq == 3 and robot.nv == 2
    q = robot.group_state("s")
    np.testing.assert_allclose(q[:2], [math.cos(0.5), math.sin(0.5)], rtol=0, atol=1e-15)


# -- scenarios -------------------------------------------------------------------------


def planar_scenario(folder, initial: str, srdf: str = 'srdf = "planar4r.srdf"'):
    (folder / "planar4r.srdf").write_text(PLANAR_SRDF)
    path = folder / "case.toml"
    path.write_text(
        f"""
[robot]
source = "planar4r"
{srdf}

[initial]
{initial}

[task]
frame = "tip"
kind = "position"
axes = ["x", "y"]

[trajectory]
kind = "line"
goal = [0.15, 0.95, 0.0]
duration = 1.0

[solver]
law = "pseudoinverse"
dt = 0.001

[constraints.self_collision]
enabled = true
threshold = 0.02
"""
    )
    return path


def test_scenario_with_srdf_and_a_group_state_runs(tmp_path):
    run = build(planar_scenario(tmp_path, 'q = "srdf:bent"'))
    assert run.robot.srdf_path == (tmp_path / "planar4r.srdf").resolve()
    np.testing.assert_array_equal(run.q0, [0.5, 0.0, -1.0, 0.0])
    cset = run.tracker.constraints
    assert cset is not None and cset.srdf_skipped_pairs == 1
    assert link_pairs(cset) == [("link1", "link4"), ("link2", "link4")]
    result = run.execute()
    assert_completed(result, run.robot)
    assert result.max_task_error < 1e-4
    scene = cset.scene
    data = run.robot.model.createData()
    import pinocchio as pin

    for q in result.q:  # every kept pair apart by its threshold along the run
        pin.forwardKinematics(run.robot.model, data, q)
        scene.update(data, 0.0)
        assert min(scene.distance(p)[0] for p, _, _ in scene.self_pairs) >= 0.02 - 1e-6


def test_scenario_srdf_errors(tmp_path):
    with pytest.raises(ScenarioError, match=r"initial\.q: expected the name of a group state"):
        build(planar_scenario(tmp_path, 'q = "srdf:ready"'))
    with pytest.raises(ScenarioError, match=r"initial\.q: expected 'reference', 'srdf:NAME'"):
        load_scenario(planar_scenario(tmp_path, 'q = "ready"'))
    with pytest.raises(ScenarioError, match=r"robot\.srdf: expected an SRDF file path"):
        load_scenario(planar_scenario(tmp_path, "", 'srdf = "https://x.org/a.srdf"'))
    with pytest.raises(ScenarioError, match=r"robot\.srdf: cannot load robot .*file not found"):
        build(planar_scenario(tmp_path, "", 'srdf = "missing.srdf"'))
    with pytest.raises(ScenarioError, match=r"robot\.srdf: expected an SRDF file path"):
        load_scenario(planar_scenario(tmp_path, "", "srdf = true"))
    scenario = load_scenario(planar_scenario(tmp_path, "", "srdf = false"))
    assert scenario.robot["srdf"] is False and scenario.initial_q is None


def test_sweep_workers_load_the_scenario_srdf(tmp_path):
    from clik.sweep.worker import cached_robot, robot_key

    spec = load_scenario(planar_scenario(tmp_path, 'q = "srdf:bent"')).robot
    bare = {**spec, "srdf": None}
    assert robot_key(spec) != robot_key(bare)
    assert cached_robot(spec).disabled_collision_pairs == {("link1", "link3")}
    assert cached_robot(bare).srdf_path is None


def test_a_floating_base_state_read_by_a_planar_base(capfd):
    """b1_z1's SRDF gives its root_joint 7 values (a free flyer): a planar base keeps x, y, yaw.

    The reference posture is read by clik (Pinocchio's reader prints "Could not read joint
    config" for a planar root and leaves the base at neutral).
    """
    srdf = Robot.load("b1_z1").srdf_path
    states = {
        s.get("name"): {j.get("name"): j.get("value") for j in s.iter("joint")}
        for s in ET.parse(srdf).getroot().iter("group_state")
    }
    planar = Robot.load("b1_z1", base="planar")
    floating = Robot.load("b1_z1", base="floating")
    assert "Could not read joint config" not in capfd.readouterr().out
    for name, joints in states.items():
        x, y, _, qx, qy, qz, qw = (float(v) for v in joints["root_joint"].split())
        yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
        q = planar.group_state(name)
        np.testing.assert_allclose(q[:4], [x, y, math.cos(yaw), math.sin(yaw)], atol=1e-12)
        np.testing.assert_allclose(q[4:], floating.group_state(name)[7:], atol=1e-12)
    np.testing.assert_allclose(planar.q_reference[4:], floating.q_reference[7:], atol=1e-12)
    assert planar.q_reference[4:].any()  # the legs' posture, not neutral
