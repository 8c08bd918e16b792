"""Xacro robot descriptions: expansion, the model it gives, scenarios, and the errors.

The test robot is ``tests/data/xacro/clik_xacro_demo``: a package whose
``urdf/arm.urdf.xacro`` includes ``$(find clik_xacro_demo)/urdf/macros.xacro``
(properties, recursive macros) and takes two arguments, ``n_links`` (7) and
``link_length`` (0.2 m). ``urdf/arm.urdf`` is its expansion with those values,
committed once.
"""

from __future__ import annotations

import json
import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import xacro
from xacro import substitution_args

from clik import InputError, RobotLoadError, ScenarioError
from clik.cli import main
from clik.model.robot import Robot
from clik.model.xacro_expand import XacroWarning, expand_xacro, is_xacro
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario
from clik.sweep.worker import cached_robot, robot_key
from clik.viz.target import load_target
from tests.limits_check import assert_summary_within_limits, assert_within_limits

DATA = Path(__file__).parents[1] / "data" / "xacro"
PACKAGE = DATA / "clik_xacro_demo"
ARM_XACRO = PACKAGE / "urdf" / "arm.urdf.xacro"
ARM_URDF = PACKAGE / "urdf" / "arm.urdf"
SCENARIO = DATA / "arm_xacro.toml"
COMMITTED_ARGS = {"n_links": "7", "link_length": "0.2"}
BASE_HEIGHT = 0.1  # [m] the first joint's height in arm.urdf.xacro
MODEL_TOL = 1e-12  # the same numbers, printed and read back
OBSTACLE_THRESHOLD = 0.05  # [m] arm_xacro.toml's constraints.obstacles.threshold
CLEARANCE_TOL = 1e-3  # [m] how far below the threshold a link may come

HEAD = '<?xml version="1.0"?>\n<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
TAIL = (
    '<link name="a"/><link name="b"/>\n<joint name="j" type="revolute"><parent link="a"/>'
    '<child link="b"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n</robot>\n'
)


def xacro_file(folder: Path, body: str, name: str = "pkg/urdf/r.urdf.xacro") -> Path:
    """A one-joint xacro robot with ``body`` before its links."""
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(HEAD + body + "\n" + TAIL, encoding="utf-8")
    return path


def assert_same_model(a: pin.Model, b: pin.Model) -> None:
    """Same joints, limits, inertias and frames, to rounding."""
    assert list(a.names) == list(b.names)
    assert (a.nq, a.nv, a.njoints, a.nframes) == (b.nq, b.nv, b.njoints, b.nframes)
    assert [j.shortname() for j in a.joints] == [j.shortname() for j in b.joints]
    for name in ("lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=MODEL_TOL)
    assert list(a.parents) == list(b.parents)
    for pa, pb in zip(a.jointPlacements, b.jointPlacements, strict=True):
        np.testing.assert_allclose(pa.homogeneous, pb.homogeneous, atol=MODEL_TOL)
    for ia, ib in zip(a.inertias, b.inertias, strict=True):
        assert ia.mass == pytest.approx(ib.mass, abs=MODEL_TOL)
        np.testing.assert_allclose(ia.lever, ib.lever, atol=MODEL_TOL)
        np.testing.assert_allclose(ia.inertia, ib.inertia, atol=MODEL_TOL)
    for fa, fb in zip(a.frames, b.frames, strict=True):
        assert (fa.name, fa.parentJoint, fa.type) == (fb.name, fb.parentJoint, fb.type)
        np.testing.assert_allclose(fa.placement.homogeneous, fb.placement.homogeneous, atol=1e-12)


def assert_same_geometry(a: pin.GeometryModel, b: pin.GeometryModel) -> None:
    assert [g.name for g in a.geometryObjects] == [g.name for g in b.geometryObjects]
    for ga, gb in zip(a.geometryObjects, b.geometryObjects, strict=True):
        assert type(ga.geometry) is type(gb.geometry)
        assert ga.parentJoint == gb.parentJoint
        np.testing.assert_allclose(ga.placement.homogeneous, gb.placement.homogeneous, atol=1e-12)


@pytest.fixture(scope="module")
def arm() -> Robot:
    return Robot.load(ARM_XACRO, xacro_args=COMMITTED_ARGS)


# ------------------------------------------------------------------ the model


@pytest.mark.parametrize("args", [COMMITTED_ARGS, None], ids=["given", "defaults"])
def test_xacro_model_equals_the_committed_expansion(args):
    robot = Robot.load(ARM_XACRO, xacro_args=args)
    urdf = Robot.load(ARM_URDF)
    assert robot.joint_names == [f"j{i}" for i in range(1, 8)]
    assert_same_model(robot.model, urdf.model)
    assert_same_geometry(robot.collision_model, urdf.collision_model)
    assert_same_geometry(robot.visual_model, urdf.visual_model)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = robot.random_configuration(rng)
        for r in (robot, urdf):
            pin.framesForwardKinematics(r.model, r.data, q)
        tool = robot.frame_id("tool")
        np.testing.assert_allclose(
            robot.data.oMf[tool].homogeneous, urdf.data.oMf[tool].homogeneous, atol=1e-12
        )


def test_committed_urdf_is_the_expansion_of_the_xacro():
    """``arm.urdf`` is still what the xacro gives (regenerate it if this fails)."""
    expanded = expand_xacro(ARM_XACRO, COMMITTED_ARGS, [DATA])
    banner = 5  # xacro's comment lines, which hold the file's path
    body = ARM_URDF.read_text(encoding="utf-8").splitlines()[banner:]
    assert expanded.splitlines()[banner:] == body


def test_arguments_change_the_model():
    length = 0.25  # [m]
    robot = Robot.load(ARM_XACRO, xacro_args={"n_links": "5", "link_length": str(length)})
    assert robot.joint_names == [f"j{i}" for i in range(1, 6)]
    heights = [p.translation[2] for p in robot.model.jointPlacements[1:]]
    np.testing.assert_allclose(heights, [BASE_HEIGHT] + [length] * 4, atol=MODEL_TOL)
    pin.framesForwardKinematics(robot.model, robot.data, np.zeros(robot.nq))
    tool = robot.data.oMf[robot.frame_id("tool")].translation
    np.testing.assert_allclose(tool, [0.0, 0.0, BASE_HEIGHT + 5 * length], atol=MODEL_TOL)
    density, radius = 2700.0, 0.03  # macros.xacro
    mass = density * np.pi * radius**2 * length
    np.testing.assert_allclose([i.mass for i in robot.model.inertias[1:]], [mass] * 5)
    axes = [j.shortname() for j in robot.model.joints[1:]]
    assert axes == ["JointModelRZ", "JointModelRY", "JointModelRZ", "JointModelRY", "JointModelRZ"]


def test_the_robot_keeps_its_xacro_file_arguments_and_text(arm):
    assert arm.name == "arm"
    assert arm.source_path == ARM_XACRO.resolve()
    assert arm.xacro_args == COMMITTED_ARGS
    assert arm.urdf_text is not None and '<joint name="j7" type="revolute">' in arm.urdf_text
    locked = Robot.load(ARM_XACRO, xacro_args=COMMITTED_ARGS, lock={"j7": 0.0})
    assert locked.nq == 6
    assert (locked.xacro_args, locked.urdf_text) == (arm.xacro_args, arm.urdf_text)
    assert len(locked.visual_model.geometryObjects) == len(arm.visual_model.geometryObjects)
    assert Robot.load(ARM_URDF).urdf_text is None


def test_visual_geometry_comes_from_the_expanded_text(tmp_path):
    """The xacro file is not read again: removing it after loading changes nothing."""
    shutil.copytree(PACKAGE, tmp_path / "clik_xacro_demo")
    copy = tmp_path / "clik_xacro_demo" / "urdf" / "arm.urdf.xacro"
    robot = Robot.load(copy)
    copy.unlink()
    (copy.parent / "macros.xacro").unlink()
    visuals = robot.visual_model.geometryObjects
    assert len(visuals) == 8  # 7 cylinders and the tool's mesh
    mesh = Path(visuals[-1].meshPath).resolve()
    assert mesh == (tmp_path / "clik_xacro_demo" / "meshes" / "tip.stl").resolve()


def test_xacro_is_left_as_it_was(tmp_path):
    """The scoped replacements inside xacro are undone, after success and after an error."""
    before = (xacro.parse, substitution_args._eval_find, substitution_args._eval_dict["find"])
    Robot.load(ARM_XACRO)
    with pytest.raises(InputError):
        Robot.load(ARM_XACRO, package_dirs=[tmp_path])
    after = (xacro.parse, substitution_args._eval_find, substitution_args._eval_dict["find"])
    assert after == before
    assert "open" not in vars(xacro)
    assert xacro.substitution_args_context["arg"] == {}


def test_threads_expand_one_at_a_time():
    counts = [3, 4, 5, 6, 7, 3, 4, 5]
    with ThreadPoolExecutor(4) as pool:
        robots = list(
            pool.map(lambda n: Robot.load(ARM_XACRO, xacro_args={"n_links": str(n)}), counts)
        )
    assert [r.nq for r in robots] == counts


def test_xacro_messages_become_warnings(tmp_path):
    path = xacro_file(tmp_path, '<xacro:property name="pi" value="3"/>')
    with pytest.warns(XacroWarning, match="redefining global symbol: pi"):
        Robot.load(path)


def test_is_xacro():
    assert is_xacro("a/arm.urdf.xacro") and is_xacro("arm.xacro")
    assert not is_xacro("arm.urdf") and not is_xacro("xacro")


# ------------------------------------------------------------------ errors


def test_missing_argument_names_it_and_xacro_args(tmp_path):
    path = xacro_file(tmp_path, '<link name="c"><inertial><mass value="$(arg mass)"/></inertial>')
    path.write_text(path.read_text().replace("</inertial>", "</inertial></link>"))
    with pytest.raises(InputError) as caught:
        Robot.load(path)
    assert caught.value.field == "xacro_args"
    assert "the xacro argument 'mass'" in str(caught.value)
    assert "declares no default" in str(caught.value)


def test_an_argument_used_before_its_declaration_is_said_so(tmp_path):
    body = (
        '<link name="c"><inertial><mass value="$(arg mass)"/></inertial></link>\n'
        '<xacro:arg name="mass" default="1.0"/>'
    )
    with pytest.raises(InputError) as caught:
        Robot.load(xacro_file(tmp_path, body))
    message = str(caught.value)
    assert "or its declaration moved up" in message and "declares no default" not in message
    assert "line 4 declares it with a default" in message  # the <xacro:arg> line


def test_a_misspelt_argument_is_named_when_the_expansion_fails(tmp_path):
    """A misspelt name leaves the real argument without a value: the misspelling is the
    error, not the failure it causes further on."""
    body = (
        '<xacro:arg name="mass"/>\n'
        '<link name="c"><inertial><mass value="$(arg mass)"/></inertial></link>'
    )
    with pytest.raises(InputError) as caught:
        Robot.load(xacro_file(tmp_path, body), xacro_args={"mas": "2.0"})
    message = str(caught.value)
    assert caught.value.field == "xacro_args" and "{'mas': '2.0'}" in message
    assert "declares or uses ('mass')" in message and "the expansion then failed" in message
    assert "did you mean 'mass' for 'mas'?" in message


def test_unknown_argument_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"xacro_args: expected arguments that .* \('link_length'"):
        Robot.load(ARM_XACRO, xacro_args={"n_link": "5"})
    with pytest.raises(InputError, match=r"did you mean 'n_links' for 'n_link'\?"):
        Robot.load(ARM_XACRO, xacro_args={"n_link": "5"})
    with pytest.raises(InputError) as caught:
        Robot.load(ARM_XACRO, xacro_args={"colour": "5"})
    assert "did you mean" not in str(caught.value)  # nothing close


@pytest.mark.parametrize("args", [{"n_links": 5}, {"n_links": ["5"]}, "n_links:=5"])
def test_arguments_must_be_strings(args):
    with pytest.raises(InputError, match="xacro_args: expected a table of strings"):
        Robot.load(ARM_XACRO, xacro_args=args)


def test_xacro_args_on_a_plain_urdf_or_a_name():
    for source in (ARM_URDF, "planar4r"):
        with pytest.raises(InputError, match="xacro_args: expected a xacro source"):
            Robot.load(source, xacro_args={"n_links": "5"})


def test_unknown_package_names_it_and_the_folders_searched(tmp_path):
    with pytest.raises(InputError) as caught:
        Robot.load(ARM_XACRO, package_dirs=[tmp_path])
    message = str(caught.value)
    assert caught.value.field == "package_dirs"
    assert "'clik_xacro_demo'" in message and str(tmp_path) in message
    assert "$(find clik_xacro_demo)" in message


@pytest.mark.parametrize(
    "include",
    ["../../secret.xacro", "$(find pkg)/../secret.xacro", "/etc/hostname", "link.xacro"],
    ids=["relative", "find-then-up", "absolute", "symlink"],
)
def test_an_include_may_not_leave_its_package(tmp_path, include):
    (tmp_path / "secret.xacro").write_text(HEAD + TAIL)
    path = xacro_file(tmp_path, f'<xacro:include filename="{include}"/>')
    (path.parent / "link.xacro").symlink_to(tmp_path / "secret.xacro")
    with pytest.raises(RobotLoadError, match="which leaves the folders a xacro file may read"):
        Robot.load(path, package_dirs=[tmp_path])


def test_an_include_inside_the_package_is_read(tmp_path):
    (tmp_path / "pkg" / "common").mkdir(parents=True)
    (tmp_path / "pkg" / "common" / "p.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:property name="upper" value="0.5"/></robot>'
    )
    body = '<xacro:include filename="../common/p.xacro"/>'
    path = xacro_file(tmp_path, body)
    path.write_text(path.read_text().replace('upper="1"', 'upper="${upper}"'))
    robot = Robot.load(path, package_dirs=[tmp_path])
    assert robot.upper.tolist() == [0.5]


def test_yaml_files_stay_inside_the_package_too(tmp_path):
    (tmp_path / "limits.yaml").write_text("upper: 0.5\n")
    body = '<xacro:property name="y" value="${xacro.load_yaml(\'../../limits.yaml\')}"/>'
    path = xacro_file(tmp_path, body)
    path.write_text(path.read_text().replace('upper="1"', 'upper="${y.upper}"'))
    with pytest.raises(RobotLoadError, match=r"limits\.yaml.*which leaves the folders"):
        Robot.load(path)


@pytest.mark.parametrize(
    ("body", "words"),
    [
        (
            '<link name="c" v="${undefined_property}"/>',
            ["name 'undefined_property' is not defined"],
        ),
        ('<xacro:call macro="nothere"/>', ["unknown macro name: xacro:nothere"]),
        ('<link name="c" v="${1 +}"/>', ["invalid syntax", "1 +"]),
    ],
    ids=["undefined-property", "undefined-macro", "bad-expression"],
)
def test_xacro_errors_name_the_file_and_xacro_message(tmp_path, body, words):
    path = xacro_file(tmp_path, body)
    with pytest.raises(RobotLoadError) as caught:
        Robot.load(path)
    message = str(caught.value)
    assert str(path) in message and "xacro cannot expand it" in message
    for word in words:
        assert word in message
    assert "Traceback" not in message


def test_an_error_in_an_included_file_names_both_files(tmp_path):
    inner = tmp_path / "pkg" / "urdf" / "inner.xacro"
    inner.parent.mkdir(parents=True)
    inner.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><c v="${nope}"/></robot>')
    path = xacro_file(tmp_path, '<xacro:include filename="inner.xacro"/>')
    with pytest.raises(RobotLoadError, match=r"\(in .*inner.xacro, included from .*r.urdf.xacro\)"):
        Robot.load(path)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("<robot><link", ["inner.xacro", "malformed XML", "included by"]),
        (
            '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY e "x">]>\n<robot/>',
            ["inner.xacro, line 2", "declares XML entities"],
        ),
        ("", ["inner.xacro", "file is empty"]),
    ],
    ids=["malformed", "entity", "empty"],
)
def test_included_files_are_read_strictly(tmp_path, text, words):
    path = xacro_file(tmp_path, '<xacro:include filename="inner.xacro"/>')
    (path.parent / "inner.xacro").write_text(text)
    with pytest.raises(RobotLoadError) as caught:
        Robot.load(path)
    for word in words:
        assert word in str(caught.value)


def test_the_expanded_urdf_is_checked_like_any_urdf(tmp_path):
    path = xacro_file(tmp_path, '<xacro:property name="low" value="2"/>')
    path.write_text(path.read_text().replace('lower="-1"', 'lower="${low}"'))
    with pytest.raises(RobotLoadError) as caught:
        Robot.load(path)
    message = str(caught.value)
    assert "r.urdf.xacro (as expanded by xacro), line" in message
    assert "joint 'j' has lower limit 2 above its upper limit 1" in message


def test_missing_xacro_file():
    with pytest.raises(RobotLoadError, match=r"nothere\.urdf\.xacro: file not found"):
        Robot.load(DATA / "nothere.urdf.xacro")


# ------------------------------------------------------------------ scenarios


def scenario_text(**robot: str) -> str:
    """arm_xacro.toml with its ``[robot]`` keys replaced (TOML values as written)."""
    text = SCENARIO.read_text(encoding="utf-8")
    head, rest = text.split("[robot]\n", 1)
    rest = rest.split("\n\n", 1)[1]
    keys = "".join(f"{k} = {v}\n" for k, v in robot.items())
    return f"{head}[robot]\n{keys}\n{rest}"


def write_scenario(folder: Path, **robot: str) -> Path:
    path = folder / "s.toml"
    path.write_text(scenario_text(**robot), encoding="utf-8")
    return path


def test_scenario_reads_xacro_args_relative_to_its_file():
    scenario = load_scenario(SCENARIO)
    assert scenario.robot["xacro_args"] == COMMITTED_ARGS
    assert Path(scenario.robot["source"]).resolve() == ARM_XACRO.resolve()
    assert [Path(p).resolve() for p in scenario.robot["package_dirs"]] == [DATA.resolve()]


@pytest.mark.parametrize(
    ("robot", "words"),
    [
        (
            {"source": f'"{ARM_XACRO}"', "xacro_args": "{ n_links = 7 }"},
            ["robot.xacro_args.n_links: expected a string, got 7"],
        ),
        (
            {"source": f'"{ARM_XACRO}"', "xacro_args": '"n_links:=7"'},
            ["robot.xacro_args: expected a table, got 'n_links:=7'"],
        ),
        (
            {"source": f'"{ARM_URDF}"', "xacro_args": '{ n_links = "7" }'},
            ["robot.xacro_args", "robot.source is not a xacro file"],
        ),
        (
            {"source": f'"{ARM_XACRO}"', "xacro_args": '{ n_link = "7" }'},
            ["robot.xacro_args: expected arguments that", "'n_links'", "got {'n_link': '7'}"],
        ),
        (
            {"source": f'"{ARM_XACRO}"', "package_dirs": '["/nowhere"]'},
            ["robot.package_dirs", "'clik_xacro_demo'", "/nowhere"],
        ),
    ],
    ids=["arg-not-a-string", "args-not-a-table", "args-on-a-urdf", "unknown-arg", "no-package"],
)
def test_bad_xacro_scenarios(tmp_path, robot, words):
    with pytest.raises(ScenarioError) as caught:
        build(write_scenario(tmp_path, **robot))
    for word in words:
        assert word in str(caught.value)


def test_missing_argument_in_a_scenario(tmp_path):
    path = xacro_file(tmp_path, '<link name="c"><inertial><mass value="$(arg mass)"/></inertial>')
    path.write_text(path.read_text().replace("</inertial>", "</inertial></link>"))
    with pytest.raises(ScenarioError, match=r"robot.xacro_args: .*xacro argument 'mass'"):
        build(write_scenario(tmp_path, source=f'"{path}"'))


def test_clik_solve_runs_a_xacro_scenario(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["solve", str(SCENARIO), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["max_task_error"] < 1e-3  # [m]
    robot = Robot.load(ARM_XACRO, xacro_args=COMMITTED_ARGS)
    assert len(summary["joint_min"]) == robot.nq == 7
    assert_summary_within_limits(summary, robot, OBSTACLE_THRESHOLD - CLEARANCE_TOL)
    result = load_target(out)  # the robot rebuilt from the scenario file
    assert result.robot.xacro_args == COMMITTED_ARGS
    assert_within_limits(result, result.robot, OBSTACLE_THRESHOLD - CLEARANCE_TOL)
    assert result.info["robot_xacro_args"] == COMMITTED_ARGS


def test_a_saved_run_rebuilds_its_xacro_robot_without_the_scenario(tmp_path):
    args = '{ n_links = "6", link_length = "0.22" }'
    scenario = write_scenario(
        tmp_path, source=f'"{ARM_XACRO}"', package_dirs=f'["{DATA}"]', xacro_args=args
    )
    scenario.write_text(
        scenario.read_text().replace("q = [0, 30, 0, 45, 0, 45, 0]", "q = [0, 30, 0, 45, 0, 45]")
    )
    out = tmp_path / "out"
    assert main(["solve", str(scenario), "--out", str(out), "--quiet"]) == 0
    scenario.unlink()
    result = load_target(out)
    assert result.robot.nq == 6
    assert result.robot.xacro_args == {"n_links": "6", "link_length": "0.22"}


def test_sweep_workers_load_xacro_robots_with_their_arguments():
    spec = load_scenario(SCENARIO).robot
    other = {**spec, "xacro_args": {"n_links": "5"}}
    assert robot_key(spec) != robot_key(other)
    assert cached_robot(spec).nq == 7
    assert cached_robot(other).nq == 5
    assert cached_robot(other) is cached_robot(other)


def test_an_error_inside_a_macro_names_the_macros_and_their_files(tmp_path):
    # kortex_description's gen3_lite_gen3_lite_2f.xacro: load_robot passes a parameter
    # ("gripper") that the arm's macro, in another file, does not take.
    inner = tmp_path / "pkg" / "urdf" / "arm_macro.xacro"
    inner.parent.mkdir(parents=True)
    inner.write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:macro name="load_arm" params="prefix"><link name="${prefix}c"/></xacro:macro>'
        "</robot>"
    )
    body = (
        '<xacro:include filename="arm_macro.xacro"/>'
        '<xacro:macro name="load_robot" params="">'
        '<xacro:load_arm prefix="" gripper="2f"/></xacro:macro><xacro:load_robot/>'
    )
    path = xacro_file(tmp_path, body)
    with pytest.raises(RobotLoadError) as caught:
        Robot.load(path)
    message = str(caught.value)
    assert 'Invalid parameter "gripper"' in message
    assert f"the macro 'load_arm' (defined in {inner})" in message
    assert f"instantiated from 'load_robot' (defined in {path})" in message
