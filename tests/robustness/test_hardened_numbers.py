"""Finite in, finite out; robots as they come (issue 15, points 1 and 5).

The numbers catalogue: one row per probed scenario number, each written in a scratch
folder and run the way a user would (``clik solve FILE --out DIR``), stating the exit
code, the words of the message (the key path first) and that a refused scenario leaves
no output folder. Every test has a time bound: a hang fails the test, not the suite.

Decisions recorded here:

- Scenario numbers have documented ranges (README, "Ranges"): positions, sizes and
  thresholds within 1 km, scale factors within 1e-6..1e6, angles within four turns
  (8 pi), ``gain * dt <= 1e4``, ``duration >= 1e-6 s`` and ``dt <= duration / 2``.
- A robot's own reference posture outside its limits is clipped into them with a
  :class:`~clik.model.loading.ReferenceClippedWarning`; a user's ``q0`` outside them is still
  infeasible.
- A link geometry whose hull coal cannot build is skipped (warned, and listed in
  ``info["unmonitored_geometries"]``); the other geometries stay monitored.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik import GeometryError, InfeasibleError, Task
from clik.cli import main
from clik.constraints import ConstraintSet, Obstacle
from clik.constraints.collision_scene import SkippedGeometryWarning
from clik.loop.laws import damped_solve, prioritized, solve_small
from clik.model.loading import ReferenceClippedWarning
from clik.model.robot import Robot
from clik.scenarios import scenario_path
from clik.trajectory import Hold
from tests.limits_check import assert_summary_within_limits, assert_within_limits
from tests.urdf_snippets import J1, J2, LINKS, urdf_text
from tests.zoo_runs import zoo_run

CASE = scenario_path("case_study_both").read_text()
LINE = 'kind = "line"\ngoal = [0.8, -0.2, 0.0]\nduration = 3.0\ncruise_speed = 0.12'
CIRCLE = 'kind = "circle"\ncenter = [0.75, -0.2, 0.0]\nangle = {}\nduration = 3.0'
CLIPPED = ("kinova", "simple_humanoid", "alex_psyonic_hands")


@dataclass(frozen=True)
class Exits:
    """``clik solve`` returns ``code``, stderr holds ``words``; ``made``: the output folder."""

    code: int
    words: tuple[str, ...] = ()
    made: bool = False


def solve(tmp: Path, text: str, capsys: pytest.CaptureFixture[str]) -> tuple[int, str, Path]:
    """Write ``text`` as a scenario and run ``clik solve`` on it: code, stderr, out folder."""
    path = tmp / "s.toml"
    path.write_bytes(text.encode("utf-8"))
    out = tmp / "out"
    capsys.readouterr()
    code = main(["solve", str(path), "--out", str(out)])
    return code, capsys.readouterr().err, out


def case(old: str, new: str) -> str:
    """The shipped case study with ``old`` replaced by ``new``."""
    assert old in CASE, f"the case study has no {old!r}"
    return CASE.replace(old, new, 1)


NUMBERS = [
    pytest.param(
        case(LINE, CIRCLE.format("1e300")),
        Exits(2, ("trajectory.angle", "magnitude at most 25.13", "1e+300")),
        id="circle-angle-huge",
    ),
    pytest.param(
        case(LINE, CIRCLE.format("-30.0")),
        Exits(2, ("trajectory.angle", "magnitude at most 25.13")),
        id="circle-angle-five-turns",
    ),
    pytest.param(
        case("gain = 1000.0", "gain = 1e300"),
        Exits(2, ("solver.gain", "gain * solver.dt <= 10000", "1e+300")),
        id="solver-gain-huge",
    ),
    pytest.param(
        case("gain = 1000.0", "gain = [1000.0, 1e12]"),
        Exits(2, ("solver.gain", "gain * solver.dt <= 10000")),
        id="solver-gain-row-huge",
    ),
    pytest.param(
        case("threshold = 0.03", "threshold = 0.03\ngain = 1e300"),
        Exits(2, ("constraints.obstacles.gain", "gain * solver.dt <= 10000")),
        id="obstacle-gain-huge",
    ),
    pytest.param(
        case("threshold = 2.0", "threshold = 1e300"),
        Exits(2, ("constraints.joint_limits.threshold", "magnitude at most 1440")),
        id="joint-threshold-huge",
    ),
    pytest.param(
        case("threshold = 2.0", "threshold = 1000.0"),
        Exits(2, ("constraints.joint_limits.threshold", "smaller than a revolute joint's range")),
        id="joint-threshold-beyond-the-range",
    ),
    pytest.param(
        case("dt = 0.001", "dt = 1e300"),
        Exits(2, ("solver.dt", "at most trajectory.duration / 2 = 1.5 s", "1e+300")),
        id="solver-dt-huge",
    ),
    pytest.param(
        case("dt = 0.001", "dt = 3.0"),
        Exits(2, ("solver.dt", "at least 2 samples")),
        id="solver-dt-equals-duration",
    ),
    pytest.param(
        case("duration = 3.0\ncruise_speed = 0.12", "duration = 1e-300"),
        Exits(2, ("trajectory.duration", "a number >= 1e-06 [s]", "1e-300")),
        id="trajectory-duration-tiny",
    ),
    pytest.param(
        case("duration = 3.0\ncruise_speed = 0.12", "cruise_speed = 0.12").replace(
            "dt = 0.001", "dt = 1.5"
        ),
        Exits(2, ("solver.dt", "at least 2 samples")),
        id="solver-dt-against-cruise-speed-duration",
    ),
    pytest.param(
        case("[constraints.obstacles]", "[constraints]\nmax_active = 0\n[constraints.obstacles]"),
        Exits(2, ("constraints.max_active", "an integer >= 1")),
        id="max-active-zero",
    ),
    pytest.param(
        case("position = [0.7, -0.28, 0.0]", "position = [1e300, -0.28, 0.0]"),
        Exits(2, ("obstacles[0].position", "magnitude at most 1000")),
        id="obstacle-position-huge",
    ),
    pytest.param(
        case("radius = 0.0", "radius = 2000.0"),
        Exits(2, ("obstacles[0].radius", "magnitude at most 1000")),
        id="obstacle-radius-huge",
    ),
    pytest.param(
        case(
            "position = [0.7, -0.28, 0.0]", "position = [0.7, -0.28, 0.0]\nvelocity = [0, 5e3, 0]"
        ),
        Exits(2, ("obstacles[0].velocity", "magnitude at most 1000")),
        id="obstacle-velocity-huge",
    ),
    pytest.param(
        case("goal = [0.8, -0.2, 0.0]", "goal = [0.8, -1e4, 0.0]"),
        Exits(2, ("trajectory.goal", "magnitude at most 1000")),
        id="trajectory-goal-huge",
    ),
    pytest.param(
        case("q = [180, -30, -90, -30]", "q = [1e300, -30, -90, -30]"),
        Exits(2, ("initial.q", "magnitude at most")),
        id="initial-q-huge",
    ),
    pytest.param(
        case(
            'shape = "sphere"\nposition = [0.7, -0.28, 0.0]\nradius = 0.0',
            'shape = "mesh"\nposition = [0.7, -0.28, 0.0]\nfile = "m.obj"\nscale = [1e-9, 1, 1]',
        ),
        Exits(2, ("obstacles[0].scale", "[1e-06, 1e+06]")),
        id="mesh-scale-tiny",
    ),
    pytest.param(
        case('frame = "tip"', f'frame = "{"f" * 1_000_000}"'),
        Exits(2, ("task.frame", "(1000000 characters) not found", "available frames: ")),
        id="task-frame-megabyte",
    ),
    pytest.param(
        case("duration = 3.0\ncruise_speed = 0.12", "duration = 20000.0"),
        Exits(2, ("solver.record_every", "an integer >= 11", "MAX_RECORD_BYTES")),
        id="record-too-large-for-memory",
    ),
    pytest.param(
        case("duration = 3.0\ncruise_speed = 0.12", "duration = 20000.0").replace(
            "dt = 0.001", "dt = 0.001\nrecord_every = 10"
        ),
        Exits(2, ("solver.record_every", "an integer >= 11", "every 10-th of its 20000001")),
        id="record-every-too-small-for-memory",
    ),
    pytest.param(
        CASE,
        Exits(0, (), made=True),
        id="in-range-runs",
    ),
    pytest.param(
        "\ufeff" + CASE,
        Exits(0, (), made=True),
        id="utf8-bom-accepted",
    ),
]


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("text", "expect"), NUMBERS)
def test_scenario_numbers(tmp_path, capsys, planar4r, text, expect):
    code, err, out = solve(tmp_path, text, capsys)
    assert code == expect.code, err
    for word in expect.words:
        assert word in err, err
    assert "Traceback" not in err
    assert len(err) < 5000, "a long value is shortened in the message"
    assert out.exists() == expect.made, "a refused scenario must not create its output folder"
    if expect.made:
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "completed"
        assert_summary_within_limits(summary, planar4r)


# ------------------------------------------------------------------ non-finite solver input


@pytest.mark.timeout(20)
def test_no_solver_call_on_a_non_finite_matrix():
    J = np.array([[np.inf, 1.0], [0.0, 1.0]])
    A = J @ J.T
    assert np.isnan(solve_small(A, np.ones(2))).all()
    assert np.isnan(damped_solve(A, np.ones(2), 0.01, 0.0)).all()
    out = np.zeros(2)
    prioritized(J, np.ones(2), np.zeros((0, 2)), np.zeros(0), out, 0.0, 1e-3)
    assert np.isnan(out).all()
    prioritized(np.eye(2), np.ones(2), np.array([[np.nan, 0.0]]), np.ones(1), out, 0.0, 1e-3)
    assert np.isnan(out).all()


HUGE_ARM = (
    '<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>'
    '<origin xyz="1e200 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    '<joint name="j4" type="fixed"><parent link="l3"/><child link="tip"/>'
    '<origin xyz="1e200 0 0"/></joint>'
)
"""Two links of 1e200 m: finite, but ``J J^T`` overflows to inf."""


@pytest.mark.timeout(60)
@pytest.mark.parametrize("law", ["transpose", "nonlinear", "pseudoinverse"])
def test_a_huge_but_finite_model_diverges_alike_in_both_engines(law):
    """``J J^T`` overflows: both engines stop ``diverged`` with the same reason, no hang.

    The URDF check refuses such offsets (each within 1 km), so the model is built in code
    with Pinocchio, as a caller of :class:`clik.Robot` with their own model could.
    """
    text = urdf_text(LINKS + '<link name="l3"/><link name="tip"/>' + J1 + HUGE_ARM + J2)
    model = pin.buildModelFromXML(text)
    robot = Robot("huge", None, [], model, pin.GeometryModel(), pin.neutral(model))
    task = Task(robot, "tip", "position")
    hold = Hold(position=task.placement(robot.q_reference).translation + 1.0, duration=0.01)
    results = []
    for engine in ("python", "compiled"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the StabilityWarning of an infinite margin
            results.append(clik.track(task, hold, law=law, gain=10.0, dt=1e-3, engine=engine))
    assert [r.status for r in results] == ["diverged", "diverged"]
    assert results[0].reason == results[1].reason


# ------------------------------------------------------------------ robots as they come


def hold_scenario(tmp: Path, robot: Robot, source: str, extra: str = "") -> str:
    """A short position hold of the robot's last frame, from its reference posture."""
    frame = robot.model.frames[len(robot.model.frames) - 1].name
    del tmp
    return (
        f'[robot]\nsource = "{source}"\n[initial]\nq = "reference"\n'
        f'[task]\nframe = "{frame}"\nkind = "position"\n'
        '[trajectory]\nkind = "hold"\nduration = 0.05\n'
        '[solver]\nlaw = "pseudoinverse"\ngain = 100.0\ndt = 0.001\n' + extra
    )


@pytest.mark.timeout(180)
@pytest.mark.parametrize("name", CLIPPED)
def test_a_reference_outside_the_limits_is_clipped_with_a_warning(tmp_path, capsys, name):
    with pytest.warns(ReferenceClippedWarning) as caught:
        robot = Robot.load(name)
    warning = caught[0].message
    assert isinstance(warning, ReferenceClippedWarning)
    joint, (value, low, high) = next(iter(warning.joints.items()))
    assert repr(joint) in str(warning) and f"{value:.6g}" in str(warning)
    assert f"[{low:.6g}, {high:.6g}]" in str(warning)
    robot.check_within_limits(robot.q_reference)  # now a start the robot can be in
    code, err, out = solve(tmp_path, hold_scenario(tmp_path, robot, name), capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert_summary_within_limits(summary, robot)


@pytest.mark.timeout(180)
def test_a_user_q0_outside_the_limits_stays_infeasible():
    with pytest.warns(ReferenceClippedWarning):
        robot = Robot.load("kinova")
    q = robot.q_reference
    q[robot.model.joints[3].idx_q] = robot.lower[robot.model.joints[3].idx_q] - 0.5
    task = Task(robot, robot.model.frames[len(robot.model.frames) - 1].name, "position")
    hold = Hold(position=task.placement(robot.q_reference).translation, duration=0.05)
    with pytest.raises(InfeasibleError, match="outside the joint limits of kinova"):
        clik.track(task, hold, q0=q)


@pytest.mark.timeout(240)
def test_centauro_keeps_its_other_geometries_monitored(tmp_path, capsys):
    robot = Robot.load("centauro")
    with pytest.warns(SkippedGeometryWarning, match="pelvis"):
        cset = ConstraintSet(robot, obstacles=[Obstacle("ball", "sphere", [3, 0, 0], radius=0.1)])
    assert cset.scene is not None
    assert cset.scene.skipped_geometries
    assert cset.scene.n_links > 0  # the other geometries are checked
    extra = '[[obstacles]]\nname = "ball"\nshape = "sphere"\nposition = [3.0, 0, 0]\nradius = 0.1\n'
    text = hold_scenario(tmp_path, robot, "centauro", extra)
    code, err, out = solve(tmp_path, text, capsys)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["info"]["unmonitored_geometries"] == cset.scene.skipped_geometries
    assert summary["min_obstacle_distance"] is not None
    assert_summary_within_limits(summary, robot)


@pytest.mark.timeout(30)
def test_a_robot_without_collision_geometry_and_an_obstacle_is_named(tmp_path, capsys):
    (tmp_path / "r.urdf").write_text(urdf_text(LINKS + J1 + J2))
    robot = Robot.load(tmp_path / "r.urdf")
    with pytest.raises(GeometryError, match="has no collision geometry") as caught:
        ConstraintSet(robot, obstacles=[Obstacle("ball", "sphere", [1, 0, 0], radius=0.1)])
    assert "'ball'" in str(caught.value)
    extra = '[[obstacles]]\nname = "ball"\nshape = "sphere"\nposition = [1.0, 0, 0]\nradius = 0.1\n'
    text = hold_scenario(tmp_path, robot, "r.urdf", extra)
    code, err, out = solve(tmp_path, text, capsys)
    assert code == 2, err
    assert "no collision geometry" in err and "'ball'" in err
    assert "internal error" not in err
    assert not out.exists()


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name", [*CLIPPED, "centauro"])
def test_zoo_robots_once_refused_now_run(name):
    """The zoo's obstacle run (tests/zoo_runs.py): once refused before running, now run."""
    run = zoo_run(name)
    assert run.result is not None, f"{name} refused: {run.status}: {run.reason}"
    result = run.result
    assert result.status in ("completed", "deadlock", "violated"), result.reason
    assert np.all(np.isfinite(result.q))
    if result.status == "completed":
        assert_within_limits(result, result.robot)
    if name == "centauro":
        assert result.info["links"], "the other geometries stay monitored"


def test_the_record_budget_names_the_smallest_decimation_that_fits(planar4r):
    """``Tracker.check_size``: the ``record_every`` it names fits, the one below does not."""
    from clik.bounds import MAX_RECORD_BYTES
    from clik.loop.recording import bytes_per_sample, kept_samples

    tracker = clik.Tracker(Task(planar4r, "tip", "position", axes=["x", "y"]), dt=1e-3)
    with pytest.raises(clik.InputError, match="record_every: expected an integer >= ") as caught:
        tracker.check_size(5000.0, 1)
    least = int(str(caught.value).split(">= ")[1].split()[0])
    size = bytes_per_sample(planar4r.nq, planar4r.nv)
    assert kept_samples(5_000_001, least) * size <= MAX_RECORD_BYTES
    assert kept_samples(5_000_001, least - 1) * size > MAX_RECORD_BYTES
    tracker.check_size(5000.0, least)  # no error
    with pytest.raises(clik.InputError, match="record_every"):  # the run itself checks too
        tracker.run(Hold(position=np.zeros(3), duration=5000.0), record_every=least - 1)


def test_a_threshold_no_joint_can_use_is_refused_from_python_too(planar4r):
    """``JointLimits`` itself refuses it (the scenario's check is this one)."""
    from clik.constraints import JointLimits

    with pytest.raises(clik.InputError, match=r"constraints\.joint_limits\.threshold: expected a"):
        JointLimits(planar4r, 1e300)
    assert JointLimits(planar4r, 1.0).threshold.max() <= 0.25 * 2 * np.pi  # capped, not refused
