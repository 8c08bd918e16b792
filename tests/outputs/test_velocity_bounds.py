"""Every joint's speed against the bound the run used for it: ``velocity_bounds`` and the source.

``max_velocity_ratio`` covers every velocity coordinate: a URDF limit (``"urdf"``), a
per-joint ``joint_speed.velocity`` (``"setting"``), ``joint_speed.default_velocity`` for
a joint without a limit (``"default"``: every joint of an MJCF model), a base's speed
(``"base_speed"``). The expected numbers are computed here from the recorded ``qdot``
and the bounds each case sets, in both engines.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.commands.solve import print_summary
from clik.loop.joint_speed import JointSpeed
from clik.outputs.result import TrackingResult
from clik.outputs.velocity_report import (
    VelocityLimits,
    run_velocity_limits,
    speed_line,
    velocity_report,
)
from clik.trajectory import Line
from tests.model.test_joint_kinds import CONTINUOUS_BODY
from tests.urdf_snippets import urdf_text

ENGINES = ("python", "compiled")
AT = 1e-9
"""A ratio within this of 1: the law held the joint at its bound."""

FLOATER = """<mujoco model="floater">
  <compiler angle="radian"/>
  <worldbody>
    <body name="torso" pos="0 0 1">
      <freejoint name="float"/>
      <geom type="box" size="0.1 0.1 0.1"/>
      <body name="upper" pos="0 0 0.1">
        <joint name="shoulder" axis="0 1 0" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
        <body name="fore" pos="0.3 0 0">
          <joint name="elbow" axis="0 1 0" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
          <site name="hand" pos="0.3 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
"""An MJCF torso on a free joint with a two-hinge arm: MJCF gives no velocity limits."""


def quiet_track(task: clik.Task, line: Line, q0: np.ndarray, **kwargs: object) -> TrackingResult:
    """``clik.track`` without the warnings (a joint without a limit, a run off track)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return clik.track(task, line, q0=q0, **kwargs)  # type: ignore[arg-type]


def expected(result: TrackingResult, bound: np.ndarray) -> tuple[float, int, np.ndarray]:
    """The largest ``max |qdot_i| / bound_i``, its coordinate, and each coordinate's."""
    ratio = np.abs(result.qdot).max(axis=0) / bound
    return float(ratio.max()), int(np.argmax(ratio)), ratio


def assert_engines_agree(runs: dict[str, TrackingResult]) -> dict:
    """Both engines' velocity keys, equal; returns the python run's summary."""
    keys = ("max_velocity_ratio_joint", "max_velocity_ratio_source", "velocity_bounds")
    a, b = (runs[e].summary() for e in ENGINES)
    assert {k: a[k] for k in keys} == {k: b[k] for k in keys}
    assert a["max_velocity_ratio"] == pytest.approx(b["max_velocity_ratio"], abs=1e-7)
    return a


@pytest.fixture(scope="module")
def unlimited(tmp_path_factory: pytest.TempPathFactory) -> clik.Robot:
    """j1 continuous with no ``<limit>`` (inf), j2 and j3 with ``velocity="0"``."""
    path = tmp_path_factory.mktemp("unlimited") / "unlimited.urdf"
    path.write_text(urdf_text(CONTINUOUS_BODY.replace('velocity="1"', 'velocity="0"')))
    return clik.Robot.load(path)


def unlimited_runs(robot: clik.Robot, joint_speed: JointSpeed) -> dict[str, TrackingResult]:
    """A 5 cm tip line in 0.05 s, faster than 0.5 rad/s or m/s allows, in both engines."""
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.array([1.0, 0.0, 0.5, 0.05])
    start = task.placement(q0).translation
    line = Line(start, start + [0.0, 0.05, 0.0], duration=0.05)
    return {
        e: quiet_track(task, line, q0, joint_speed=joint_speed, engine=e, gain=200.0)
        for e in ENGINES
    }


def test_joints_without_a_urdf_limit_are_held_to_the_default(unlimited, capsys):
    assert np.array(unlimited.model.velocityLimit).tolist() == [np.inf, 0.0, 0.0]
    runs = unlimited_runs(unlimited, JointSpeed(default_velocity=0.5))
    summary = assert_engines_agree(runs)
    names = ["j1", "j2", "j3"]
    assert summary["velocity_bounds"] == {j: {"bound": 0.5, "source": "default"} for j in names}
    ratio, top, _ = expected(runs["python"], np.full(3, 0.5))
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert summary["max_velocity_ratio"] == pytest.approx(1.0, abs=AT)  # the default held it
    assert summary["max_velocity_ratio_joint"] == names[top]
    assert summary["max_velocity_ratio_source"] == "default"
    print_summary("unlimited", summary)
    line = next(s for s in capsys.readouterr().out.splitlines() if "joint speed" in s)
    assert line == (
        f"  joint speed: max |qdot| / bound 1.00 ({names[top]}, "
        "default bound joint_speed.default_velocity)"
    )


def test_a_per_joint_setting_is_that_joints_bound(planar4r):
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    start = task.placement(q0).translation
    line = Line(start, start + [0.25, -0.05, 0.0], duration=0.1)
    setting = JointSpeed(velocity={"joint2": 0.4})
    runs = {e: quiet_track(task, line, q0, joint_speed=setting, engine=e) for e in ENGINES}
    summary = assert_engines_agree(runs)
    urdf = np.array(planar4r.model.velocityLimit)
    bound = urdf.copy()
    bound[1] = 0.4
    assert summary["velocity_bounds"]["joint2"] == {"bound": 0.4, "source": "setting"}
    for i in (0, 2, 3):
        assert summary["velocity_bounds"][f"joint{i + 1}"] == {"bound": urdf[i], "source": "urdf"}
    ratio, top, each = expected(runs["python"], bound)
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert summary["max_velocity_ratio_joint"] == f"joint{top + 1}"
    assert each[1] == pytest.approx(1.0, abs=AT)  # joint 2 ran at its 0.4 rad/s
    assert np.abs(runs["python"].qdot[:, 1]).max() <= 0.4 * (1 + AT)
    source = "setting" if top == 1 else "urdf"
    assert summary["max_velocity_ratio_source"] == source
    words = "joint_speed.velocity" if top == 1 else "URDF limit"
    assert speed_line(summary) == f"joint speed: max |qdot| / bound 1.00 (joint{top + 1}, {words})"


@pytest.mark.parametrize("engine", ENGINES)
def test_a_joint_driven_to_its_urdf_limit_is_named(panda, engine):
    """0.3 m in 0.15 s asks about twice the Panda's limits: the law holds a joint at one."""
    task = clik.Task(panda, "panda_hand", "position")
    start = task.placement(panda.q_reference).translation
    line = Line(start, start + [0.0, 0.3, 0.0], duration=0.15)
    result = quiet_track(task, line, panda.q_reference, engine=engine, gain=100.0)
    summary = result.summary()
    ratio, top, _ = expected(result, np.array(panda.model.velocityLimit))
    assert ratio == pytest.approx(1.0, abs=AT)
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    joint = panda.joint_names[top]
    assert summary["max_velocity_ratio_joint"] == joint
    assert summary["max_velocity_ratio_source"] == "urdf"
    assert speed_line(summary) == f"joint speed: max |qdot| / bound 1.00 ({joint}, URDF limit)"


@pytest.fixture(scope="module")
def floater(tmp_path_factory: pytest.TempPathFactory) -> clik.Robot:
    path: Path = tmp_path_factory.mktemp("floater") / "floater.xml"
    path.write_text(FLOATER)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return clik.Robot.load(path, base="floating")


def test_a_floating_base_reports_its_joints_not_only_the_base(floater):
    """MJCF on a free joint: the hinges at the default bound, the base under its speed."""
    assert floater.joint_names == ["root_joint", "shoulder", "elbow"]
    task = clik.Task(floater, "hand", "position")
    q0 = floater.q_reference.copy()
    q0[-1] = 0.5
    start = task.placement(q0).translation
    line = Line(start, start + [0.0, 0.0, 0.3], duration=0.1)
    setting = JointSpeed(default_velocity=0.5)
    runs = {e: quiet_track(task, line, q0, joint_speed=setting, engine=e) for e in ENGINES}
    summary = assert_engines_agree(runs)
    bounds = summary["velocity_bounds"]
    base = [f"root_joint[{k}]" for k in range(6)]
    assert list(bounds) == [*base, "shoulder", "elbow"]
    assert all(bounds[b] == {"bound": 1.0, "source": "base_speed"} for b in base)
    assert bounds["shoulder"] == bounds["elbow"] == {"bound": 0.5, "source": "default"}
    ratio, top, each = expected(runs["python"], np.array([1.0] * 6 + [0.5] * 2))
    assert each[:6].max() < 0.95  # the base alone would have read below 1
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert summary["max_velocity_ratio"] == pytest.approx(1.0, abs=AT)
    assert top >= 6 and summary["max_velocity_ratio_joint"] == ["shoulder", "elbow"][top - 6]
    assert summary["max_velocity_ratio_source"] == "default"


def test_without_the_law_a_floating_base_keeps_its_speed_and_the_urdf_limits(planar4r):
    """``joint_speed=None``: the bounds are the model's, the base's speed on the base."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = clik.Robot.load("planar4r", base="floating")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = robot.q_reference.copy()
    q0[7:] = np.radians([180.0, -30.0, -90.0, -30.0])
    start = task.placement(q0).translation
    line = Line(start, start + [0.05, 0.0, 0.0], duration=0.5)
    result = quiet_track(task, line, q0, joint_speed=None)
    summary = result.summary()
    sources = [b["source"] for b in summary["velocity_bounds"].values()]
    assert sources == ["base_speed"] * 6 + ["urdf"] * 4
    ratio, top, _ = expected(result, np.array(robot.model.velocityLimit))
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert summary["max_velocity_ratio_source"] == sources[top]


def test_with_the_law_off_a_joint_without_a_limit_has_no_bound(unlimited):
    runs = unlimited_runs(unlimited, JointSpeed(enabled=False))
    summary = assert_engines_agree(runs)
    assert summary["max_velocity_ratio"] is None
    assert {b["source"] for b in summary["velocity_bounds"].values()} == {"none"}
    line = "joint speed: no joint has a bound (no URDF limit, joint_speed off)"
    assert speed_line(summary) == line


def test_the_console_line_names_each_source_and_the_unbounded():
    limits = VelocityLimits(
        ["a", "b", "c", "base[0]"], np.array([1.0, 2.0, np.inf, 4.0]),
        ["setting", "default", "none", "base_speed"],
    )  # fmt: skip
    t = np.array([0.0, 0.1])
    qdot = np.array([[0.5, 1.0, 9.0, 8.0], [0.2, 0.5, 9.0, 1.0]])
    summary = velocity_report(t, qdot, limits).as_summary()
    assert summary["max_velocity_ratio"] == 2.0
    assert summary["velocity_bounds"]["c"] == {"bound": None, "source": "none"}
    assert speed_line(summary) == (
        "joint speed: max |qdot| / bound 2.00 (base[0], base speed); without a bound: c "
        "(over the bound: base[0] x2.00 from t = 0.000 s)"
    )
    qdot[0, 3] = 0.0
    line = speed_line(velocity_report(t, qdot, limits).as_summary())
    assert (
        line == "joint speed: max |qdot| / bound 0.50 (a, joint_speed.velocity); without a bound: c"
    )
    assert "URDF" not in line


def test_a_record_without_sources_is_read_from_the_scale_and_the_unlimited():
    """A result saved before ``info["joint_speed"]`` held ``limit`` and ``source``."""
    model = VelocityLimits(["j1", "j2", "j3"], np.array([3.0, 3.0, np.inf]))
    info = {"joint_speed": {"scale": 0.5, "velocity": [1.5, 0.5, 1.0], "unlimited": ["j3"]}}
    bounds = run_velocity_limits(info, model)
    np.testing.assert_allclose(bounds.limit, [3.0, 1.0, 2.0])
    assert bounds.sources() == ["urdf", "setting", "default"]
    assert run_velocity_limits({"joint_speed": None}, model) is model
