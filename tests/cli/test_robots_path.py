"""``clik robots --path WS``: the robot descriptions in a ROS workspace, and how to load them."""

from __future__ import annotations

from pathlib import Path

import pytest

from clik.cli import main
from clik.model.robot import Robot
from tests.model.test_packages import make_workspace, manifest


@pytest.fixture(scope="module")
def src(tmp_path_factory) -> Path:
    src = make_workspace(tmp_path_factory.mktemp("robots_path"))
    urdf = src / "common" / "macros" / "urdf"
    (urdf / "plain.urdf").write_text('<robot name="plain"><link name="a"/></robot>')
    (urdf / "broken.urdf").write_text("<robot name='broken'>")
    (urdf / "not_a_robot.urdf").write_text("<sdf/>")
    (src / "common" / "loose.urdf").write_text('<robot name="loose"><link name="a"/></robot>')
    # as moveit_resources' panda_moveit_config and ur_description have them:
    wiki = 'xmlns:xacro="http://wiki.ros.org/xacro"'
    (urdf / "hand.xacro").write_text(  # an SRDF's macro, named: not a description
        f'<robot {wiki} name="panda"><xacro:macro name="hand">'
        '<group name="hand"><link name="a"/></group></xacro:macro></robot>'
    )
    (urdf / "arm.srdf.xacro").write_text(
        f'<robot {wiki} name="panda"><xacro:include filename="hand.xacro"/><xacro:hand/></robot>'
    )
    (urdf / "arm.srdf").write_text('<robot name="arm"><group name="g"/></robot>')
    (urdf / "chain_macro.xacro").write_text(  # links only inside a macro: not a description
        f'<robot {wiki}><xacro:macro name="chain"><link name="a"/></xacro:macro></robot>'
    )
    (urdf / "uses_macro.urdf.xacro").write_text(  # calls a macro: a description
        f'<robot {wiki} name="uses"><xacro:include filename="chain_macro.xacro"/>'
        "<xacro:chain/></robot>"
    )
    return src


def listed(output: str) -> list[tuple[str, str]]:
    """The (package, file) rows of the listing."""
    lines = output.split("package", 1)[1].split("\n\n")[0].splitlines()[1:]
    return [(line.split()[0], line.split()[1]) for line in lines]


def test_lists_the_descriptions_in_packages(src, capsys):
    assert main(["robots", "--path", str(src)]) == 0
    out = capsys.readouterr().out
    arm = src / "arm_repo" / "robots" / "ws_arm_description" / "urdf" / "arm.urdf.xacro"
    macros = src / "common" / "macros" / "urdf"
    assert listed(out) == [
        ("ws_arm_description", str(arm)),  # not inc/tool.xacro: macros only
        ("ws_arm_macros", str(macros / "plain.urdf")),  # not macros.xacro, not_a_robot.urdf
        ("ws_arm_macros", str(macros / "uses_macro.urdf.xacro")),  # not SRDFs, not macros
    ]
    assert f"skipped {macros / 'broken.urdf'}: malformed XML" in out
    assert str(src / "common" / "loose.urdf") not in out  # in no package
    assert "ignored" not in out and "/old/" not in out and "/.git/" not in out
    assert f"Robot.load(path, package_dirs=[{str(src)!r}])" in out
    assert Robot.load(arm, package_dirs=[src]).nq == 7  # loaded as the listing says


def test_says_when_there_is_none(tmp_path, capsys):
    manifest(tmp_path / "repo" / "empty_pkg", "empty_pkg")
    assert main(["robots", "--path", str(tmp_path)]) == 1
    assert "no robot description" in capsys.readouterr().out


def test_a_missing_folder_is_refused(tmp_path, capsys):
    assert main(["robots", "--path", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err
    assert "--path: expected a folder holding ROS packages" in err and "nowhere" in err


def test_without_path_lists_the_robots_known_by_name(capsys):
    assert main(["robots"]) == 0
    assert "planar4r" in capsys.readouterr().out


def test_two_packages_of_one_name_are_pointed_out(src, capsys):
    # make_workspace's dup_a/dup and dup_b/dup are both "dup_pkg": colcon refuses them.
    assert main(["robots", "--path", str(src)]) == 0
    out = capsys.readouterr().out
    note = next(line for line in out.splitlines() if line.startswith("note:"))
    assert "2 packages named 'dup_pkg'" in note and "COLCON_IGNORE" in note
    assert str(src / "dup_a" / "dup" / "package.xml") in note
    assert str(src / "dup_b" / "dup" / "package.xml") in note
    assert "'ws_meshes'" not in out  # the ignored and hidden copies are no duplicates
