"""SRDF files with xacro markup: expanded like the URDF, with its ``xacro_args``.

The test robot is written here: ``pkg/urdf/arm.urdf.xacro``, a three-joint arm whose
link and joint names start with the argument ``prefix`` (its other argument,
``reach``, only the URDF takes), and ``pkg/config/arm.srdf.xacro``, which builds the
same names from ``prefix`` with a property, writes three of its four disabled pairs
and one of its two group states with macros.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from clik import InputError, RobotLoadError, ScenarioError, SrdfMismatchWarning
from clik.model.robot import Robot
from clik.model.srdf import SrdfWarning, read_srdf, srdf_of
from clik.model.srdf_xacro import has_xacro_markup
from clik.model.urdf_check import parse_xml
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario

XACRO_ROBOT = '<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'

URDF_XACRO = (
    XACRO_ROBOT
    + """  <xacro:arg name="prefix" default=""/>
  <xacro:arg name="reach" default="0.3"/>
  <xacro:property name="prefix" value="$(arg prefix)"/>
  <xacro:macro name="segment" params="i parent">
    <joint name="${prefix}joint${i}" type="revolute">
      <parent link="${prefix}${parent}"/><child link="${prefix}link${i}"/>
      <origin xyz="0 0 $(arg reach)"/><axis xyz="0 1 0"/>
      <limit lower="-2" upper="2" effort="1" velocity="1"/>
    </joint>
    <link name="${prefix}link${i}">
      <collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision>
    </link>
  </xacro:macro>
  <link name="${prefix}base"/>
  <xacro:segment i="1" parent="base"/>
  <xacro:segment i="2" parent="link1"/>
  <xacro:segment i="3" parent="link2"/>
</robot>
"""
)

SRDF_XACRO = (
    XACRO_ROBOT
    + """  <xacro:arg name="prefix" default=""/>
  <xacro:property name="prefix" value="$(arg prefix)"/>
  <xacro:property name="bend" value="0.5"/>
  <xacro:macro name="adjacent" params="a b">
    <disable_collisions link1="${prefix}${a}" link2="${prefix}${b}" reason="Adjacent"/>
  </xacro:macro>
  <xacro:macro name="state" params="name first second">
    <group_state name="${name}" group="arm">
      <joint name="${prefix}joint1" value="${first}"/>
      <joint name="${prefix}joint2" value="${second}"/>
    </group_state>
  </xacro:macro>
  <group name="arm"><chain base_link="${prefix}base" tip_link="${prefix}link3"/></group>
  <group_state name="home" group="arm"><joint name="${prefix}joint3" value="0.25"/></group_state>
  <xacro:state name="bent" first="${bend}" second="${-2 * bend}"/>
  <disable_collisions link1="${prefix}base" link2="${prefix}link2" reason="Never"/>
  <xacro:adjacent a="base" b="link1"/>
  <xacro:adjacent a="link1" b="link2"/>
  <xacro:adjacent a="link2" b="link3"/>
</robot>
"""
)

ARGS = {"prefix": "left_", "reach": "0.25"}
PAIRS = {
    ("left_base", "left_link1"),
    ("left_base", "left_link2"),
    ("left_link1", "left_link2"),
    ("left_link2", "left_link3"),
}


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def files(tmp_path) -> tuple[Path, Path]:
    """The URDF and SRDF xacro files, in a package folder ``pkg``."""
    urdf = write(tmp_path, "pkg/urdf/arm.urdf.xacro", URDF_XACRO)
    srdf = write(tmp_path, "pkg/config/arm.srdf.xacro", SRDF_XACRO)
    return urdf, srdf


def load(urdf: Path, srdf: Path, args: dict[str, str] | None = None) -> Robot:
    return Robot.load(urdf, xacro_args=ARGS if args is None else args, srdf=srdf)


def test_every_pair_and_state_of_a_xacro_srdf_is_read(files):
    urdf, srdf = files
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning at all: every name is the robot's
        robot = load(urdf, srdf)
    assert robot.link_names == ["left_base", "left_link1", "left_link2", "left_link3"]
    assert robot.srdf_path == srdf.resolve()
    assert len(robot.disabled_collision_pairs) == 4
    assert robot.disabled_collision_pairs == PAIRS
    assert sorted(robot.group_states) == ["bent", "home"]
    assert dict(robot.group_states["bent"].values) == {
        "left_joint1": (0.5,),
        "left_joint2": (-1.0,),
    }
    assert dict(robot.group_states["home"].values) == {"left_joint3": (0.25,)}
    np.testing.assert_array_equal(robot.group_state("bent"), [0.5, -1.0, 0.0])


def test_the_raw_reading_differs(files):
    """Read as it is written, the file gives no pair and a state of joints the robot lacks."""
    urdf, srdf = files
    robot = load(urdf, srdf)
    root = parse_xml(srdf).getroot()
    assert has_xacro_markup(root)
    with pytest.warns(SrdfMismatchWarning, match="names 0 of the robot's 4 links"):
        raw = srdf_of(srdf, root, robot.link_names, robot.joint_names)
    assert raw.disabled_pairs == frozenset()
    assert list(raw.group_states) == ["home"]  # "bent" is written by a macro
    assert list(raw.group_states["home"].values) == ["${prefix}joint3"]
    assert (len(raw.disabled_pairs), len(raw.group_states)) != (
        len(robot.disabled_collision_pairs),
        len(robot.group_states),
    )


def test_another_prefix_gives_other_names(files):
    urdf, srdf = files
    robot = load(urdf, srdf, {"prefix": "right_"})
    assert robot.disabled_collision_pairs == {
        tuple(n.replace("left_", "right_") for n in pair) for pair in PAIRS
    }
    assert set(robot.group_states["bent"].values) == {"right_joint1", "right_joint2"}


def test_a_plain_srdf_is_not_expanded(files, tmp_path):
    urdf, _ = files
    plain = write(
        tmp_path,
        "plain.srdf",
        '<robot name="arm"><disable_collisions link1="left_base" link2="left_link3"/></robot>',
    )
    assert not has_xacro_markup(parse_xml(plain).getroot())
    robot = load(urdf, plain)
    assert robot.disabled_collision_pairs == {("left_base", "left_link3")}


def test_xacro_markup_in_a_file_named_srdf_is_expanded(files, tmp_path):
    urdf, _ = files
    srdf = write(tmp_path, "pkg/config/arm.srdf", SRDF_XACRO)
    assert load(urdf, srdf).disabled_collision_pairs == PAIRS


def test_an_srdf_naming_none_of_the_robot_warns_once_with_the_counts(files, tmp_path):
    urdf, _ = files
    other = write(tmp_path, "other.srdf", SRDF_XACRO.replace("$(arg prefix)", "right_"))
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        robot = load(urdf, other)
    assert [type(r.message) for r in record] == [SrdfMismatchWarning]  # no SrdfWarning too
    warning = record[0].message
    assert isinstance(warning, SrdfMismatchWarning)
    assert f"{other} names 0 of the robot's 4 links and 0 of its 3 joints" in str(warning)
    assert "its 4 <disable_collisions> pairs are left out and its 2 group states" in str(warning)
    assert (warning.link_count, warning.joint_count) == (4, 3)
    assert "right_base" in warning.names and "right_joint1" in warning.names
    assert robot.disabled_collision_pairs == frozenset()


def test_some_unknown_links_are_one_line_with_counts(files, tmp_path):
    urdf, _ = files
    stale = SRDF_XACRO.replace('b="link3"', 'b="gripper"')
    srdf = write(tmp_path, "pkg/config/stale.srdf.xacro", stale)
    with pytest.warns(SrdfWarning) as record:
        robot = load(urdf, srdf)
    assert len(record) == 1
    assert "1 of its 4 <disable_collisions> pairs name links the robot does not have" in str(
        record[0].message
    )
    assert record[0].message.names == ["left_gripper"]
    assert len(robot.disabled_collision_pairs) == 3


def test_an_undefined_property_names_the_srdf_file(files):
    urdf, srdf = files
    srdf.write_text(SRDF_XACRO.replace("${bend}", "${bent_angle}"), encoding="utf-8")
    with pytest.raises(RobotLoadError, match="xacro cannot expand it") as caught:
        load(urdf, srdf)
    assert isinstance(caught.value, RobotLoadError)
    assert caught.value.source == str(srdf.resolve())
    assert "bent_angle" in caught.value.problem


def test_an_argument_the_srdf_needs_names_the_srdf_file(files):
    urdf, srdf = files
    srdf.write_text(SRDF_XACRO.replace('"arm"', '"$(arg group)"'), encoding="utf-8")
    with pytest.raises(InputError, match="'group'") as caught:
        load(urdf, srdf)
    assert caught.value.field == "xacro_args"
    assert str(srdf.resolve()) in str(caught.value)


def test_an_error_in_the_expansion_names_its_line_there(files):
    urdf, srdf = files
    srdf.write_text(SRDF_XACRO.replace('value="0.25"', 'value="up"'), encoding="utf-8")
    with pytest.raises(RobotLoadError, match=r"of its xacro expansion\)$") as caught:
        load(urdf, srdf)
    assert caught.value.line is None and "joint 'left_joint3'" in caught.value.problem


def test_xacro_args_with_a_plain_urdf_are_checked_against_the_srdf(tmp_path):
    srdf = write(
        tmp_path,
        "arm.srdf.xacro",
        XACRO_ROBOT + '<xacro:arg name="far" default="link4"/>\n'
        '<disable_collisions link1="link1" link2="$(arg far)"/>\n</robot>\n',
    )
    robot = Robot.load("planar4r", srdf=srdf, xacro_args={"far": "link3"})
    assert robot.disabled_collision_pairs == {("link1", "link3")}
    with pytest.raises(InputError, match=r"arguments that .*arm\.srdf\.xacro declares or uses"):
        Robot.load("planar4r", srdf=srdf, xacro_args={"fra": "link3"})
    with pytest.raises(InputError, match="a xacro source or SRDF"):
        Robot.load("planar4r", srdf=False, xacro_args={"far": "link3"})


def test_read_srdf_takes_the_arguments_itself(files):
    _, srdf = files
    links = ["a_base", "a_link1", "a_link2", "a_link3"]
    read = read_srdf(srdf, links, ["a_joint1"], {"prefix": "a_"})
    assert len(read.disabled_pairs) == 4 and set(read.group_states) == {"bent", "home"}
    with pytest.raises(InputError, match="xacro_args"):
        read_srdf(srdf, links, [], {"prefix": "a_", "reach": "1"})  # not an SRDF argument
    read_srdf(srdf, links, [], {"prefix": "a_", "reach": "1"}, extra_args=True)


def scenario(folder: Path, srdf: str, args: str) -> Path:
    """A scenario beside ``pkg``: the xacro arm with ``srdf``, starting from ``bent``."""
    return write(
        folder,
        "arm.toml",
        f"""name = "xacro SRDF"

[robot]
source = "pkg/urdf/arm.urdf.xacro"
srdf = "{srdf}"
xacro_args = {{ {args} }}

[initial]
q = "srdf:bent"

[task]
frame = "left_link3"
kind = "position"

[trajectory]
kind = "line"
goal = [0.0, 0.0, 0.7]
duration = 0.1
""",
    )


def test_a_scenario_expands_its_srdf_with_its_xacro_args(files, tmp_path):
    run = build(scenario(tmp_path, "pkg/config/arm.srdf.xacro", 'prefix = "left_"'))
    assert run.robot.disabled_collision_pairs == PAIRS
    np.testing.assert_array_equal(run.q0, [0.5, -1.0, 0.0])
    _, srdf = files
    srdf.write_text(SRDF_XACRO.replace("${bend}", "${bent_angle}"), encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"robot\.srdf: cannot load robot .*bent_angle"):
        build(scenario(tmp_path, "pkg/config/arm.srdf.xacro", 'prefix = "left_"'))


def test_a_scenario_takes_xacro_args_for_a_xacro_srdf_alone(tmp_path):
    srdf = write(
        tmp_path,
        "arm.srdf.xacro",
        XACRO_ROBOT + '<xacro:arg name="far" default="link4"/>\n'
        '<disable_collisions link1="link1" link2="$(arg far)"/>\n</robot>\n',
    )
    path = write(
        tmp_path,
        "planar.toml",
        f'name = "p"\n[robot]\nsource = "planar4r"\nsrdf = "{srdf.name}"\n'
        'xacro_args = { far = "link3" }\n[task]\nframe = "tip"\nkind = "position"\n'
        'axes = ["x", "y"]\n[trajectory]\nkind = "line"\ngoal = [0.15, 0.95, 0.0]\n'
        "duration = 0.1\n",
    )
    assert load_scenario(path).robot["xacro_args"] == {"far": "link3"}
    with pytest.raises(ScenarioError, match=r"robot\.xacro_args: .*nor robot\.srdf"):
        load_scenario(write(tmp_path, "plain.toml", path.read_text().replace(".xacro", "")))
