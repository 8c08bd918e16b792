"""ROS workspaces: packages found by their package.xml name, as colcon and rospack find them.

The workspace is laid out the way ROS users lay theirs out (:func:`make_workspace`)::

    ws/src/arm_repo/robots/ws_arm_description/      (3 levels below src) the xacro robot
    ws/src/arm_repo/repo_only.xacro                   a file of the repository, in no package
    ws/src/common/macros/                            package "ws_arm_macros" ($(find))
    ws/src/meshes_repo/mesh_files/                   package "ws_meshes" (package:// meshes)
    ws/src/old/COLCON_IGNORE, old/ws_meshes/         an ignored "ws_meshes" (must not clash)
    ws/src/.git/ws_meshes/                           a hidden "ws_meshes" (must not clash)
    ws/src/dup_a/dup/, ws/src/dup_b/dup/             two packages "dup_pkg" (an error)
    ws/src/meshes_repo/mesh_files/inner/             package "ws_inner", inside ws_meshes

The robot (7 revolute joints, as ``tests/data/xacro``'s arm) has mesh collision
geometry at its base and tool (binary STL boxes written here).
"""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

import clik
from clik import InputError, RobotLoadError
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.model import packages
from clik.model.packages import PackageDirs
from clik.model.robot import Robot
from clik.trajectory import Line
from tests.limits_check import assert_within_limits

MACROS = Path(__file__).parents[1] / "data" / "xacro" / "clik_xacro_demo" / "urdf" / "macros.xacro"
N_JOINTS = 7
THRESHOLD = 0.05  # [m] obstacle threshold of the run
CLEARANCE_TOL = 2e-3  # [m] how far below the threshold a link may come
TASK_TOL = 5e-3  # [m] largest task error of the run

ARM = """<?xml version="1.0"?>
<robot name="ws_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:include filename="$(find ws_arm_macros)/urdf/macros.xacro"/>
  <xacro:include filename="inc/tool.xacro"/>
  <link name="base_link">
    <collision>
      <origin xyz="0 0 0.05" rpy="0 0 0"/>
      <geometry><mesh filename="package://ws_meshes/meshes/box.stl" scale="0.2 0.2 0.1"/></geometry>
    </collision>
  </link>
  <xacro:chain parent="base_link" index="1" count="7" offset="0.1" length="0.2"/>
  <xacro:tool parent="l7"/>
</robot>
"""

TOOL = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="tool" params="parent">
    <joint name="tool_joint" type="fixed">
      <parent link="${parent}"/><child link="tool"/><origin xyz="0 0 0.2" rpy="0 0 0"/>
    </joint>
    <link name="tool">
      <visual>
        <geometry>
          <mesh filename="package://ws_meshes/meshes/box.stl" scale="0.02 0.02 0.02"/>
        </geometry>
      </visual>
      <collision>
        <geometry>
          <mesh filename="package://ws_meshes/meshes/box.stl" scale="0.03 0.03 0.03"/>
        </geometry>
      </collision>
    </link>
  </xacro:macro>
</robot>
"""


def box_stl(half: float = 0.5) -> bytes:
    """A binary STL of the cube [-half, half]^3 (12 triangles)."""
    corners = [(x, y, z) for x in (-half, half) for y in (-half, half) for z in (-half, half)]
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1)]
    faces += [(2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    data = b"clik test box".ljust(80, b" ") + struct.pack("<I", len(faces))
    for face in faces:
        data += struct.pack("<3f", 0, 0, 0)
        data += b"".join(struct.pack("<3f", *corners[i]) for i in face) + b"\0\0"
    return data


def manifest(folder: Path, name: str) -> Path:
    """A ``package.xml`` naming ``name`` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "package.xml"
    path.write_text(
        f'<?xml version="1.0"?>\n<package format="3">\n  <name>{name}</name>\n'
        "  <version>0.1.0</version>\n</package>\n"
    )
    return path


def mesh_package(folder: Path, name: str) -> Path:
    """A package ``name`` in ``folder`` holding ``meshes/box.stl``."""
    manifest(folder, name)
    (folder / "meshes").mkdir(exist_ok=True)
    (folder / "meshes" / "box.stl").write_bytes(box_stl())
    return folder


def write_arm(folder: Path, text: str, tool: str = TOOL) -> Path:
    """``folder/arm.urdf.xacro`` holding ``text``, with the ``inc/tool.xacro`` it includes."""
    (folder / "inc").mkdir(parents=True, exist_ok=True)
    (folder / "inc" / "tool.xacro").write_text(tool)
    (folder / "arm.urdf.xacro").write_text(text)
    return folder / "arm.urdf.xacro"


def make_workspace(root: Path) -> Path:
    """The workspace of the module docstring under ``root``; returns its ``src``."""
    src = root / "ws" / "src"
    arm = src / "arm_repo" / "robots" / "ws_arm_description"
    manifest(arm, "ws_arm_description")
    write_arm(arm / "urdf", ARM)
    (src / "arm_repo" / "repo_only.xacro").write_text(TOOL)
    manifest(src / "common" / "macros", "ws_arm_macros")
    (src / "common" / "macros" / "urdf").mkdir()
    shutil.copy(MACROS, src / "common" / "macros" / "urdf" / "macros.xacro")
    mesh_package(src / "meshes_repo" / "mesh_files", "ws_meshes")
    manifest(src / "meshes_repo" / "mesh_files" / "inner", "ws_inner")
    (src / "old").mkdir()
    (src / "old" / "COLCON_IGNORE").touch()
    mesh_package(src / "old" / "ws_meshes", "ws_meshes")
    mesh_package(src / ".git" / "ws_meshes", "ws_meshes")
    for repo in ("dup_a", "dup_b"):
        mesh_package(src / repo / "dup", "dup_pkg")
    return src


@pytest.fixture(scope="module")
def src(tmp_path_factory) -> Path:
    return make_workspace(tmp_path_factory.mktemp("packages"))


@pytest.fixture(scope="module")
def xacro(src) -> Path:
    return src / "arm_repo" / "robots" / "ws_arm_description" / "urdf" / "arm.urdf.xacro"


@pytest.fixture(scope="module")
def robot(xacro, src) -> Robot:
    return Robot.load(xacro, package_dirs=[src])


@pytest.fixture(autouse=True)
def no_ros_environment(monkeypatch):
    """The tests' own environment: no ROS workspace of the machine's."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)


# --------------------------------------------------------------- the package search


def test_packages_are_found_by_their_manifest_name(src):
    dirs = PackageDirs([src])
    meshes = dirs.find("ws_meshes")
    assert meshes is not None
    assert meshes.folder == (src / "meshes_repo" / "mesh_files").resolve()  # not old/, .git/
    assert meshes.manifest == src / "meshes_repo" / "mesh_files" / "package.xml"
    arm = dirs.find("ws_arm_description")
    assert arm is not None and arm.folder.relative_to(src.resolve()).parts == (
        "arm_repo",
        "robots",
        "ws_arm_description",
    )
    assert dirs.find("mesh_files") is None  # a folder name is not a package name
    assert dirs.find("ws_inner") is None  # the search does not enter a package
    assert dirs.find("../src") is None and dirs.find("") is None
    names = sorted(p.name for p in dirs.packages() if p.name != "dup_pkg")
    assert names == ["ws_arm_description", "ws_arm_macros", "ws_meshes"]


def test_a_workspace_is_searched_once_per_package_dirs(src, monkeypatch):
    dirs = PackageDirs([src])
    calls = []
    search = packages._search
    monkeypatch.setattr(packages, "_search", lambda top: calls.append(top) or search(top))
    assert dirs.find("ws_meshes") == dirs.find("ws_meshes") is not None
    assert dirs.find("ws_arm_macros") is not None
    assert calls == [src]
    PackageDirs([src]).find("ws_meshes")  # a new load searches again
    assert calls == [src, src]


def test_two_packages_of_one_name_name_both(src):
    with pytest.raises(InputError) as caught:
        PackageDirs([src]).find("dup_pkg")
    message = str(caught.value)
    assert caught.value.field == "package_dirs"
    assert str(src / "dup_a" / "dup" / "package.xml") in message
    assert str(src / "dup_b" / "dup" / "package.xml") in message
    assert "COLCON_IGNORE" in message


def test_a_folder_directly_in_a_package_dir_is_found_by_its_name(tmp_path):
    """As before workspaces were searched, and as Pinocchio looks ``package://`` up."""
    (tmp_path / "plain_pkg" / "meshes").mkdir(parents=True)
    found = PackageDirs([tmp_path]).find("plain_pkg")
    assert found is not None and found.folder == (tmp_path / "plain_pkg").resolve()
    assert found.manifest is None
    manifest(tmp_path / "example-robot-data", "example_robot_data")  # its own layout
    dirs = PackageDirs([tmp_path])
    for name in ("example-robot-data", "example_robot_data"):
        found = dirs.find(name)
        assert found is not None and found.folder == (tmp_path / "example-robot-data").resolve()


def test_a_repository_named_after_its_package_gives_the_package(tmp_path):
    inner = tmp_path / "moveit_resources" / "moveit_resources"
    manifest(inner, "moveit_resources")
    manifest(tmp_path / "moveit_resources" / "panda_description", "panda_pkg")
    found = PackageDirs([tmp_path]).find("moveit_resources")
    assert found is not None and found.folder == inner.resolve()


def test_symlinked_folders_are_not_followed(tmp_path):
    outside = mesh_package(tmp_path / "outside" / "linked", "linked_pkg")
    (tmp_path / "ws").mkdir()
    (tmp_path / "ws" / "repo").symlink_to(outside.parent, target_is_directory=True)
    assert PackageDirs([tmp_path / "ws"]).find("linked_pkg") is None
    (tmp_path / "ws" / "linked_pkg").symlink_to(outside, target_is_directory=True)
    direct = PackageDirs([tmp_path / "ws"]).find("linked_pkg")  # named directly: as before
    assert direct is not None and direct.folder == outside.resolve()


def test_a_bad_manifest_names_its_file(tmp_path):
    (tmp_path / "repo" / "pkg").mkdir(parents=True)
    bad = tmp_path / "repo" / "pkg" / "package.xml"
    bad.write_text('<!DOCTYPE p [<!ENTITY x "y">]><package><name>&x;</name></package>')
    with pytest.raises(RobotLoadError, match="declares XML entities") as caught:
        PackageDirs([tmp_path]).find("anything")
    assert caught.value.source == str(bad)
    bad.write_text("<package><version>1</version></package>")
    with pytest.raises(RobotLoadError, match="expected a <name>"):
        PackageDirs([tmp_path]).find("anything")


def test_the_search_budgets_stop_it_with_a_clear_error(src, monkeypatch):
    monkeypatch.setattr(packages, "MAX_FOLDERS_VISITED", 5)
    with pytest.raises(InputError, match=r"MAX_FOLDERS_VISITED\); .*src holds more") as caught:
        PackageDirs([src]).find("ws_meshes")
    assert caught.value.field == "package_dirs"
    monkeypatch.setattr(packages, "MAX_FOLDERS_VISITED", 20_000)
    monkeypatch.setattr(packages, "MAX_PACKAGE_DEPTH", 2)
    with pytest.raises(InputError, match=r"at most 2 folders below .*MAX_PACKAGE_DEPTH"):
        PackageDirs([src]).find("ws_arm_description")
    monkeypatch.setattr(packages, "MAX_PACKAGE_DEPTH", 3)  # src/arm_repo/robots/ws_arm_...
    assert PackageDirs([src]).find("ws_arm_description") is not None


def test_ros_package_path_is_searched_after_package_dirs(src, tmp_path, monkeypatch):
    underlay = tmp_path / "underlay" / "src"
    mesh_package(underlay / "repo" / "meshes_folder", "underlay_meshes")
    mesh_package(underlay / "repo" / "mine", "ws_meshes")
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"{tmp_path / 'nowhere'}:{underlay}:")
    dirs = PackageDirs([src])
    found = dirs.find("underlay_meshes")
    assert found is not None and found.folder == (underlay / "repo" / "meshes_folder").resolve()
    mine = dirs.find("ws_meshes")  # package_dirs first: the workspace's own
    assert mine is not None and mine.folder == (src / "meshes_repo" / "mesh_files").resolve()
    assert f"ROS_PACKAGE_PATH: {tmp_path / 'nowhere'}, {underlay}" in dirs.searched()


def test_ament_prefix_path_is_searched_last(tmp_path, monkeypatch):
    prefix = tmp_path / "install"
    mesh_package(prefix / "share" / "ament_meshes", "ament_meshes")
    manifest(prefix / "share" / "misnamed", "not_misnamed")
    monkeypatch.setenv("AMENT_PREFIX_PATH", f"{tmp_path / 'none'}:{prefix}")
    found = PackageDirs([tmp_path / "empty"]).find("ament_meshes")
    assert found is not None and found.folder == (prefix / "share" / "ament_meshes").resolve()
    assert PackageDirs([]).find("misnamed") is None


# ------------------------------------------------------- loading a robot from the workspace


def test_a_xacro_robot_loads_from_the_workspace(robot, src):
    assert robot.nq == N_JOINTS
    meshes = [g for g in robot.collision_model.geometryObjects if g.meshPath.endswith(".stl")]
    box = (src / "meshes_repo" / "mesh_files" / "meshes" / "box.stl").resolve()
    assert len(robot.collision_model.geometryObjects) == N_JOINTS + 2  # cylinders, 2 meshes
    assert [Path(g.meshPath) for g in meshes] == [box, box]
    np.testing.assert_allclose(meshes[0].meshScale, [0.2, 0.2, 0.1])
    assert "package://ws_meshes/meshes/box.stl" in str(robot.urdf_text)  # as expanded
    visual = robot.visual_model.geometryObjects  # read on first use, from the same files
    assert len(visual) == N_JOINTS + 1
    assert Path(visual[-1].meshPath) == box
    np.testing.assert_allclose(visual[-1].meshScale, [0.02, 0.02, 0.02])


def test_the_workspace_robot_tracks_past_an_obstacle(robot):
    """tests/data/xacro/arm_xacro.toml's run: a line past a ball the free arm goes through."""
    task = clik.Task(robot, "tool", "position")
    q0 = robot.configuration([0, 30, 0, 45, 0, 45, 0], "deg")
    line = Line(task.placement(q0).translation, [0.55, 0.25, 0.75], duration=2.0)
    ball = Obstacle("ball", "sphere", [0.45, 0.1, 0.95], radius=0.05)
    monitor = ConstraintSet(robot, obstacles=[ball], obstacle_rows=False)
    free = clik.track(task, line, q0=q0, law="pseudoinverse", gain=500.0, constraints=monitor)
    assert free.summary()["min_obstacle_distance"] < THRESHOLD - CLEARANCE_TOL
    cs = ConstraintSet(
        robot,
        obstacles=[ball],
        obstacle_threshold=THRESHOLD,
        joint_limits=JointLimits(robot, np.radians(5.0)),
    )
    result = clik.track(task, line, q0=q0, law="pseudoinverse", gain=500.0, constraints=cs)
    assert result.status == "completed"
    assert result.max_task_error < TASK_TOL
    assert_within_limits(result, robot, obstacle_floor=THRESHOLD - CLEARANCE_TOL)
    assert result.summary()["min_obstacle_distance"] >= THRESHOLD - CLEARANCE_TOL


def test_a_missing_package_names_the_folders_searched(xacro, tmp_path):
    with pytest.raises(InputError) as caught:
        Robot.load(xacro, package_dirs=[tmp_path])
    message = str(caught.value)
    assert "'ws_arm_macros'" in message and str(tmp_path) in message


def test_a_duplicate_package_stops_the_load_naming_both(src, tmp_path):
    path = write_arm(tmp_path, ARM.replace("ws_meshes/meshes", "dup_pkg/meshes"))
    with pytest.raises(InputError, match="one package named 'dup_pkg'") as caught:
        Robot.load(path, package_dirs=[src])
    assert str(src / "dup_a" / "dup" / "package.xml") in str(caught.value)
    assert str(src / "dup_b" / "dup" / "package.xml") in str(caught.value)


@pytest.mark.parametrize(
    "include",
    ["../../../repo_only.xacro", "$(find ws_meshes)/../../arm_repo/repo_only.xacro"],
    ids=["up-to-the-repository", "find-then-up"],
)
def test_a_file_outside_the_package_is_refused(src, xacro, include, tmp_path):
    copy = xacro.with_name("outside.urdf.xacro")
    copy.write_text(ARM.replace("inc/tool.xacro", include))
    try:
        with pytest.raises(RobotLoadError, match="which leaves the folders a xacro file may read"):
            Robot.load(copy, package_dirs=[src])
    finally:
        copy.unlink()


def test_a_mesh_may_not_leave_its_package(src, tmp_path):
    secret = src / "meshes_repo" / "secret.stl"
    secret.write_bytes(box_stl())
    link = src / "meshes_repo" / "mesh_files" / "meshes" / "link.stl"
    link.symlink_to(secret)
    try:
        for filename, words in [
            ("package://ws_meshes/../secret.stl", "leaves its package folder"),
            ("package://ws_meshes/meshes/link.stl", "which leaves its folder"),
        ]:
            path = write_arm(tmp_path, ARM.replace("package://ws_meshes/meshes/box.stl", filename))
            with pytest.raises(RobotLoadError, match=words):
                Robot.load(path, package_dirs=[src])
    finally:
        link.unlink()
        secret.unlink()


def test_a_robot_loads_through_ros_package_path_and_ament_prefix_path(src, tmp_path, monkeypatch):
    prefix = tmp_path / "install"
    mesh_package(prefix / "share" / "ament_meshes", "ament_meshes")
    ros = tmp_path / "ros"
    manifest(ros / "repo" / "macro_files", "ros_macros")
    (ros / "repo" / "macro_files" / "urdf").mkdir()
    shutil.copy(MACROS, ros / "repo" / "macro_files" / "urdf" / "macros.xacro")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ros))
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(prefix))
    text = ARM.replace("$(find ws_arm_macros)", "$(find ros_macros)")
    folder = tmp_path / "robot"
    path = write_arm(
        folder,
        text.replace("package://ws_meshes", "package://ament_meshes"),
        TOOL.replace("package://ws_meshes", "package://ament_meshes"),
    )
    robot = Robot.load(path, package_dirs=[folder])
    assert robot.nq == N_JOINTS
    paths = [g.meshPath for g in robot.collision_model.geometryObjects if ".stl" in g.meshPath]
    box = (prefix / "share" / "ament_meshes" / "meshes" / "box.stl").resolve()
    assert paths == [str(box), str(box)]


def test_a_package_dir_that_is_a_package_lets_its_files_include_each_other(tmp_path):
    """``package_dirs=[pkg]`` (a package itself): its xacro files read the whole package."""
    package = tmp_path / "ws_single"
    mesh_package(package, "ws_single")
    (package / "common").mkdir()
    (package / "common" / "tool.xacro").write_text(TOOL.replace("ws_meshes", "ws_single"))
    text = ARM.replace("inc/tool.xacro", "../common/tool.xacro").replace("ws_meshes", "ws_single")
    (package / "urdf").mkdir()
    (package / "urdf" / "arm.urdf.xacro").write_text(
        text.replace("$(find ws_arm_macros)/urdf", "../common")
    )
    shutil.copy(MACROS, package / "common" / "macros.xacro")
    robot = Robot.load(package / "urdf" / "arm.urdf.xacro", package_dirs=[package])
    assert robot.nq == N_JOINTS
    box = str((package / "meshes" / "box.stl").resolve())
    assert [g.meshPath for g in robot.collision_model.geometryObjects].count(box) == 2


def test_a_package_directly_in_the_folder_does_not_hide_a_namesake_below(tmp_path):
    # franka_description (ROS 2) cloned into src/ next to franka_ros, which holds a
    # franka_description of its own: colcon refuses the pair, so does clik, rather
    # than reading the one directly in src/ for a robot of the other.
    direct = manifest(tmp_path / "franka_description", "franka_description")
    nested = manifest(tmp_path / "franka_ros" / "franka_description", "franka_description")
    with pytest.raises(InputError, match="one package named 'franka_description'") as caught:
        PackageDirs([tmp_path]).find("franka_description")
    assert caught.value.field == "package_dirs"
    assert str(direct) in str(caught.value) and str(nested) in str(caught.value)
    (nested.parent / "COLCON_IGNORE").touch()  # the way out the message gives
    found = PackageDirs([tmp_path]).find("franka_description")
    assert found is not None and found.folder == direct.parent.resolve()


def test_a_folder_named_otherwise_than_its_package_is_still_found_directly(tmp_path):
    # example-robot-data's folder and package names differ: no search, as before.
    manifest(tmp_path / "example-robot-data", "example_robot_data")
    manifest(tmp_path / "copy" / "example-robot-data", "example-robot-data")
    found = PackageDirs([tmp_path]).find("example-robot-data")
    assert found is not None and found.folder == (tmp_path / "example-robot-data").resolve()


def test_an_unsearchable_folder_keeps_the_package_found_directly(tmp_path, monkeypatch):
    manifest(tmp_path / "pkg_a", "pkg_a")
    (tmp_path / "deep" / "a" / "b" / "c").mkdir(parents=True)
    monkeypatch.setattr(packages, "MAX_PACKAGE_DEPTH", 1)
    found = PackageDirs([tmp_path]).find("pkg_a")
    assert found is not None and found.folder == (tmp_path / "pkg_a").resolve()
    with pytest.raises(InputError, match="MAX_PACKAGE_DEPTH"):  # a search still says so
        PackageDirs([tmp_path]).find("pkg_elsewhere")


@pytest.mark.parametrize("given", ["SRC", "src"], ids=["absolute-string", "relative-string"])
def test_a_string_for_package_dirs_is_said_so(src, xacro, given, monkeypatch):
    # package_dirs="ws/src" instead of ["ws/src"]: one folder per character, "/" among
    # them; neither the filesystem root is searched nor a bare "not found" said.
    monkeypatch.chdir(src.parent)
    folder = str(src) if given == "SRC" else "src"
    with pytest.raises(InputError, match=r"a list of folders, e.g. \['ws/src'\]") as caught:
        Robot.load(xacro, package_dirs=folder)
    assert caught.value.field == "package_dirs" and folder in str(caught.value)
    with pytest.raises(InputError, match=r"a list of folders"):
        Robot.load(xacro, package_dirs=Path(folder))


def test_a_missing_package_folder_is_named_as_missing(xacro, tmp_path):
    with pytest.raises(InputError) as caught:
        Robot.load(xacro, package_dirs=[tmp_path / "scr"])
    assert f"{tmp_path / 'scr'} (no such folder)" in str(caught.value)


def test_folders_that_cannot_be_looked_into_are_skipped(tmp_path, monkeypatch):
    # As /proc/1/fdinfo for a user: Path.exists raises PermissionError there.
    manifest(tmp_path / "repo" / "pkg_ok", "pkg_ok")
    locked = tmp_path / "locked"
    manifest(locked / "pkg_locked", "pkg_locked")
    exists, is_file = Path.exists, Path.is_file

    def refused(method):
        def check(path: Path, *args, **kwargs) -> bool:
            if path.is_relative_to(locked) and path != locked:
                raise PermissionError(13, "Permission denied", str(path))
            return method(path, *args, **kwargs)

        return check

    monkeypatch.setattr(Path, "exists", refused(exists))
    monkeypatch.setattr(Path, "is_file", refused(is_file))
    dirs = PackageDirs([tmp_path])
    found = dirs.find("pkg_ok")
    assert found is not None and found.folder == (tmp_path / "repo" / "pkg_ok").resolve()
    assert dirs.find("pkg_locked") is None
