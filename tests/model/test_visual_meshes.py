"""Visual meshes are optional (issue 26, part 2): collision geometry is what counts.

A robot whose visual meshes are absent (not found, a Git LFS pointer) loads with a
:class:`~clik.MissingVisualMeshWarning` per mesh, runs with obstacles, and is drawn
with its collision geometry where its visual meshes are missing; collision meshes
stay required, and a visual mesh that is there is checked as strictly as before.
Constraint sets never read the visual model.
"""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.constraints import ConstraintSet, Obstacle
from clik.constraints.collision_scene import NoCollisionGeometryWarning
from clik.errors import RobotLoadError, shown_path
from clik.model.robot import PANDA_FINGERS
from clik.trajectory import Line
from clik.viz import build_scene, export_html
from clik.viz.robot_layer import drawn_geometry
from tests.limits_check import assert_completed
from tests.viz.test_viz import html_commands

PACKAGE = "package://arm_description/meshes"
LFS_TEXT = "version https://git-lfs.github.com/spec/v1\noid sha256:0123abcd\nsize 123456\n"
Q0 = np.array([0.0, 0.4, 0.9, 0.7])
"""A bent start [rad]: the elbow (link l3) passes near the ball as the tip moves."""
BALL = Obstacle("ball", "sphere", [0.2, 0.12, 0.6], radius=0.04)
THRESHOLD = 0.03
"""Obstacle threshold [m]: the run keeps its links this far from the ball."""


def write_box_stl(path: Path, half: tuple[float, float, float]) -> Path:
    """A binary STL of a box of half sizes ``half`` [m] about its origin."""
    path.parent.mkdir(parents=True, exist_ok=True)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1)]
    faces += [(2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    data = bytearray(b"\0" * 80 + struct.pack("<I", len(faces)))
    for face in faces:
        data += struct.pack("<3f", 0.0, 0.0, 0.0)
        for corner in face:
            data += struct.pack("<3f", *corners[corner])
        data += b"\0\0"
    path.write_bytes(bytes(data))
    return path


def link(name: str, visual: str, collision: str, z: float) -> str:
    mesh = f'<visual><geometry><mesh filename="{visual}"/></geometry></visual>'
    shape = f'<collision><origin xyz="0 0 {z}"/><geometry>{collision}</geometry></collision>'
    return f'<link name="{name}">{mesh}{shape}</link>'


def joint(name: str, parent: str, child: str, z: float, axis: str) -> str:
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 {z}"/><axis xyz="{axis}"/>'
        '<limit lower="-2.5" upper="2.5" effort="10" velocity="2.0"/></joint>'
    )


def arm_urdf(l1_collision: str = f"{PACKAGE}/collision/l1.stl", extra: str = "") -> str:
    """A 4R arm: visual meshes absent except l2's; collision boxes and one STL mesh."""
    return "\n".join(
        [
            '<robot name="arm">',
            link("base", f"{PACKAGE}/visual/base.dae", '<box size="0.2 0.2 0.1"/>', 0.0),
            joint("j1", "base", "l1", 0.1, "0 0 1"),
            link("l1", f"{PACKAGE}/visual/l1.dae", f'<mesh filename="{l1_collision}"/>', 0.05),
            joint("j2", "l1", "l2", 0.1, "0 1 0"),
            link("l2", f"{PACKAGE}/visual/l2.stl", '<box size="0.06 0.06 0.3"/>', 0.15),
            joint("j3", "l2", "l3", 0.3, "0 1 0"),
            link("l3", f"{PACKAGE}/visual/l3.dae", '<box size="0.05 0.05 0.3"/>', 0.15),
            joint("j4", "l3", "l4", 0.3, "0 1 0"),
            link("l4", "meshes/nothere.obj", '<box size="0.04 0.04 0.2"/>', 0.1),
            '<joint name="tip_joint" type="fixed"><parent link="l4"/><child link="tip"/>'
            '<origin xyz="0 0 0.2"/></joint><link name="tip"/>',
            extra,
            "</robot>",
        ]
    )


def write_workspace(root: Path, urdf: str | None = None) -> Path:
    """A package ``arm_description`` under ``root`` without its visual meshes (but l2's)."""
    package = root / "arm_description"
    write_box_stl(package / "meshes" / "collision" / "l1.stl", (0.04, 0.04, 0.05))
    write_box_stl(package / "meshes" / "visual" / "l2.stl", (0.03, 0.03, 0.15))
    (package / "meshes" / "visual" / "l3.dae").write_text(LFS_TEXT)  # cloned without git lfs
    (package / "urdf").mkdir(parents=True, exist_ok=True)
    path = package / "urdf" / "arm.urdf"
    path.write_text(arm_urdf() if urdf is None else urdf)
    return path


def load(path: Path, root: Path, **options: Any) -> clik.Robot:
    return clik.Robot.load(path, package_dirs=[root], **options)


@pytest.fixture(scope="module")
def arm(tmp_path_factory) -> tuple[clik.Robot, list[warnings.WarningMessage], Path]:
    """The arm, loaded once, with the warnings its loading gave."""
    root = tmp_path_factory.mktemp("ws")
    path = write_workspace(root)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load(path, root)
    return robot, list(caught), root


@pytest.fixture(scope="module")
def arm_run(arm) -> tuple[clik.TrackingResult, clik.TrackingResult]:
    """The tip's line past the ball, without and with obstacle rows."""
    robot = arm[0]
    pin.framesForwardKinematics(robot.model, robot.data, Q0)
    start = robot.data.oMf[robot.frame_id("tip")].translation.copy()
    line = Line(start, start + np.array([-0.05, 0.2, 0.0]), duration=1.0)
    task = clik.Task(robot, "tip", "position")
    runs = []
    for rows in (False, True):
        cs = ConstraintSet(
            robot, obstacles=[BALL], obstacle_rows=rows, obstacle_threshold=THRESHOLD
        )
        runs.append(clik.track(task, line, q0=Q0, law="pseudoinverse", constraints=cs))
    return runs[0], runs[1]


# ------------------------------------------------------------------ loading


def test_each_missing_visual_mesh_is_a_warning_naming_its_link_and_file(arm):
    robot, caught, root = arm
    package = root / "arm_description"
    missing = [w for w in caught if issubclass(w.category, clik.MissingVisualMeshWarning)]
    assert [w.filename for w in missing] == [__file__] * 4  # points at the Robot.load call
    messages = {w.message.link: str(w.message) for w in missing}
    assert sorted(messages) == ["base", "l1", "l3", "l4"]
    assert f"link 'l1': visual mesh '{PACKAGE}/visual/l1.dae' not found" in messages["l1"]
    assert f"'{PACKAGE}/visual/l3.dae' is a Git LFS pointer" in messages["l3"]
    assert str(package / "meshes" / "visual" / "l3.dae") in messages["l3"]
    assert "git lfs pull" in messages["l3"]
    looked_for = package / "urdf" / "meshes" / "nothere.obj"
    assert f"'meshes/nothere.obj' not found (looked for {looked_for})" in messages["l4"]
    assert "drawn with its collision geometry" in messages["base"]
    assert [(m.link, m.index) for m in robot.missing_visuals] == [
        ("base", 0),
        ("l1", 0),
        ("l3", 0),
        ("l4", 0),
    ]
    assert robot.visual_links == {"base", "l1", "l2", "l3", "l4"}


def test_a_long_missing_mesh_path_keeps_its_file_name(tmp_path):
    deep = "package://arm_description/" + "folder/" * 60 + "link0_visual.dae"
    path = write_workspace(tmp_path, arm_urdf().replace(f"{PACKAGE}/visual/l1.dae", deep))
    with pytest.warns(clik.MissingVisualMeshWarning) as caught:
        load(path, tmp_path)
    (l1,) = [w.message for w in caught if w.message.link == "l1"]
    assert l1.filename == deep
    assert f"visual mesh {shown_path(deep)} not found" in str(l1)
    assert shown_path(deep).rstrip(")").endswith(("link0_visual.dae'", " characters"))


def test_collision_meshes_stay_required(tmp_path):
    missing = f"{PACKAGE}/collision/gone.stl"
    path = write_workspace(tmp_path, arm_urdf(l1_collision=missing))
    with pytest.warns(clik.MissingVisualMeshWarning), pytest.raises(RobotLoadError) as error:
        load(path, tmp_path)
    assert f"mesh file {missing!r} not found" in error.value.problem
    (tmp_path / "arm_description" / "meshes" / "collision" / "lfs.stl").write_text(LFS_TEXT)
    path.write_text(arm_urdf(l1_collision=f"{PACKAGE}/collision/lfs.stl"))
    with pytest.warns(clik.MissingVisualMeshWarning), pytest.raises(RobotLoadError) as error:
        load(path, tmp_path)
    assert "link 'l1' collision mesh" in error.value.problem
    assert "is a Git LFS pointer, not the mesh" in error.value.problem


@pytest.mark.parametrize(
    ("visual", "refusal"),
    [
        ("package://arm_description/../elsewhere/m.stl", "leaves its package folder"),
        (f"{PACKAGE}/visual/escape.stl", "which leaves its folder"),
        (f"{PACKAGE}/visual/notes.txt", "has format '.txt'"),
        (f"{PACKAGE}/visual", "is a folder, not a regular file"),
    ],
)
def test_a_visual_mesh_that_is_there_is_still_checked(tmp_path, visual, refusal):
    """Only a missing visual mesh is a warning: one that is there obeys every rule."""
    outside = write_box_stl(tmp_path / "elsewhere" / "m.stl", (0.1, 0.1, 0.1))
    path = write_workspace(tmp_path / "ws", arm_urdf().replace(f"{PACKAGE}/visual/l2.stl", visual))
    (tmp_path / "ws" / "arm_description" / "meshes" / "visual" / "escape.stl").symlink_to(outside)
    (tmp_path / "ws" / "arm_description" / "meshes" / "visual" / "notes.txt").write_text("x")
    with pytest.warns(clik.MissingVisualMeshWarning), pytest.raises(RobotLoadError) as error:
        load(path, tmp_path / "ws")
    assert refusal in error.value.problem
    assert error.value.line == 6  # l2's line


def test_a_broken_symlink_is_a_missing_visual_mesh(tmp_path):
    path = write_workspace(tmp_path)
    link_path = tmp_path / "arm_description" / "meshes" / "visual" / "l2.stl"
    link_path.unlink()
    link_path.symlink_to(tmp_path / "nowhere.stl")
    with pytest.warns(clik.MissingVisualMeshWarning) as caught:
        robot = load(path, tmp_path)
    (l2,) = [str(w.message) for w in caught if w.message.link == "l2"]
    assert f"{link_path} is a broken symbolic link" in l2
    assert robot.visual_model.ngeoms == 0  # every visual mesh missing: nothing left


# ------------------------------------------------------------------ the visual model


def test_the_visual_model_leaves_the_missing_meshes_out(arm):
    robot = arm[0]
    visual = robot.visual_model  # Pinocchio would throw on the missing meshes
    frames = robot.model.frames
    assert [frames[go.parentFrame].name for go in visual.geometryObjects] == ["l2"]
    assert visual.geometryObjects[0].meshPath.endswith("arm_description/meshes/visual/l2.stl")


def test_a_locked_robot_leaves_them_out_too(arm):
    robot, _, root = arm
    with pytest.warns(clik.MissingVisualMeshWarning):
        locked = load(robot.source_path, root, lock={"j4": 0.3})
    assert locked.nq == 3 and locked.missing_visuals == robot.missing_visuals
    (go,) = locked.visual_model.geometryObjects
    assert locked.model.frames[go.parentFrame].name == "l2"


def test_a_file_changed_since_loading_is_refused(tmp_path):
    path = write_workspace(tmp_path)
    with pytest.warns(clik.MissingVisualMeshWarning):
        robot = load(path, tmp_path)
    path.write_text(arm_urdf().replace("l2.stl", "l2.dae"))
    with pytest.raises(RobotLoadError, match="changed since the robot was loaded"):
        robot.visual_model  # noqa: B018 (the property reads the file)


# ------------------------------------------------------------------ constraint sets


@pytest.mark.parametrize("name", ["arm", "panda"])
def test_a_constraint_set_never_builds_the_visual_model(arm, name, monkeypatch):
    """Obstacle and self-collision rows use collision geometry only (no DAE parsing)."""

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a constraint set read the visual model")

    monkeypatch.setattr("clik.model.robot.read_visual_model", refuse)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", clik.MissingVisualMeshWarning)
        if name == "panda":
            robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
        else:
            robot = load(arm[0].source_path, arm[2])
    cs = ConstraintSet(robot, obstacles=[BALL], self_collision=True)
    assert cs.scene is not None and cs.scene.n_links > 0
    assert robot._visual_model is None
    assert robot.visual_links is not None and len(robot.visual_links) >= 5
    with pytest.raises(AssertionError, match="read the visual model"):
        robot.visual_model  # noqa: B018 (the reader was replaced: it would have been called)


def test_links_drawn_without_collision_geometry_are_still_reported(tmp_path):
    box = '<geometry><box size="0.1 0.1 0.01"/></geometry>'
    flange = f'<link name="flange"><visual>{box}</visual></link>'
    extra = joint("j5", "tip", "flange", 0.0, "0 0 1") + flange
    path = write_workspace(tmp_path, arm_urdf(extra=extra))
    with pytest.warns(clik.MissingVisualMeshWarning):
        robot = load(path, tmp_path)
    with pytest.warns(NoCollisionGeometryWarning, match=r"obstacles\): flange$"):
        cs = ConstraintSet(robot, obstacles=[BALL])
    assert cs.scene is not None and cs.scene.links_without_geometry == ["flange"]
    assert robot._visual_model is None


# ------------------------------------------------------------------ runs and the view


def test_runs_with_obstacles_to_completed(arm, arm_run):
    robot = arm[0]
    free, kept = arm_run
    assert free.summary()["min_obstacle_distance"] < THRESHOLD - 0.005  # the ball is in the way
    assert_completed(kept, robot)
    assert kept.summary()["min_obstacle_distance"] >= THRESHOLD - 1e-3
    assert np.nanmin(kept.min_obstacle_distance) >= 0.0


def test_the_view_draws_collision_geometry_where_visual_meshes_are_missing(arm, arm_run, tmp_path):
    robot = arm[0]
    drawn = drawn_geometry(robot, "visual")
    frames = robot.model.frames
    by_link = {frames[go.parentFrame].name: go for go in drawn.geometryObjects}
    assert sorted(by_link) == ["base", "l1", "l2", "l3", "l4"]
    assert by_link["l2"].meshPath.endswith("meshes/visual/l2.stl")  # its visual mesh
    assert by_link["l1"].meshPath.endswith("meshes/collision/l1.stl")  # stand-ins
    for name in ("base", "l3", "l4"):
        assert isinstance(by_link[name].geometry, coal.Box)

    path = export_html(arm_run[1], tmp_path / "scene.html")
    objects = {
        c["path"]: c["object"]["geometries"][0]
        for c in html_commands(path)
        if c["type"] == "set_object" and c["path"].startswith("/meshcat/robot/")
    }
    by_joint = {re.sub(r"^/meshcat/robot/([^/]+)/.*", r"\1", p): g for p, g in objects.items()}
    assert sorted(by_joint) == ["j1", "j2", "j3", "j4", "universe"]
    assert (by_joint["j3"]["type"], by_joint["j3"]["depth"]) == ("BoxGeometry", 0.3)
    assert (by_joint["j4"]["type"], by_joint["j4"]["depth"]) == ("BoxGeometry", 0.2)
    assert by_joint["j2"]["type"] == by_joint["j1"]["type"] == "BufferGeometry"
    assert len(build_scene(arm_run[1], geometry="collision").robot_nodes) == 4


def test_a_link_with_one_visual_mesh_missing_is_drawn_whole_with_collision(tmp_path):
    """Two visuals on l2, the second one missing: the visual model keeps the first, the
    view draws l2's collision box (a link is never half drawn)."""
    present = f'<visual><geometry><mesh filename="{PACKAGE}/visual/l2.stl"/></geometry></visual>'
    gone = (
        f'<visual><geometry><mesh filename="{PACKAGE}/visual/l2_detail.dae"/></geometry></visual>'
    )
    urdf = arm_urdf().replace(present, present + gone + present)
    path = write_workspace(tmp_path, urdf)
    with pytest.warns(clik.MissingVisualMeshWarning):
        robot = load(path, tmp_path)
    assert ("l2", 1) in [(m.link, m.index) for m in robot.missing_visuals]
    frames = robot.model.frames
    kept = [frames[go.parentFrame].name for go in robot.visual_model.geometryObjects]
    assert kept == ["l2", "l2"]  # the first and third <visual>
    (l2,) = [
        go for go in drawn_geometry(robot).geometryObjects if frames[go.parentFrame].name == "l2"
    ]
    assert isinstance(l2.geometry, coal.Box)
    assert drawn_geometry(robot, "collision") is robot.collision_model


def test_a_xacro_robot_leaves_its_missing_visual_meshes_out(tmp_path):
    """The expanded text is what is checked and what the visual model is read from."""
    write_workspace(tmp_path)
    xacro = tmp_path / "arm_description" / "urdf" / "arm.urdf.xacro"
    xacro.write_text(
        arm_urdf()
        .replace(
            '<robot name="arm">', '<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        )
        .replace("meshes/nothere.obj", "$(find arm_description)/meshes/${'nothere'}.obj")
    )
    with pytest.warns(clik.MissingVisualMeshWarning) as caught:
        robot = load(xacro, tmp_path)
    assert robot.urdf_text is not None
    messages = [str(w.message) for w in caught if w.message.link == "l4"]
    assert [f"{tmp_path}/arm_description/meshes/nothere.obj' not found" in m for m in messages] == [
        True
    ]
    frames = robot.model.frames
    assert [frames[go.parentFrame].name for go in robot.visual_model.geometryObjects] == ["l2"]
