"""The bad-input catalogue: one row per kind of bad input, its error class and key words.

Every row runs one call the way a user would make it (``Robot.load`` on a
file, ``build`` on a scenario, ``track``/``solve`` on arrays, the command
line's ``main``) and states what must come out:

- ``Raises(cls, words)``: that exception, a :class:`clik.ClikError` (or the
  :class:`clik.StabilityWarning` turned into an error), whose message holds
  every one of ``words``;
- ``Ends(statuses, words, seconds)``: a result (tracking or solve mode) that
  stopped with a documented status, ``words`` in its reason, within a wall
  time;
- ``Exits(code, words)``: ``clik.cli.main`` returns that exit code and prints
  ``words`` on stderr, without a traceback.

Decisions recorded here:

- A start outside the robot's own joint limits is infeasible
  (:class:`clik.InfeasibleError`, exit code 3, from
  :meth:`clik.Robot.check_within_limits`); a start beyond a joint-range
  constraint's stricter override, inside the model's limits, is recovered: the
  row is active from the first sample and drives the joint back.
- A start inside an obstacle is recovered when obstacle rows are on: the row
  pushes the link out along the contact normal (recorded distances are
  negative meanwhile) and is released once the link is out.
- No scenario key refers to an obstacle by name, so "unknown names" rows cover
  frames, joints (lock, override) and links (``constraints.obstacles.links``).
"""

from __future__ import annotations

import importlib
import math
import pkgutil
import subprocess
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik import (
    GeometryError,
    InfeasibleError,
    InputError,
    JointNotFound,
    RobotLoadError,
    ScenarioError,
    StabilityWarning,
    Task,
    UnknownRobotError,
    solve,
    track,
)
from clik.cli import main
from clik.constraints import ConstraintSet, Dexterity, JointLimits, Obstacle
from clik.model.robot import Robot
from clik.scenarios import scenario_path
from clik.scenarios.runner import build, run_scenario
from clik.speed.velocity_limits import track_within_limits
from clik.trajectory import Hold, Line
from tests.urdf_snippets import J1, J2, LINKS, urdf_text

DATA = Path(__file__).parents[1] / "data"
ARM_XACRO = DATA / "xacro" / "clik_xacro_demo" / "urdf" / "arm.urdf.xacro"
CASE = scenario_path("case_study_both").read_text()
Q0 = np.radians([180.0, -30.0, -90.0, -30.0])
GOAL = [0.8, -0.2, 0.0]
CLEARANCE_TOL = 1e-3  # [m] how far below d_o a recovered link may end


def with_link_geometry(geometry: str, inertial: str = "") -> str:
    link = (
        f'<link name="l1">{inertial}<collision><geometry>{geometry}</geometry></collision></link>'
    )
    return urdf_text(LINKS.replace('<link name="l1"/>', link) + J1 + J2)


def xacro_file(env: Env, body: str) -> Path:
    """A xacro robot (``pkg/urdf/r.urdf.xacro``): the small URDF with ``body`` added."""
    text = urdf_text(LINKS + J1 + J2 + body).replace(
        '<robot name="r">', '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
    )
    return env.file(text, "pkg/urdf/r.urdf.xacro")


XACRO_ARG_MASS = '<link name="c"><inertial><mass value="$(arg mass)"/></inertial></link>'
"""A xacro body that needs the argument ``mass`` (declared nowhere, no default)."""


# ------------------------------------------------------------------ expectations


@dataclass(frozen=True)
class Raises:
    """The call raises ``error`` with every one of ``words`` in its message."""

    error: type[BaseException]
    words: Sequence[str]


@dataclass(frozen=True)
class Ends:
    """The call returns a result with one of ``statuses``, ``words`` in its reason."""

    statuses: Sequence[str]
    words: Sequence[str] = ()
    seconds: float = 10.0
    check: Callable[[Any], None] | None = None


@dataclass(frozen=True)
class Exits:
    """``clik.cli.main`` returns ``code``; stderr holds ``words`` and no traceback."""

    code: int
    words: Sequence[str] = ()


@dataclass
class Env:
    """What a row's call may use: a scratch folder, the planar arm, capture, patching."""

    tmp: Path
    robot: Robot
    capsys: Any
    monkeypatch: Any

    def file(self, text: str | bytes, name: str = "r.urdf") -> Path:
        path = self.tmp / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8")
        return path

    def scenario(self, old: str, new: str, base: str = CASE) -> Path:
        assert old in base, f"the base scenario has no {old!r}"
        return self.file(base.replace(old, new, 1), "s.toml")

    def task(self) -> Task:
        return Task(self.robot, "tip", "position", axes=["x", "y"])

    def line(self, duration: float = 0.5) -> Line:
        return Line(self.task().placement(Q0).translation, GOAL, duration=duration)

    def cli(self, *args: str) -> tuple[int, str]:
        """``clik.cli.main`` in this process: its exit code and stderr."""
        self.capsys.readouterr()
        code = main([*args])
        return code, self.capsys.readouterr().err

    def command(self, *args: str) -> tuple[int, str]:
        """``python -m clik.cli`` in a new process (warnings reach its stderr)."""
        proc = subprocess.run(
            [sys.executable, "-m", "clik.cli", *args],
            capture_output=True,
            text=True,
            check=False,
            timeout=120,
        )
        return proc.returncode, proc.stderr


def out(env: Env) -> str:
    return str(env.tmp / "out")


# ------------------------------------------------------------------ row helpers


def octahedron_obj(env: Env, squash: float = 1.0, name: str = "m.obj") -> str:
    """A small octahedron mesh; ``squash = 0`` flattens it into a plane."""
    v = 0.02 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    v[:, 2] *= squash
    faces = [(1, 3, 5), (3, 2, 5), (2, 4, 5), (4, 1, 5), (3, 1, 6), (2, 3, 6), (4, 2, 6), (1, 4, 6)]
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    text += "".join(f"f {a} {b} {c}\n" for a, b, c in faces)
    return str(env.file(text, name))


def unstable_gain(env: Env) -> None:
    """A gain above the bound: the warning comes before the first step (else the run stops)."""
    task = env.task()
    J = task.jacobian(Q0)
    gain = 1.05 * 2.0 / (1e-3 * np.linalg.eigvalsh(J @ J.T)[-1])

    def started(k: int, n: int) -> None:
        raise AssertionError("the run started before the StabilityWarning")

    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        track(task, env.line(), q0=Q0, gain=gain, dt=1e-3, progress=started)


def start_outside_limits(env: Env) -> None:
    q = np.array([0.3, 3.3, -1.0, 0.5])  # joint2 beyond pi
    track(env.task(), Hold(position=env.task().placement(q).translation, duration=0.1), q0=q)


def inside_obstacle(env: Env, law: str) -> clik.TrackingResult:
    """Link 2 starts 5 cm deep inside a sphere; obstacle rows are on."""
    robot = env.robot
    pin.forwardKinematics(robot.model, robot.data, Q0)
    center = 0.5 * (robot.data.oMi[2].translation + robot.data.oMi[3].translation)
    sphere = Obstacle("blob", "sphere", center, radius=0.05)
    constraints = ConstraintSet(robot, obstacles=[sphere], obstacle_threshold=0.03)
    return track(env.task(), env.line(), q0=Q0, law=law, constraints=constraints)


def recovered_from_obstacle(result: clik.TrackingResult) -> None:
    """A start in collision is a violation at t = 0, recovered: never crossed again."""
    assert result.min_obstacle_distance[0] < 0.0  # it did start inside
    (violation,) = result.violations
    assert violation["constraint"] == "obstacle:blob:link2" and violation["t_first"] == 0.0
    assert violation["t_last"] < 0.3  # out within a fraction of a second (law (9): 0.202 s)
    assert violation["worst"] == pytest.approx(-result.min_obstacle_distance[0])
    assert result.events[0] == {"t": 0.0, "constraint": "obstacle:blob:link2", "action": "activate"}
    assert result.min_obstacle_distance[-1] >= 0.03 - CLEARANCE_TOL


def beyond_override(env: Env) -> clik.TrackingResult:
    """joint3 at -60 deg with an override upper limit of -80 deg (the model allows pi)."""
    q = np.radians([180.0, -30.0, -60.0, -30.0])
    limits = JointLimits(env.robot, np.radians(2.0), {"joint3": {"upper": np.radians(-80.0)}})
    constraints = ConstraintSet(env.robot, joint_limits=limits)
    hold = Hold(position=env.task().placement(q).translation, duration=0.5)
    return track(env.task(), hold, q0=q, law="pseudoinverse", constraints=constraints)


def driven_back(result: clik.TrackingResult) -> None:
    """A start beyond a constraint's limit is a violation at t = 0, then driven back."""
    (violation,) = result.violations
    assert violation["constraint"] == "joint:joint3:upper" and violation["t_first"] == 0.0
    assert violation["worst"] == pytest.approx(np.radians(20.0))
    assert result.events[0]["constraint"] == "joint:joint3:upper"
    assert result.events[0]["t"] == 0.0
    assert result.q[-1, 2] <= np.radians(-80.0) + 1e-6


def velocity_section(env: Env, body: str) -> Path:
    """The case study with a ``[constraints.velocity_limits]`` table holding ``body``."""
    section = f"[constraints.velocity_limits]\n{body}\n\n[constraints.obstacles]"
    return env.scenario("[constraints.obstacles]", section)


def dexterity_section(env: Env, body: str) -> Path:
    """The case study with a ``[constraints.dexterity]`` table holding ``body``."""
    section = f"[constraints.dexterity]\n{body}\n\n[constraints.obstacles]"
    return env.scenario("[constraints.obstacles]", section)


def no_velocity_limits(env: Env) -> Path:
    """A one-joint URDF whose joint has ``velocity="0"`` (no limit), velocity limits enabled."""
    urdf = env.file(urdf_text(LINKS + J1.replace('velocity="1"', 'velocity="0"') + J2))
    text = (
        f'[robot]\nsource = "{urdf}"\n[task]\nframe = "l2"\nkind = "position"\n'
        '[trajectory]\nkind = "hold"\nduration = 0.1\n'
        "[constraints.velocity_limits]\nenabled = true\n"
    )
    return env.file(text, "s.toml")


def error_correction_too_fast(env: Env) -> clik.TrackingResult:
    """A line starting 5 cm from the tip with K = 500: K e alone exceeds the speed limits.

    Without the law's own speed limits (which would keep them: ``completed``), re-timing
    cannot slow the correction.
    """
    start = env.task().placement(Q0).translation + [0.05, 0.0, 0.0]
    line = Line(start, GOAL, duration=1.0)
    return track_within_limits(
        env.task(), line, q0=Q0, law="pseudoinverse", gain=500.0, joint_speed=None
    )


def visual_model_after(env: Env, change: str) -> None:
    """The visual model is read on first use: only from the file that was checked."""
    path = env.file(urdf_text(), "arm.urdf")
    robot = Robot.load(path)
    if change == "removed":
        path.unlink()
    else:
        path.write_text(urdf_text().replace('name="r"', 'name="other"'))
    robot.visual_model  # noqa: B018 (the property reads the file)


def internal_error(env: Env) -> tuple[int, str]:
    def broken(_scenario: object) -> None:
        raise RuntimeError("simulated bug")

    env.monkeypatch.setattr("clik.scenarios.runner.build", broken)
    return env.cli("solve", str(scenario_path("case_study_both")), "--out", out(env))


def debug_shows_the_traceback(env: Env) -> None:
    bad = env.scenario("dt = 0.001", "dt = -1")
    main(["--debug", "solve", str(bad), "--out", out(env)])


# ------------------------------------------------------------------ the catalogue

URDF = [
    pytest.param(
        lambda env: Robot.load(env.tmp / "nothere.urdf"),
        Raises(RobotLoadError, ["nothere.urdf", "file not found"]),
        id="urdf-missing-file",
    ),
    pytest.param(
        lambda env: Robot.load(env.file("  \n")),
        Raises(RobotLoadError, ["file is empty"]),
        id="urdf-empty",
    ),
    pytest.param(
        lambda env: Robot.load(env.file('<robot name="r">\n<link name="a">\n</robot>\n')),
        Raises(RobotLoadError, ["line 3", "malformed XML", "tag mismatch"]),
        id="urdf-malformed-xml",
    ),
    pytest.param(
        lambda env: Robot.load(env.tmp),
        Raises(RobotLoadError, ["is a folder, not a regular file"]),
        id="urdf-folder",
    ),
    pytest.param(
        lambda env: Robot.load(env.file(urdf_text(LINKS + J1 + J2.replace('"l2"', '"l9"')))),
        Raises(RobotLoadError, ["joint 'j2' names child link 'l9' that does not exist"]),
        id="urdf-missing-link",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(
                urdf_text(
                    '<link name="a"/><link name="b"/>'
                    '<joint name="ab" type="revolute"><parent link="a"/><child link="b"/>'
                    '<limit lower="0" upper="1"/></joint>'
                    '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>'
                )
            )
        ),
        Raises(RobotLoadError, ["the joints form a cycle through links"]),
        id="urdf-cyclic-tree",
    ),
    pytest.param(
        lambda env: Robot.load(env.file(urdf_text(LINKS + J1.replace("revolute", "fixed") + J2))),
        Raises(RobotLoadError, ["no movable (revolute, continuous or prismatic) joint"]),
        id="urdf-zero-movable-joints",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(urdf_text(LINKS + J1.replace("0 0 0.1", "0 nan 0.1") + J2))
        ),
        Raises(RobotLoadError, ["joint 'j1' origin xyz='0 nan 0.1' is not finite"]),
        id="urdf-nan-in-origin",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(
                urdf_text(LINKS + J1.replace('lower="-1" upper="1"', 'lower="1" upper="-1"') + J2)
            )
        ),
        Raises(RobotLoadError, ["joint 'j1' has lower limit 1 above its upper limit -1"]),
        id="urdf-inverted-limits",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(urdf_text(LINKS + J1.replace('effort="1"', 'effort="-1"') + J2))
        ),
        Raises(RobotLoadError, ["joint 'j1' limit effort='-1' is negative"]),
        id="urdf-negative-effort",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(urdf_text(LINKS + J1.replace('velocity="1"', 'velocity="-2"') + J2))
        ),
        Raises(RobotLoadError, ["joint 'j1' limit velocity='-2' is negative"]),
        id="urdf-negative-velocity",
    ),
    pytest.param(
        lambda env: Robot.load(env.file(with_link_geometry('<box size="0.1 -0.1 0.1"/>'))),
        Raises(RobotLoadError, ["link 'l1' collision box size='0.1 -0.1 0.1' is negative"]),
        id="urdf-negative-box",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(
                with_link_geometry(
                    '<sphere radius="0.1"/>', '<inertial><mass value="-2"/></inertial>'
                )
            )
        ),
        Raises(RobotLoadError, ["link 'l1' mass value='-2' is negative"]),
        id="urdf-negative-mass",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(with_link_geometry('<mesh filename="meshes/nothere.stl"/>'))
        ),
        Raises(RobotLoadError, ["mesh file 'meshes/nothere.stl' not found"]),
        id="urdf-unknown-mesh",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(with_link_geometry('<mesh filename="package://pkg/../../secret.stl"/>')),
            package_dirs=[env.tmp],
        ),
        Raises(RobotLoadError, ["mesh 'package://pkg/../../secret.stl' leaves its package folder"]),
        id="urdf-mesh-escapes-package",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(with_link_geometry('<mesh filename="https://example.com/l1.stl"/>'))
        ),
        Raises(RobotLoadError, ["uses an unsupported URI scheme"]),
        id="urdf-network-mesh",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(with_link_geometry(f'<mesh filename="{env.file("not a mesh", "m.stl")}"/>'))
        ),
        Raises(RobotLoadError, ["Pinocchio cannot build the model", "Could not load resource"]),
        id="urdf-mesh-not-a-mesh",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(
                '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY e "x">]>\n'
                + urdf_text().split("\n", 1)[1]
            )
        ),
        Raises(RobotLoadError, ["line 2", "declares XML entities, which are refused"]),
        id="urdf-entity-declared",
    ),
    pytest.param(
        lambda env: Robot.load(
            env.file(
                urdf_text(
                    LINKS + J1 + J2 + '<xi:include xmlns:xi="http://www.w3.org/2001/XInclude" '
                    'href="other.xml"/>'
                )
            )
        ),
        Raises(RobotLoadError, ["line 3", "XInclude elements are refused"]),
        id="urdf-xinclude",
    ),
    pytest.param(
        lambda env: visual_model_after(env, "removed"),
        Raises(RobotLoadError, ["arm.urdf", "removed or changed since the robot was loaded"]),
        id="urdf-removed-after-load",
    ),
    pytest.param(
        lambda env: visual_model_after(env, "changed"),
        Raises(RobotLoadError, ["arm.urdf", "removed or changed since the robot was loaded"]),
        id="urdf-changed-after-load",
    ),
    pytest.param(
        lambda env: Robot.load("planar5r"),
        Raises(UnknownRobotError, ["planar5r", "available robot names", "'planar4r'", "'panda'"]),
        id="robot-unknown-name",
    ),
    pytest.param(
        lambda env: Robot.load("planar4r", lock={"joint9": 0.0}),
        Raises(JointNotFound, ["joint 'joint9' not found", "available joints: 'joint1'"]),
        id="robot-lock-unknown-joint",
    ),
    pytest.param(
        lambda env: Robot.load("planar4r", lock={"joint2": 4.0}),
        Raises(InputError, ["lock['joint2']", "within the joint's limits [-3.14159, 3.14159]"]),
        id="robot-lock-outside-limits",
    ),
    pytest.param(
        lambda env: Robot.load(xacro_file(env, XACRO_ARG_MASS)),
        Raises(InputError, ["xacro_args", "the xacro argument 'mass'", "declares no default"]),
        id="xacro-missing-arg",
    ),
    pytest.param(
        lambda env: Robot.load(ARM_XACRO, package_dirs=[env.tmp]),
        Raises(InputError, ["package_dirs", "'clik_xacro_demo'", "package folders searched"]),
        id="xacro-unknown-package",
    ),
    pytest.param(
        lambda env: Robot.load(
            xacro_file(env, '<xacro:include filename="../../secret.xacro"/>'),
            package_dirs=[env.tmp],
        ),
        Raises(RobotLoadError, ["secret.xacro", "leaves the folders a xacro file may read"]),
        id="xacro-include-leaves-package",
    ),
    pytest.param(
        lambda env: Robot.load(xacro_file(env, '<link name="c" v="${nothere}"/>')),
        Raises(RobotLoadError, ["r.urdf.xacro", "xacro cannot expand it", "'nothere'"]),
        id="xacro-undefined-property",
    ),
    pytest.param(
        lambda env: Robot.load(env.file(urdf_text()), xacro_args={"n": "1"}),
        Raises(InputError, ["xacro_args", "a xacro source"]),
        id="xacro-args-on-plain-urdf",
    ),
]

SCENARIO = [
    pytest.param(
        lambda env: build(env.tmp / "none.toml"),
        Raises(ScenarioError, ["none.toml", "no such scenario file"]),
        id="scenario-missing-file",
    ),
    pytest.param(
        lambda env: build(env.file("name = [1, 2", "s.toml")),
        Raises(ScenarioError, ["not valid TOML"]),
        id="scenario-not-toml",
    ),
    pytest.param(
        lambda env: build(env.file("name = " + "[" * 50_000 + "]" * 50_000, "s.toml")),
        Raises(ScenarioError, ["not valid TOML", "nested too deeply"]),
        id="scenario-nested-too-deeply",
    ),
    pytest.param(
        lambda env: build(env.scenario('[robot]\nsource = "planar4r"\n', "")),
        Raises(ScenarioError, ["robot: required key is missing"]),
        id="scenario-missing-table",
    ),
    pytest.param(
        lambda env: build(env.scenario('frame = "tip"\n', "")),
        Raises(ScenarioError, ["task.frame: required key is missing"]),
        id="scenario-missing-key",
    ),
    pytest.param(
        lambda env: build(env.scenario("duration = 3.0", 'duration = "3 s"')),
        Raises(ScenarioError, ["trajectory.duration: expected a number > 0 [s], got '3 s'"]),
        id="scenario-wrong-type-number",
    ),
    pytest.param(
        lambda env: build(env.scenario('source = "planar4r"', "source = 4")),
        Raises(ScenarioError, ["robot.source: expected a string, got 4"]),
        id="scenario-wrong-type-string",
    ),
    pytest.param(
        lambda env: build(env.scenario('axes = ["x", "y"]', 'axes = "xy"')),
        Raises(ScenarioError, ["task.axes: expected a list of strings, got 'xy'"]),
        id="scenario-wrong-type-list",
    ),
    pytest.param(
        lambda env: build(
            env.scenario("enabled = true\nthreshold = 2.0", "enabled = 1\nthreshold = 2.0")
        ),
        Raises(ScenarioError, ["constraints.joint_limits.enabled: expected true or false"]),
        id="scenario-wrong-type-boolean",
    ),
    pytest.param(
        lambda env: build(env.scenario("[[obstacles]]", "[obstacles]")),
        Raises(ScenarioError, ["obstacles: expected an array of tables ([[...]])"]),
        id="scenario-wrong-type-table-array",
    ),
    pytest.param(
        lambda env: build(env.scenario("gain = 1000.0", "gain = -5.0")),
        Raises(ScenarioError, ["solver.gain: expected a number > 0 [1/s], got -5.0"]),
        id="scenario-out-of-range-gain",
    ),
    pytest.param(
        lambda env: build(env.scenario("dt = 0.001", "dt = 0.001\nrecord_every = 0")),
        Raises(ScenarioError, ["solver.record_every: expected an integer >= 1, got 0"]),
        id="scenario-out-of-range-integer",
    ),
    pytest.param(
        lambda env: build(env.scenario("threshold = 0.03", "threshold = 0.0")),
        Raises(ScenarioError, ["constraints.obstacles.threshold: expected a number > 0 [m]"]),
        id="scenario-out-of-range-threshold",
    ),
    pytest.param(
        lambda env: build(env.scenario("gain = 1000.0", "gain = 1" + "0" * 400)),
        Raises(ScenarioError, ["solver.gain: expected a number > 0 [1/s]", "characters)"]),
        id="scenario-integer-too-large",
    ),
    pytest.param(
        lambda env: build(env.scenario('kind = "line"', 'kind = "spiral"')),
        Raises(ScenarioError, ["trajectory.kind: expected one of 'line', 'circle', 'waypoints'"]),
        id="scenario-unknown-choice",
    ),
    pytest.param(
        lambda env: build(env.scenario("dt = 0.001", "dt = 0.001\nsubsteps = 3")),
        Raises(
            ScenarioError,
            [
                "solver.substeps: unknown key; valid keys here: damping, dt, engine, gain, law, "
                "record_every"
            ],
        ),
        id="scenario-unknown-key",
    ),
    pytest.param(
        lambda env: build(env.scenario('name = "', 'include = "other.toml"\nname = "')),
        Raises(
            ScenarioError, ["include: unknown key; valid keys here: constraints, initial, name"]
        ),
        id="scenario-unknown-top-level-key",
    ),
    pytest.param(
        lambda env: build(env.scenario('frame = "tip"', 'frame = "hand"')),
        Raises(
            ScenarioError, ["task.frame: frame 'hand' not found", "available frames: 'universe'"]
        ),
        id="scenario-unknown-frame",
    ),
    pytest.param(
        lambda env: build(
            env.scenario(
                "[constraints.joint_limits.override.joint3]",
                "[constraints.joint_limits.override.joint9]",
            )
        ),
        Raises(
            ScenarioError,
            ["constraints.joint_limits.override", "joint 'joint9' not found", "'joint1', 'joint2'"],
        ),
        id="scenario-unknown-joint-override",
    ),
    pytest.param(
        lambda env: build(
            env.scenario('source = "planar4r"', 'source = "planar4r"\nlock = {elbow = 0.0}')
        ),
        Raises(
            ScenarioError, ["robot.lock", "joint 'elbow' not found; available joints: 'joint1'"]
        ),
        id="scenario-unknown-joint-lock",
    ),
    pytest.param(
        lambda env: build(env.scenario("threshold = 0.03", 'threshold = 0.03\nlinks = ["link9"]')),
        Raises(
            ScenarioError,
            ["constraints.obstacles.links", "among ['link1', 'link2', 'link3', 'link4']"],
        ),
        id="scenario-unknown-link",
    ),
    pytest.param(
        lambda env: build(
            env.scenario(
                "[constraints.obstacles]",
                '[[obstacles]]\nname = "pin"\nshape = "sphere"\nposition = [0, 0, 0]\n'
                "radius = 0.1\n\n[constraints.obstacles]",
            )
        ),
        Raises(ScenarioError, ["obstacles: expected distinct obstacle names, got ['pin', 'pin']"]),
        id="scenario-duplicate-obstacle-name",
    ),
    pytest.param(
        lambda env: build(env.scenario('axes = ["x", "y"]', "axes = []")),
        Raises(ScenarioError, ["task.axes: expected a non-empty list of axis names"]),
        id="scenario-empty-axes",
    ),
    pytest.param(
        lambda env: build(env.scenario("duration = 3.0", "duration = 3.0\ngoal_rpy = [0, 0, 10]")),
        Raises(ScenarioError, ["trajectory.goal_rpy", "the task has no orientation rows"]),
        id="scenario-rpy-for-position-task",
    ),
    pytest.param(
        lambda env: build(
            env.scenario('source = "planar4r"', 'source = "https://example.com/r.urdf"')
        ),
        Raises(ScenarioError, ["robot.source", "URLs are not fetched"]),
        id="scenario-url-robot",
    ),
    pytest.param(
        lambda env: build(
            env.scenario(
                'source = "planar4r"', f'source = "{ARM_XACRO}"\nxacro_args = {{ n_links = 7 }}'
            )
        ),
        Raises(ScenarioError, ["robot.xacro_args.n_links: expected a string, got 7"]),
        id="scenario-xacro-arg-not-string",
    ),
    pytest.param(
        lambda env: build(
            env.scenario('source = "planar4r"', f'source = "{xacro_file(env, XACRO_ARG_MASS)}"')
        ),
        Raises(ScenarioError, ["robot.xacro_args", "the xacro argument 'mass'"]),
        id="scenario-xacro-missing-arg",
    ),
    pytest.param(
        lambda env: build(env.scenario("q = [180, -30, -90, -30]", "q = [180, -30, -90]")),
        Raises(ScenarioError, ["initial.q", "an array of 4 finite joint values"]),
        id="scenario-initial-q-length",
    ),
    pytest.param(
        lambda env: build(env.scenario("upper = -80.0", "upper = -80.0\nlower = -70.0")),
        Raises(ScenarioError, ["constraints.joint_limits", "lower <= upper", "['joint3']"]),
        id="scenario-inverted-override",
    ),
    pytest.param(
        lambda env: build(env.scenario("dt = 0.001", "dt = 1e-9")),
        Raises(ScenarioError, ["solver.dt: expected a step giving at most 1e+08 steps", "3 s"]),
        id="scenario-too-many-steps",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nscale = 0")),
        Raises(ScenarioError, ["constraints.velocity_limits.scale: expected a number > 0, got 0"]),
        id="scenario-velocity-limits-scale-zero",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nscale = -1")),
        Raises(ScenarioError, ["constraints.velocity_limits.scale: expected a number > 0, got -1"]),
        id="scenario-velocity-limits-scale-negative",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, 'enabled = true\nscale = "a"')),
        Raises(
            ScenarioError, ["constraints.velocity_limits.scale: expected a number > 0, got 'a'"]
        ),
        id="scenario-velocity-limits-scale-not-a-number",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nscale = 11.0")),
        Raises(ScenarioError, ["constraints.velocity_limits.scale", "<= 10", "got 11.0"]),
        id="scenario-velocity-limits-scale-above-ten",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nspeed = 2.0")),
        Raises(
            ScenarioError,
            [
                "constraints.velocity_limits.speed: unknown key; valid keys here: acceleration, "
                "enabled, margin, max_passes, scale, window"
            ],
        ),
        id="scenario-velocity-limits-unknown-key",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nacceleration = 0")),
        Raises(
            ScenarioError,
            ["constraints.velocity_limits.acceleration: expected a number > 0 [rad/s^2 or m/s^2]"],
        ),
        id="scenario-velocity-limits-acceleration-zero",
    ),
    pytest.param(
        lambda env: build(velocity_section(env, "enabled = true\nacceleration = { joint9 = 1.0 }")),
        Raises(
            ScenarioError,
            ["constraints.velocity_limits.acceleration", "joint 'joint9' not found", "'joint1'"],
        ),
        id="scenario-velocity-limits-acceleration-unknown-joint",
    ),
    pytest.param(
        lambda env: build(no_velocity_limits(env)),
        Raises(
            ScenarioError,
            ["constraints.velocity_limits.enabled", "has none", "nothing to respect"],
        ),
        id="scenario-velocity-limits-robot-without-limits",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, "enabled = true\nthreshold = 0.0")),
        Raises(
            ScenarioError,
            ["constraints.dexterity.threshold: expected a number > 0 [m^p]", "got 0.0"],
        ),
        id="scenario-dexterity-threshold-zero",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, "enabled = true\nthreshold = -0.1")),
        Raises(ScenarioError, ["constraints.dexterity.threshold: expected a number > 0", "-0.1"]),
        id="scenario-dexterity-threshold-negative",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, 'enabled = true\nthreshold = "high"')),
        Raises(ScenarioError, ["constraints.dexterity.threshold: expected a number > 0", "'high'"]),
        id="scenario-dexterity-threshold-not-a-number",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, "enabled = true")),
        Raises(ScenarioError, ["constraints.dexterity.threshold: required key is missing"]),
        id="scenario-dexterity-threshold-missing",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, "enabled = true\nthreshold = 0.1\nmargin = 1")),
        Raises(
            ScenarioError,
            [
                "constraints.dexterity.margin: unknown key; valid keys here: enabled, gain, "
                "threshold"
            ],
        ),
        id="scenario-dexterity-unknown-key",
    ),
    pytest.param(
        lambda env: build(dexterity_section(env, "enabled = true\nthreshold = 0.1\ngain = 0")),
        Raises(ScenarioError, ["constraints.dexterity.gain: expected a number > 0 [1/s]"]),
        id="scenario-dexterity-gain-zero",
    ),
    pytest.param(
        lambda env: ConstraintSet(env.robot, dexterity=Dexterity(-1.0)),
        Raises(InputError, ["constraints.dexterity.threshold: expected a positive"]),
        id="api-dexterity-threshold-negative",
    ),
    pytest.param(
        lambda env: ConstraintSet(env.robot, dexterity=0.1),
        Raises(InputError, ["constraints.dexterity: expected a Dexterity(threshold=...)"]),
        id="api-dexterity-not-a-dexterity",
    ),
]

NUMBERS = [
    pytest.param(
        lambda env: track(env.task(), env.line(), q0=[0.0, math.nan, 0.0, 0.0]),
        Raises(InputError, ["q0: expected an array of 4 finite joint values", "nan"]),
        id="number-nan-q0",
    ),
    pytest.param(
        lambda env: track(env.task(), env.line(), q0=[math.inf, 0.0, 0.0, 0.0]),
        Raises(InputError, ["q0: expected an array of 4 finite joint values", "inf"]),
        id="number-inf-q0",
    ),
    pytest.param(
        lambda env: build(env.scenario("q = [180, -30, -90, -30]", "q = [nan, -30, -90, -30]")),
        Raises(ScenarioError, ["initial.q: expected a list of N numbers (finite)"]),
        id="number-nan-q0-scenario",
    ),
    pytest.param(
        lambda env: Line([0.5, 0.0, 0.0], [math.nan, 0.0, 0.0], duration=1.0),
        Raises(InputError, ["goal: expected a finite 3-vector [m]"]),
        id="number-nan-target-line",
    ),
    pytest.param(
        lambda env: solve(env.task(), [math.inf, 0.0, 0.0]),
        Raises(InputError, ["target: expected finite values"]),
        id="number-inf-target-solve",
    ),
    pytest.param(
        lambda env: build(env.scenario("goal = [0.8, -0.2, 0.0]", "goal = [0.8, inf, 0.0]")),
        Raises(ScenarioError, ["trajectory.goal: expected a list of 3 numbers [m] (finite)"]),
        id="number-inf-target-scenario",
    ),
    pytest.param(
        lambda env: Obstacle("o", "sphere", [0.7, math.nan, 0.0], radius=0.1),
        Raises(InputError, ["obstacles.o.position: expected three finite numbers"]),
        id="number-nan-obstacle-position",
    ),
    pytest.param(
        lambda env: Obstacle("o", "sphere", [0.7, 0.0, 0.0], [0.0, math.inf, 0.0], radius=0.1),
        Raises(InputError, ["obstacles.o.rpy: expected three finite numbers"]),
        id="number-inf-obstacle-orientation",
    ),
    pytest.param(
        lambda env: build(
            env.scenario(
                "position = [0.7, -0.28, 0.0]",
                "position = [0.7, -0.28, 0.0]\nvelocity = [nan, 0, 0]",
            )
        ),
        Raises(
            ScenarioError, ["obstacles[0].velocity: expected a list of 3 numbers [m/s] (finite)"]
        ),
        id="number-nan-obstacle-velocity-scenario",
    ),
    pytest.param(
        lambda env: track(env.task(), env.line(), q0=Q0, dt=0.0),
        Raises(InputError, ["dt: expected a positive finite number [s]"]),
        id="number-dt-zero",
    ),
    pytest.param(
        lambda env: track(env.task(), env.line(), q0=Q0, dt=-1e-3),
        Raises(InputError, ["dt: expected a positive finite number [s]"]),
        id="number-dt-negative",
    ),
    pytest.param(
        lambda env: build(env.scenario("dt = 0.001", "dt = -inf")),
        Raises(ScenarioError, ["solver.dt: expected a number > 0 [s]"]),
        id="number-dt-scenario",
    ),
    pytest.param(
        unstable_gain,
        Raises(StabilityWarning, ["gain: alpha dt lambda_max(J J^T) = 2.1", ">= 2 at q0"]),
        id="number-gain-breaks-stability-bound",
    ),
]

GEOMETRY = [
    pytest.param(
        lambda env: Obstacle(
            "plate", "mesh", [0.7, 0.0, 0.0], file=octahedron_obj(env, squash=0.0)
        ),
        Raises(GeometryError, ["obstacles.plate.file: degenerate mesh (all vertices on a plane"]),
        id="geometry-degenerate-mesh",
    ),
    pytest.param(
        lambda env: Obstacle(
            "tri",
            "mesh",
            [0.7, 0.0, 0.0],
            file=env.file("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj"),
        ),
        Raises(GeometryError, ["obstacles.tri.file: the mesh has 3 vertices, a volume needs 4"]),
        id="geometry-mesh-too-few-vertices",
    ),
    pytest.param(
        lambda env: Obstacle("m", "mesh", [0.7, 0.0, 0.0], file=env.tmp / "nothere.stl"),
        Raises(GeometryError, ["obstacles.m.file: mesh file", "no such file"]),
        id="geometry-missing-mesh",
    ),
    pytest.param(
        lambda env: Obstacle("m", "mesh", [0.7, 0.0, 0.0], file=env.file("hello", "m.stl")),
        Raises(GeometryError, ["obstacles.m.file: cannot read mesh", "Could not load resource"]),
        id="geometry-unreadable-mesh",
    ),
    pytest.param(
        lambda env: Obstacle("b", "box", [0.7, 0.0, 0.0], size=[0.1, 0.0, 0.1]),
        Raises(GeometryError, ["obstacles.b.size: expected a positive finite size [m], got 0.0"]),
        id="geometry-zero-size-box",
    ),
    pytest.param(
        lambda env: Obstacle("s", "sphere", [0.7, 0.0, 0.0], radius=-0.1),
        Raises(GeometryError, ["obstacles.s.radius: expected a non-negative finite size [m]"]),
        id="geometry-negative-radius",
    ),
    pytest.param(
        lambda env: Obstacle("c", "cylinder", [0.7, 0.0, 0.0], radius="wide", length=0.1),
        Raises(
            GeometryError, ["obstacles.c.radius: expected a positive finite size [m], got 'wide'"]
        ),
        id="geometry-radius-not-a-number",
    ),
    pytest.param(
        lambda env: build(
            env.scenario(
                'shape = "sphere"\nposition = [0.7, -0.28, 0.0]\nradius = 0.0',
                'shape = "box"\nposition = [0.7, -0.28, 0.0]\nsize = [0.0, 0.1, 0.1]',
            )
        ),
        Raises(ScenarioError, ["obstacles[0].size: expected three positive side lengths [m]"]),
        id="geometry-zero-size-box-scenario",
    ),
]

START = [
    pytest.param(
        lambda env: env.robot.check_within_limits(np.array([0.3, 3.3, -1.0, 0.5]), "q0"),
        Raises(
            InfeasibleError,
            [
                "q0: the configuration is outside the joint limits of planar4r",
                "'joint2' = 3.3 not in",
            ],
        ),
        id="start-outside-joint-limits",
    ),
    pytest.param(
        start_outside_limits,
        Raises(InfeasibleError, ["q0", "'joint2' = 3.3 not in [-3.14159, 3.14159]"]),
        id="start-outside-joint-limits-track",
    ),
    pytest.param(
        lambda env: env.cli(
            "solve",
            str(env.scenario("q = [180, -30, -90, -30]", "q = [180, -30, -190, -30]")),
            "--out",
            out(env),
        ),
        Exits(3, ["initial.q", "'joint3' = -3.31613 not in [-3.14159, 3.14159]"]),
        id="start-outside-joint-limits-cli",
    ),
    pytest.param(
        beyond_override,
        Ends(["violated"], ["joint:joint3:upper crossed by", "from t = 0 to"], check=driven_back),
        id="start-beyond-override-is-driven-back",
    ),
    pytest.param(
        lambda env: inside_obstacle(env, "pseudoinverse"),
        Ends(["violated"], ["obstacle:blob:link2 penetrated"], check=recovered_from_obstacle),
        id="start-inside-obstacle-law10",
    ),
    pytest.param(
        lambda env: inside_obstacle(env, "transpose"),
        Ends(["violated"], ["obstacle:blob:link2 penetrated"], check=recovered_from_obstacle),
        id="start-inside-obstacle-law9",
    ),
]

INFEASIBLE = [
    pytest.param(
        lambda env: run_scenario(DATA / "deadlock.toml"),
        Ends(["deadlock"], ["Remark 2", "active constraints: obstacle:pin:link4"], seconds=5.0),
        id="goal-deadlock",
    ),
    pytest.param(
        lambda env: solve(env.task(), [2.0, 0.0, 0.0]),
        Ends(["max_iterations"], ["no convergence after", "attempt(s)"], seconds=5.0),
        id="goal-unreachable-solve",
    ),
    pytest.param(
        lambda env: track(
            env.task(), Line(env.task().placement(Q0).translation, [2.0, 0.0, 0.0], 1.0), q0=Q0
        ),
        Ends(["diverged", "deadlock"], ["t = "], seconds=5.0),
        id="goal-unreachable-track",
    ),
    pytest.param(
        error_correction_too_fast,
        Ends(["velocity_limit"], ["joint speed limits not respected", "x its velocity limit at t"]),
        id="velocity-limit-error-correction",
    ),
]

CLI = [
    pytest.param(
        lambda env: env.command(
            "solve", str(scenario_path("case_study_both")), "--out", out(env), "--export", "xml"
        ),
        Exits(2, ["--export", "invalid choice: 'xml'", "'csv', 'json'"]),
        id="cli-export-unknown-format",
    ),
    pytest.param(
        lambda env: env.command(
            "solve",
            str(scenario_path("case_study_both")),
            "--out",
            out(env),
            "--export",
            "csv",
            "--export-every",
            "0",
        ),
        Exits(2, ["--export-every", "expected an integer >= 1, got '0'"]),
        id="cli-export-every-zero",
    ),
    pytest.param(
        lambda env: env.cli(
            "solve",
            str(scenario_path("case_study_both")),
            "--out",
            out(env),
            "--export-every",
            "5",
        ),
        Exits(2, ["--export-every", "to be given with --export"]),
        id="cli-export-every-without-export",
    ),
    pytest.param(
        lambda env: env.cli("solve", str(env.scenario("dt = 0.001", "dt = 0")), "--out", out(env)),
        Exits(2, ["clik: error:", "solver.dt: expected a number > 0 [s]"]),
        id="cli-bad-scenario",
    ),
    pytest.param(
        lambda env: env.cli("solve", str(env.tmp / "none.toml"), "--out", out(env)),
        Exits(2, ["no such scenario file"]),
        id="cli-missing-scenario",
    ),
    pytest.param(
        lambda env: env.cli(
            "solve",
            str(
                env.scenario('source = "planar4r"', f'source = "{env.file(urdf_text(LINKS + J1))}"')
            ),
            "--out",
            out(env),
        ),
        Exits(2, ["robot.source", "several root links"]),
        id="cli-bad-urdf",
    ),
    pytest.param(
        lambda env: env.cli(
            "solve",
            str(
                env.scenario('source = "planar4r"', f'source = "{xacro_file(env, XACRO_ARG_MASS)}"')
            ),
            "--out",
            out(env),
        ),
        Exits(2, ["robot.xacro_args", "the xacro argument 'mass'"]),
        id="cli-xacro-missing-arg",
    ),
    pytest.param(
        lambda env: env.cli(
            "solve",
            str(
                env.scenario(
                    'shape = "sphere"\nposition = [0.7, -0.28, 0.0]\nradius = 0.0',
                    'shape = "mesh"\nposition = [0.7, -0.28, 0.0]\nfile = "m.stl"',
                )
            ),
            "--out",
            out(env),
        ),
        Exits(2, ["obstacles[0]", "no such file"]),
        id="cli-bad-geometry",
    ),
    pytest.param(
        lambda env: env.cli("solve", str(DATA / "deadlock.toml"), "--out", out(env), "--quiet"),
        Exits(3),
        id="cli-infeasible-deadlock",
    ),
    pytest.param(
        lambda env: env.command(
            "solve", str(env.scenario("gain = 1000.0", "gain = 3000.0")), "--out", out(env)
        ),
        Exits(
            3,
            [
                "clik: warning: gain: alpha dt lambda_max(J J^T) = 2.66 >= 2 at q0",
                "[StabilityWarning]",
            ],
        ),
        id="cli-gain-warning",
    ),
    pytest.param(
        internal_error,
        Exits(4, ["clik: internal error: RuntimeError: simulated bug", "--debug"]),
        id="cli-internal-error",
    ),
    pytest.param(
        debug_shows_the_traceback,
        Raises(ScenarioError, ["solver.dt"]),
        id="cli-debug-raises",
    ),
]

CATALOGUE = URDF + SCENARIO + NUMBERS + GEOMETRY + START + INFEASIBLE + CLI


@pytest.fixture
def env(tmp_path, planar4r, capsys, monkeypatch) -> Env:
    return Env(tmp_path, planar4r, capsys, monkeypatch)


@pytest.mark.parametrize(("call", "expect"), CATALOGUE)
def test_catalogue(env, call, expect):
    if isinstance(expect, Raises):
        assert issubclass(expect.error, clik.ClikError | StabilityWarning)
        with pytest.raises(expect.error) as caught:
            call(env)
        message = str(caught.value)
        for word in expect.words:
            assert word in message
        assert "Traceback" not in message
    elif isinstance(expect, Ends):
        start = time.perf_counter()
        result = call(env)
        assert time.perf_counter() - start < expect.seconds
        assert result.status in expect.statuses
        assert result.status in clik.outputs.result.STATUSES
        for word in expect.words:
            assert word in result.reason
        if expect.check is not None:
            expect.check(result)
    else:
        code, err = call(env)
        assert code == expect.code, err
        for word in expect.words:
            assert word in err
        assert "Traceback" not in err


def test_the_catalogue_has_at_least_forty_rows():
    assert len(CATALOGUE) >= 40


def test_every_error_class_is_in_the_errors_page_with_its_exit_code():
    """docs/reference/errors.md's "Error classes" table names every ClikError subclass."""
    page = Path(__file__).parents[2] / "docs" / "reference" / "errors.md"
    section = page.read_text(encoding="utf-8").split("\n## Error classes\n", 1)[1]
    section = section.split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| `")]

    # clik's own folder (an editable install's clik.__path__ holds the checkout's root too)
    for module in pkgutil.walk_packages([str(Path(clik.__file__).parent)], "clik."):
        importlib.import_module(module.name)  # every error class clik defines is loaded

    def subclasses(cls: type) -> list[type]:
        return [c for sub in cls.__subclasses__() for c in (sub, *subclasses(sub))]

    for cls in subclasses(clik.ClikError):
        row = next((r for r in rows if f"`{cls.__name__}`" in r), None)
        assert row is not None, f"{cls.__name__} is not in {page.name}'s Error classes table"
        assert row.rstrip(" |").endswith(str(cls.exit_code)), row
