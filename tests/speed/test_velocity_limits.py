"""Joint speed limits respected by time scaling of the reference ([constraints.velocity_limits]).

Every number checked here is computed from the recorded arrays (``trajectory.npz`` or
the result) and the model's ``velocityLimit``, not taken from clik's own report.
"""

from __future__ import annotations

import inspect
import json
from pathlib import Path

import numpy as np
import pytest

import clik
from clik.cli import main
from clik.constraints import ConstraintSet, JointLimits
from clik.loop.tracker import Tracker
from clik.outputs.result import TrackingResult
from clik.speed.speed_limits import SpeedLimits
from clik.speed.time_scaling import running_max, running_mean, slowdown
from clik.speed.velocity_limits import track_within_limits
from clik.trajectory import Line, time_grid
from clik.trajectory.retimed import Retimed
from tests.limits_check import assert_summary_within_limits, assert_within_limits

FAST_S = 0.15
"""The Panda's hand 0.3 m along +y in this time [s]: about twice its joint speed limits."""

GAIN = 100.0
"""Law (10)'s gain [1/s]."""

DT = 1e-3
"""Sample time [s]."""

TRACKING_TOLERANCE = inspect.signature(Tracker.run).parameters["deadlock_error"].default
"""The run's tracking tolerance [m]: the task error below which clik calls no stall a deadlock."""

RATIO_TOL = 1e-9
"""Rounding allowed above a limit (ratio)."""

PATH_TOL = 1e-9
"""Distance of the re-timed reference from the original line [m]."""


def hand_line(panda: clik.Robot, offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Line:
    """0.3 m along +y from the hand at the ready pose (shifted by ``offset`` [m]) in 0.15 s."""
    start = hand_task(panda).placement(panda.q_reference).translation + np.asarray(offset)
    return Line(start, start + [0.0, 0.3, 0.0], duration=FAST_S)


def hand_task(panda: clik.Robot) -> clik.Task:
    return clik.Task(panda, "panda_hand", "position")


def hand_run(panda: clik.Robot, line: Line | None = None, **kwargs) -> TrackingResult:
    """:func:`track_within_limits` on the hand's fast line from the reference, law (10)."""
    kwargs = {"law": "pseudoinverse", "gain": GAIN, **kwargs}
    line = hand_line(panda) if line is None else line
    return track_within_limits(hand_task(panda), line, q0=panda.q_reference, **kwargs)


def scenario(
    tmp_path: Path,
    panda: clik.Robot,
    section: str = "",
    gain: float = GAIN,
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Path:
    """The fast Panda line (shifted by ``offset`` [m]) as a scenario file, ``section`` appended."""
    line = hand_line(panda, offset)
    text = f"""name = "panda fast line"
[robot]
source = "panda"
lock = {{ panda_finger_joint1 = 0.0, panda_finger_joint2 = 0.0 }}
[task]
frame = "panda_hand"
kind = "position"
[trajectory]
kind = "line"
start = {line.start.tolist()}
goal = {line.goal.tolist()}
duration = {FAST_S}
[solver]
law = "pseudoinverse"
gain = {gain}
dt = {DT}
{section}
"""
    path = tmp_path / "fast.toml"
    path.write_text(text)
    return path


def solve(path: Path, out: Path) -> tuple[int, dict, TrackingResult]:
    """``clik solve`` in this process: exit code, summary.json, trajectory.npz."""
    code = main(["solve", str(path), "--out", str(out), "--quiet"])
    summary = json.loads((out / "summary.json").read_text())
    return code, summary, TrackingResult.load(out / "trajectory.npz")


def velocity_ratio(qdot: np.ndarray, panda: clik.Robot) -> float:
    """Largest ``|qdot_i| / vmax_i`` of the recorded samples, from the model's limits."""
    return float(np.max(np.abs(qdot) / np.asarray(panda.model.velocityLimit)))


def assert_on_the_path(result: TrackingResult, line: Line) -> None:
    """The re-timed reference lies on the line; the hand within the run's tolerance of it."""
    ref = result.reference_position
    along = (ref - line.start) @ line.direction
    off = ref - line.start - along[:, None] * line.direction
    assert np.abs(off).max() <= PATH_TOL
    assert along.min() >= -PATH_TOL and along.max() <= line.length + PATH_TOL
    np.testing.assert_allclose(ref[-1], line.goal, atol=PATH_TOL)
    assert np.linalg.norm(result.position - ref, axis=1).max() <= TRACKING_TOLERANCE


FREE = "[constraints.joint_speed]\nenabled = false\n"
"""No speed limit in the law either: the law's own joint speeds."""


@pytest.fixture(scope="module")
def unconstrained(panda, tmp_path_factory) -> tuple[int, dict, TrackingResult]:
    folder = tmp_path_factory.mktemp("free")
    return solve(scenario(folder, panda, FREE), folder / "out")


@pytest.fixture(scope="module")
def constrained(panda, tmp_path_factory) -> tuple[int, dict, TrackingResult]:
    folder = tmp_path_factory.mktemp("limited")
    section = "[constraints.velocity_limits]\nenabled = true\nscale = 1.0\n"
    return solve(scenario(folder, panda, section), folder / "out")


def test_the_fast_line_breaks_its_limits_unconstrained(unconstrained, panda):
    code, summary, result = unconstrained
    # no limit in the law and no re-timing: a joint above its limit is not `completed`
    assert code == 3 and summary["status"] == "velocity_limit", summary["reason"]
    assert velocity_ratio(result.qdot, panda) > 1.5
    assert "above its speed limit" in summary["reason"]
    assert "velocity_limits" not in summary


def test_the_scenario_stays_within_its_limits(constrained, unconstrained, panda):
    code, summary, result = constrained
    assert code == 0 and summary["status"] == "completed", summary["reason"]
    assert_summary_within_limits(summary, panda)
    assert_within_limits(result, panda)
    ratio = velocity_ratio(result.qdot, panda)
    assert ratio <= 1.0 + RATIO_TOL
    assert summary["max_velocity_ratio"] == pytest.approx(ratio, rel=1e-12)
    record = summary["velocity_limits"]
    before = velocity_ratio(unconstrained[2].qdot, panda)
    assert record["max_ratio_before"] == pytest.approx(before, rel=1e-9)
    assert record["max_ratio"] == pytest.approx(ratio, rel=1e-9)
    assert record["respected"] is True and record["worst"] is None
    assert 1 <= record["passes"] <= 6 and record["kept_pass"] >= 1
    assert record["duration_s"] == FAST_S == summary["info"]["duration"]
    assert record["stretched_duration_s"] > FAST_S
    assert result.t[-1] == pytest.approx(record["stretched_duration_s"], abs=DT / 2)
    assert_on_the_path(result, hand_line(panda))
    assert summary["max_task_error"] <= TRACKING_TOLERANCE
    assert summary["max_task_error"] <= unconstrained[1]["max_task_error"]


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_the_api_stays_within_its_limits(panda, constrained, engine):
    line = hand_line(panda)
    result = hand_run(
        panda, line, velocity_limits=SpeedLimits(scale=1.0, acceleration=None), dt=DT, engine=engine
    )
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    assert velocity_ratio(result.qdot, panda) <= 1.0 + RATIO_TOL
    record = result.summary()["velocity_limits"]
    assert record["stretched_duration_s"] == pytest.approx(
        constrained[1]["velocity_limits"]["stretched_duration_s"], rel=1e-6
    )
    assert result.max_task_error <= TRACKING_TOLERANCE
    assert_on_the_path(result, line)


def test_a_smaller_scale_gives_slower_joints_and_a_longer_run(panda, constrained):
    result = hand_run(panda, velocity_limits=SpeedLimits(scale=0.5))
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    assert velocity_ratio(result.qdot, panda) <= 0.5 + RATIO_TOL
    stretched = result.summary()["velocity_limits"]["stretched_duration_s"]
    assert stretched > 1.5 * constrained[1]["velocity_limits"]["stretched_duration_s"]


def test_an_acceleration_limit_is_respected_too(panda):
    amax = 5.0
    result = hand_run(panda, velocity_limits=SpeedLimits(acceleration=amax))
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    qddot = np.diff(result.qdot, axis=0) / np.diff(result.t)[:, None]
    assert np.abs(qddot).max() <= amax * (1.0 + RATIO_TOL)
    assert velocity_ratio(result.qdot, panda) <= 1.0 + RATIO_TOL
    record = result.summary()["velocity_limits"]
    assert record["acceleration"] == amax
    assert record["max_ratio_before"] > 2.0  # sqrt(|qddot| / amax) of the fast line


def test_a_per_joint_acceleration_limit_bounds_that_joint_only(panda):
    result = hand_run(panda, velocity_limits=SpeedLimits(acceleration={"panda_joint3": 3.0}))
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    qddot = np.diff(result.qdot, axis=0) / np.diff(result.t)[:, None]
    j3 = panda.joint_names.index("panda_joint3")
    assert np.abs(qddot[:, j3]).max() <= 3.0 * (1.0 + RATIO_TOL)
    assert velocity_ratio(result.qdot, panda) <= 1.0 + RATIO_TOL


def test_the_scenario_takes_an_acceleration_table(panda, tmp_path):
    section = (
        "[constraints.velocity_limits]\nenabled = true\nscale = 0.8\n"
        "acceleration = { panda_joint2 = 4.0, panda_joint3 = 4.0 }\n"
    )
    code, summary, result = solve(scenario(tmp_path, panda, section), tmp_path / "out")
    assert code == 0 and summary["status"] == "completed", summary["reason"]
    assert_summary_within_limits(summary, panda)
    assert velocity_ratio(result.qdot, panda) <= 0.8 + RATIO_TOL
    qddot = np.diff(result.qdot, axis=0) / np.diff(result.t)[:, None]
    assert np.abs(qddot[:, 1:3]).max() <= 4.0 * (1.0 + RATIO_TOL)
    assert summary["velocity_limits"]["acceleration"] == {"panda_joint2": 4.0, "panda_joint3": 4.0}


def test_error_correction_alone_ends_velocity_limit(panda):
    """A start 0.1 m from the reference with K = 500: K e is 50 m/s, re-timing cannot help."""
    line = hand_line(panda, offset=(0.1, 0.0, 0.0))
    result = hand_run(panda, line, gain=500.0, joint_speed=None)
    ratio = velocity_ratio(result.qdot, panda)
    assert ratio > 1.5
    assert result.status == "velocity_limit"
    record = result.summary()["velocity_limits"]
    assert record["respected"] is False and record["max_ratio"] == pytest.approx(ratio, rel=1e-9)
    assert record["stop"]  # it says why re-timing stopped
    table = np.abs(result.qdot) / np.asarray(panda.model.velocityLimit)
    k, i = np.unravel_index(np.argmax(table), table.shape)
    joint, when = panda.joint_names[i], result.t[k]
    for words in (f"joint {joint!r}", f"{ratio:.3g} x its velocity limit", f"t = {when:.6g} s"):
        assert words in result.reason, result.reason
    assert "K e" in result.reason


def test_error_correction_alone_exits_3_from_the_command_line(panda, tmp_path):
    section = FREE + "[constraints.velocity_limits]\nenabled = true\n"
    path = scenario(tmp_path, panda, section, gain=500.0, offset=(0.1, 0.0, 0.0))
    code, summary, result = solve(path, tmp_path / "out")
    assert code == 3
    assert summary["status"] == "velocity_limit"
    assert summary["velocity_limits"]["max_ratio"] > 1.0
    assert velocity_ratio(result.qdot, panda) > 1.0
    assert "x its velocity limit at t = " in summary["reason"]


def test_with_a_constraint_set(panda):
    """The passes run with the constraint rows: joint ranges kept, speeds within limits."""
    constraints = ConstraintSet(panda, joint_limits=JointLimits(panda, np.radians(5.0)))
    result = hand_run(panda, constraints=constraints)
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    assert velocity_ratio(result.qdot, panda) <= 1.0 + RATIO_TOL


def test_a_disabled_section_changes_nothing(panda, tmp_path, unconstrained):
    section = FREE + "[constraints.velocity_limits]\nenabled = false\nscale = 0.5\n"
    code, summary, result = solve(scenario(tmp_path, panda, section), tmp_path / "out")
    assert code == 3 and "velocity_limits" not in summary
    assert summary["status"] == unconstrained[1]["status"] == "velocity_limit"
    np.testing.assert_array_equal(result.qdot, unconstrained[2].qdot)


# ------------------------------------------------------------------ the pieces


def test_retimed_keeps_the_path_and_scales_the_velocity(panda):
    line = hand_line(panda)
    tau = time_grid(line.duration, 1e-4)
    sigma = 1.0 - 0.5 * np.sin(np.pi * tau / line.duration) ** 2  # 1 at the ends, 0.5 midway
    slow = Retimed(line, tau, sigma)
    trapezoid = np.sum(np.diff(tau) * (1.0 / sigma[1:] + 1.0 / sigma[:-1]) / 2.0)
    assert slow.duration == pytest.approx(trapezoid, rel=1e-12)
    t = np.linspace(0.0, slow.duration, 2001)
    ref = slow.sample(t)
    inner = line.sample(slow.inner_time(t))
    np.testing.assert_allclose(ref.position, inner.position, atol=1e-15)
    np.testing.assert_allclose(ref.position[-1], line.goal, atol=1e-12)
    fd = np.gradient(ref.position, t, axis=0)
    assert np.abs(fd - ref.linear_velocity)[1:-1].max() < 1e-3 * np.abs(ref.linear_velocity).max()
    after = slow.sample(np.array([slow.duration + 1.0]))
    np.testing.assert_array_equal(after.linear_velocity, np.zeros((1, 3)))


def test_a_constant_rate_stretches_by_its_inverse(panda):
    line = hand_line(panda)
    slow = Retimed(line, [0.0, line.duration], [0.5, 0.5])
    assert slow.duration == pytest.approx(2.0 * line.duration)
    ref = slow.sample(np.array([slow.duration / 2]))
    mid = line.sample(np.array([line.duration / 2]))
    np.testing.assert_allclose(ref.position, mid.position)
    np.testing.assert_allclose(ref.linear_velocity, 0.5 * mid.linear_velocity)


@pytest.mark.parametrize("half", [1, 3, 20])
def test_the_envelope_is_continuous_and_above_the_ratio(half):
    rng = np.random.default_rng(half)
    ratio = np.abs(rng.normal(size=500)) * (rng.random(500) < 0.05) * 3.0
    peak = running_max(ratio, half)
    brute = np.array([ratio[max(0, k - half) : k + half + 1].max() for k in range(ratio.size)])
    np.testing.assert_array_equal(peak, brute)
    envelope = running_mean(peak, half)
    assert np.all(envelope >= ratio - 1e-12)
    assert np.abs(np.diff(envelope)).max() <= ratio.max() / (half + 1) + 1e-12
    factor = slowdown(ratio, 1e-3, half * 1e-3, 0.05)
    assert np.all(factor >= np.maximum(1.0, ratio * 1.05) - 1e-12)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"scale": 0.0}, "velocity_limits.scale: expected a number > 0 and <= 10"),
        ({"scale": -1.0}, "velocity_limits.scale"),
        ({"scale": "a"}, "velocity_limits.scale"),
        ({"scale": 11.0}, "<= 10"),
        ({"acceleration": 0.0}, "velocity_limits.acceleration: expected a number > 0"),
        ({"acceleration": {"j": -1.0}}, "velocity_limits.acceleration.j"),
        ({"margin": 2.0}, "velocity_limits.margin"),
        ({"max_passes": 0}, "velocity_limits.max_passes"),
        ({"window": 0.0}, "velocity_limits.window"),
    ],
)
def test_bad_settings_are_refused(kwargs, words):
    with pytest.raises(clik.InputError) as caught:
        SpeedLimits(**kwargs)
    assert words in str(caught.value)


def test_an_unknown_joint_in_the_acceleration_table_is_named(panda):
    with pytest.raises(clik.JointNotFound, match="'panda_joint9' not found"):
        SpeedLimits(acceleration={"panda_joint9": 1.0}).bounds(panda)


def test_a_slow_line_needs_no_re_timing(panda):
    task = hand_task(panda)
    start = task.placement(panda.q_reference).translation
    line = Line(start, start + [0.0, 0.3, 0.0], duration=3.0)
    result = track_within_limits(task, line, q0=panda.q_reference, law="pseudoinverse", gain=GAIN)
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    assert velocity_ratio(result.qdot, panda) < 1.0
    record = result.summary()["velocity_limits"]
    assert record["passes"] == 0 and record["stretched_duration_s"] == 3.0
    assert "no re-timing needed" in result.reason
