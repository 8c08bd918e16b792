"""The CLIK laws (8), (9), (10) tracking the case study's line and a Panda pose circle."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik import InputError, StabilityWarning, Task, TrackingResult, track
from clik.trajectory import Circle, Function, Line, PoseTrajectory, Slerp
from tests.limits_check import assert_completed, assert_within_limits

Q0_DEG = [180.0, -30.0, -90.0, -30.0]


@pytest.fixture(scope="module")
def case(planar4r):
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians(Q0_DEG)
    line = Line(task.placement(q0).translation, [0.8, -0.2, 0.0], duration=3.0, cruise_speed=0.12)
    return task, q0, line


def run(case, law, gain, **kw) -> TrackingResult:
    task, q0, line = case
    return track(task, line, q0=q0, law=law, gain=gain, dt=1e-3, **kw)


def test_transpose_error_shrinks_as_one_over_alpha(case):
    errors = {a: run(case, "transpose", a).max_task_error for a in (250.0, 500.0, 1000.0)}
    assert errors[1000.0] < 1e-3
    # bounded error proportional to |xdot_d| / alpha: halving alpha doubles it (within 10 %)
    assert errors[500.0] / errors[1000.0] == pytest.approx(2.0, rel=0.1)
    assert errors[250.0] / errors[500.0] == pytest.approx(2.0, rel=0.1)


def test_pseudoinverse_tracks_below_a_micrometre(case):
    result = run(case, "pseudoinverse", 1000.0)
    assert_completed(result)
    assert result.max_task_error < 1e-6


@pytest.mark.parametrize("alpha", [250.0, 500.0, 1000.0])
def test_nonlinear_tracks_at_least_as_well_as_transpose(case, alpha):
    nonlinear = run(case, "nonlinear", alpha).max_task_error
    transpose = run(case, "transpose", alpha).max_task_error
    assert nonlinear <= transpose
    # In discrete time (8) is not exact: its error stays a fraction of (9)'s, not zero.
    assert nonlinear > 1e-5


def test_result_arrays_and_end_point(case):
    result = run(case, "transpose", 1000.0)
    n = 3001
    assert result.t.shape == (n,) and result.q.shape == (n, 4) and result.qddot.shape == (n, 4)
    np.testing.assert_allclose(result.position[-1, :2], [0.8, -0.2], atol=1e-4)
    np.testing.assert_allclose(result.qddot[1:], np.diff(result.qdot, axis=0) / 1e-3)
    # joints integrate the recorded velocities: q_{k+1} = q_k + qdot_k dt
    np.testing.assert_allclose(np.diff(result.q, axis=0), result.qdot[:-1] * 1e-3, atol=1e-12)


def test_decimated_recording_keeps_scalars_exact(case):
    full = run(case, "transpose", 1000.0)
    dec = run(case, "transpose", 1000.0, record_every=100)
    assert dec.t.shape == (31,)
    np.testing.assert_allclose(dec.q, full.q[::100])
    assert dec.max_task_error == pytest.approx(full.max_task_error)
    np.testing.assert_allclose(dec.joint_min, full.joint_min)
    np.testing.assert_allclose(dec.joint_max, full.joint_max)


def test_save_and_load(case, tmp_path):
    result = run(case, "transpose", 1000.0)
    path = result.save(tmp_path / "run.npz")
    back = TrackingResult.load(path)
    np.testing.assert_array_equal(back.q, result.q)
    np.testing.assert_array_equal(back.task_error_norm, result.task_error_norm)
    assert back.status == "completed" and back.steps == 3001
    assert back.violations == result.violations == []
    np.testing.assert_array_equal(back.joint_max, result.joint_max)
    assert_within_limits(back, result.robot)
    assert back.info["law"] == "transpose"


def test_panda_pose_circle_with_slerp(panda):
    task = Task(panda, "panda_hand", "pose")
    start = task.placement(panda.q_reference)
    goal = start.rotation @ pin.rpy.rpyToMatrix(0.3, -0.2, 0.4)
    circle = Circle.through(
        start.translation,
        start.translation + [0.0, 0.1, 0.0],
        [1.0, 0.0, 0.0],
        2 * math.pi,
        duration=3.0,
    )
    traj = PoseTrajectory(circle, Slerp(start.rotation, goal, duration=3.0))
    result = track(task, traj, law="pseudoinverse", gain=1000.0, dt=1e-3)
    assert_completed(result, panda)
    assert result.max_task_error < 1e-3
    assert result.orientation_error_norm.max() < 1e-3


def test_unstable_gain_is_warned(panda):
    task = Task(panda, "panda_hand", "position")
    circle = Circle.through(
        task.placement(panda.q_reference).translation, [0.3, 0.1, 0.5], angle=1.0, duration=0.2
    )
    J = task.jacobian(panda.q_reference)
    bound = 2.0 / (1e-3 * np.linalg.eigvalsh(J @ J.T)[-1])  # alpha where alpha dt lambda = 2
    with pytest.warns(StabilityWarning, match="alpha dt lambda_max"):
        track(task, circle, law="transpose", gain=1.05 * bound, dt=1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        track(task, circle, law="transpose", gain=0.95 * bound, dt=1e-3)


def test_diverging_run_stops_with_status(panda):
    task = Task(panda, "panda_hand", "pose")
    M = task.placement(panda.q_reference)
    traj = PoseTrajectory(
        Line(M.translation, M.translation + [0.1, 0.0, 0.0], duration=1.0),
        Slerp(M.rotation, M.rotation, duration=1.0),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StabilityWarning)
        result = track(task, traj, law="transpose", gain=1e5, dt=1e-3, joint_speed=None)
        limited = track(task, traj, law="transpose", gain=1e5, dt=1e-3)
    assert result.status == "diverged"
    assert "in one step" in result.reason
    # within the joint speed limits no step is that large: the stability check stops it
    assert limited.status == "diverged" and "explicit Euler is unstable" in limited.reason
    assert np.all(np.isfinite(result.q))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"q0": [0.0, 0.0, 0.0]}, "q0: expected an array of 4 finite joint values"),
        ({"q0": [0.0, math.nan, 0.0, 0.0]}, "q0: expected an array of 4 finite joint values"),
        ({"q0": [0.0, math.inf, 0.0, 0.0]}, "q0: expected an array of 4 finite joint values"),
        ({"dt": 0.0}, "dt: expected a positive finite number [s]"),
        ({"dt": -1e-3}, "dt: expected a positive finite number [s]"),
        ({"gain": 0.0}, "gain: expected positive finite values [1/s]"),
        ({"gain": [1000.0, -1.0]}, "gain: expected positive finite values [1/s]"),
        ({"gain": [1.0, 2.0, 3.0]}, "gain: expected a positive number or 2 positive numbers"),
        ({"law": "newton"}, "law: expected one of 'transpose', 'nonlinear', 'pseudoinverse'"),
        ({"record_every": 0}, "record_every: expected an integer >= 1"),
    ],
)
def test_bad_input_is_named(case, kwargs, message):
    task, q0, line = case
    args = {"q0": q0, "law": "transpose", "gain": 1000.0, "dt": 1e-3} | kwargs
    with pytest.raises(InputError) as info:
        track(task, line, **args)
    assert message in str(info.value)


def test_trajectory_yielding_nan_is_refused(case):
    task, q0, _ = case

    def path(t: float):
        p = np.array([0.56, -0.15, 0.0]) + t * np.array([0.05, 0.0, 0.0])
        return (p * math.nan if t > 0.5 else p), np.array([0.05, 0.0, 0.0])

    with pytest.raises(InputError) as info:
        track(task, Function(path, duration=1.0), q0=q0)
    assert "trajectory: expected a callable returning (x_d, xdot_d), each finite" in str(info.value)
    assert "t = 0.501" in str(info.value)


def test_orientation_task_needs_orientation_reference(panda):
    task = Task(panda, "panda_hand", "pose")
    line = Line([0.3, 0.0, 0.5], [0.4, 0.0, 0.5], duration=1.0)
    with pytest.raises(InputError, match="trajectory: expected an orientation reference"):
        track(task, line)


def test_public_api_names():
    for name in ("Robot", "Task", "track", "solve", "Tracker", "ClikError"):
        assert hasattr(clik, name)
