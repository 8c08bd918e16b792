"""The compiled engine against its specification, the Python loop of clik.loop.tracking.

Both engines run the same run; they must give the same status, reason, steps and
events, and joint trajectories equal within 1e-9 rad (the engines differ only in
floating-point rounding: a different but equivalent order of operations, and
Eigen's eigensolver and SVD instead of LAPACK's).
"""

from __future__ import annotations

import re
import subprocess
import sys
import warnings

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import clik
from clik.engine import check_versions, load
from clik.errors import EngineError
from clik.loop.laws import CONDITION_RATIO
from clik.scenarios import CASE_STUDY
from clik.trajectory import Hold, Line, PoseTrajectory

TOLERANCE = 1e-9
"""Largest difference between the engines' joint trajectories [rad or m]."""

DEADLOCK_STEPS = 2
"""Largest difference of the stop sample of a deadlock between the engines: the blocked
fraction of the demand hovers about its threshold in the lost direction (measured: 1)."""


def both(task, trajectory, **kwargs):
    """The run in each engine: (python, compiled)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tuple(
            clik.track(task, trajectory, engine=e, **kwargs) for e in ("python", "compiled")
        )


def regular_samples(task, result) -> int:
    """Recorded samples before the task Jacobian first enters the damping band of a
    singularity (a singular value below ``CONDITION_RATIO`` of the largest).

    None under law (8) for a task with more rows than joints: its error then lies mostly
    outside the range of ``J`` (measured: ``|J^T e| ~ 0.04 sigma_max |e|``), and the
    law's gain ``beta = e . xdot_d / |J^T e|^2`` divides by that small number; the loop
    amplifies the engines' rounding ~1.15 times per sample (measured: 1e-16 at t = 0,
    8e-10 rad after 150 samples, on a 5-joint chain under a pose task).
    """
    if result.info["law"] == "nonlinear" and len(task.rows) > task.robot.nv:
        return 0
    for i, q in enumerate(result.q):
        sv = np.linalg.svd(task.jacobian(q), compute_uv=False)
        if sv[-1] < CONDITION_RATIO * sv[0]:
            return i
    return len(result.q)


def assert_same(a, b, task=None):
    """Same outcome; trajectories within :data:`TOLERANCE` while the task is regular.

    Where the filtered inverse is active (``task`` given and a singular value below
    ``CONDITION_RATIO`` of the largest), it weighs the weak direction by
    ``sigma / epsilon^2``: the engines' different rounding (1e-16) is amplified up to a
    million times and the joint motion along that direction may part (measured: 1.6e-6
    rad on chains whose joints all turn about one axis; 0.02 rad over a deadlock's
    chattering), so from there on only the outcome is compared (status, stop sample
    within :data:`DEADLOCK_STEPS` for a deadlock, reasons, events).
    """
    n = len(a.q) if task is None else regular_samples(task, a)
    if a.status == "deadlock":  # blocked for deadlock_window (0.1 s) before the stop
        n = min(n, int(np.searchsorted(a.t, a.t[-1] - 0.1)))
    assert a.status == b.status
    if n < len(a.q) or a.status == "deadlock":
        assert abs(a.steps - b.steps) <= DEADLOCK_STEPS
        # the words before the first number: the engines' numbers part there
        assert re.split(r"\d", a.reason)[0] == re.split(r"\d", b.reason)[0]
    else:
        assert (a.steps, a.reason) == (b.steps, b.reason)
        assert a.events == b.events
        assert [v["constraint"] for v in a.violations] == [v["constraint"] for v in b.violations]
        for va, vb in zip(a.violations, b.violations, strict=True):
            assert (va["t_first"], va["t_last"]) == (vb["t_first"], vb["t_last"])
            assert va["worst"] == pytest.approx(vb["worst"], abs=TOLERANCE)
        assert abs(a.max_task_error - b.max_task_error) <= TOLERANCE
        np.testing.assert_array_equal(a.t, b.t)
    dt = float(a.info["dt"])
    n = min(n, len(a.q), len(b.q))
    for name in ("q", "qdot", "position", "task_error_norm"):
        x, y = getattr(a, name)[:n], getattr(b, name)[:n]
        if name == "qdot":  # as joint steps qdot dt [rad or m], the unit of the bound
            x, y = x * dt, y * dt
        assert np.all(np.isfinite(x) == np.isfinite(y)), name
        finite = np.isfinite(x)
        assert np.abs(x[finite] - y[finite]).max(initial=0.0) <= TOLERANCE, name


@pytest.fixture(scope="module")
def panda():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return clik.Robot.load("panda")


def pose_line(task, q0, offset, duration):
    """A line of the frame's position from its pose at ``q0``, orientation held."""
    M = task.placement(q0)
    line = Line(M.translation, M.translation + np.asarray(offset), duration)
    return PoseTrajectory(line, Hold(rotation=M.rotation, duration=duration))


@pytest.mark.parametrize("law", ["transpose", "nonlinear", "pseudoinverse"])
@pytest.mark.parametrize("record_every", [1, 7])
def test_panda_pose_line(panda, law, record_every):
    task = clik.Task(panda, "panda_hand", "pose")
    trajectory = pose_line(task, panda.q_reference, [0.1, 0.05, -0.05], 1.0)
    gain = 100.0 if law == "pseudoinverse" else 20.0
    a, b = both(task, trajectory, law=law, gain=gain, record_every=record_every)
    # laws (9) and (8) at gain 20 lag 6.4 and 3.3 cm behind the line (measured): off track
    assert a.status == ("completed" if law == "pseudoinverse" else "off_track")
    assert_same(a, b)


def test_masked_and_orientation_tasks(panda):
    q0 = panda.q_reference
    for kind, axes in (("position", ["x", "z"]), ("orientation", None), ("pose", ["x", "ry"])):
        task = clik.Task(panda, "panda_hand", kind, axes=axes)
        a, b = both(task, pose_line(task, q0, [0.05, 0.0, 0.02], 0.5), law="pseudoinverse",
                    gain=50.0)  # fmt: skip
        assert_same(a, b)


def test_stops_agree(panda):
    """diverged (K dt >= 2), deadlock (a reference out of reach) and stall end alike."""
    task = clik.Task(panda, "panda_hand", "position")
    q0 = panda.q_reference
    a, b = both(task, pose_line(task, q0, [0.05, 0, 0], 0.3), law="pseudoinverse", gain=2500.0)
    assert a.status == "diverged" and "K dt" in a.reason
    assert_same(a, b)
    far = Line(task.placement(q0).translation, [3.0, 0.0, 0.5], 1.0)
    # within its speed limits the arm stretches after the reference's end: settle
    a, b = both(task, far, law="pseudoinverse", gain=100.0, settle=0.5)
    assert a.status == "deadlock"
    assert_same(a, b)
    runs = []
    for engine in ("python", "compiled"):  # law (9) at rest past its reach: the stall check
        tracker = clik.Tracker(task, law="transpose", gain=50.0, engine=engine)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs.append(tracker.run(far, q0, settle=1.0))
    assert runs[0].status == "deadlock"
    assert_same(*runs)


def test_joint_limit_violations_agree():
    """A run that crosses the robot's own joint limits records the same violations."""
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180, -30, -90, -30])
    line = Line(task.placement(q0).translation, [0.2, 0.1, 0.0], 1.0)
    a, b = both(task, line, q0=q0, law="pseudoinverse", gain=100.0)
    assert_same(a, b)


def chain_urdf(joints: list[tuple[str, int, tuple[float, float, float], float]]) -> str:
    """A serial chain: (kind, axis index, origin xyz, origin yaw) per joint, then a tip."""
    links = "".join(f'<link name="l{i}"/>' for i in range(len(joints) + 2))
    body = []
    for i, (kind, axis, xyz, yaw) in enumerate(joints):
        a = ["0", "0", "0"]
        a[axis] = "1"
        limit = "-0.5 0.5" if kind == "prismatic" else "-3 3"
        lo, hi = limit.split()
        body.append(
            f'<joint name="j{i}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
            f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="0 0 {yaw}"/>'
            f'<axis xyz="{" ".join(a)}"/>'
            f'<limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/></joint>'
        )
    n = len(joints)
    body.append(
        f'<joint name="tip_joint" type="fixed"><parent link="l{n}"/><child link="l{n + 1}"/>'
        '<origin xyz="0.2 0 0"/></joint>'
    )
    return f'<?xml version="1.0"?><robot name="chain">{links}{"".join(body)}</robot>'


joint_st = st.tuples(
    st.sampled_from(["revolute", "revolute", "revolute", "prismatic"]),
    st.integers(0, 2),
    st.tuples(*[st.floats(-0.3, 0.3).map(lambda v: round(v, 3))] * 3),
    st.floats(-1.5, 1.5).map(lambda v: round(v, 3)),
)

TASKS = [
    ("position", None),
    ("position", ["x", "y"]),
    ("orientation", None),
    ("pose", None),
    ("pose", ["x", "y", "rz"]),
]


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    joints=st.lists(joint_st, min_size=2, max_size=8),
    task_index=st.integers(0, len(TASKS) - 1),
    law=st.sampled_from(["transpose", "nonlinear", "pseudoinverse"]),
    gain=st.floats(5.0, 200.0),
    offset=st.tuples(*[st.floats(-0.05, 0.05)] * 3),
    seed=st.integers(0, 2**16),
)
def test_random_chains(tmp_path_factory, joints, task_index, law, gain, offset, seed):
    path = tmp_path_factory.mktemp("chain") / "chain.urdf"
    path.write_text(chain_urdf(joints))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = clik.Robot.load(str(path))
    kind, axes = TASKS[task_index]
    task = clik.Task(robot, f"l{len(joints) + 1}", kind, axes=axes)
    q0 = np.clip(np.random.default_rng(seed).uniform(-1.0, 1.0, robot.nq), robot.lower, robot.upper)
    trajectory = pose_line(task, q0, offset, 0.15)
    a, b = both(task, trajectory, q0=q0, law=law, gain=gain)
    assert_same(a, b, task)


def test_engine_is_the_default_and_checked(panda):
    task = clik.Task(panda, "panda_hand", "pose")
    assert clik.Tracker(task).engine == "compiled"
    with pytest.raises(clik.InputError, match="engine"):
        clik.Tracker(task, engine="fortran")


def test_version_mismatch_is_refused():
    check_versions({"pinocchio": "4.1.0"}, {"pinocchio": "4.1.0"})
    with pytest.raises(EngineError, match=r"pinocchio 4\.1\.0 \(built\) but 3\.8\.0"):
        check_versions({"pinocchio": "4.1.0"}, {"pinocchio": "3.8.0"})
    assert load().PINOCCHIO_VERSION == pin.__version__


def test_import_clik_with_another_pinocchio_fails_with_the_versions():
    """A faked running version: ``import clik`` stops with the message, not a crash."""
    code = (
        "import pinocchio\n"
        "pinocchio.__version__ = '3.8.0'\n"
        "try:\n"
        "    import clik\n"
        "except Exception as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("EngineError compiled engine: built against other library")
    assert "3.8.0 (running)" in out.stdout


def scenario_runs(name, row_gain=..., **solver):
    """A shipped scenario run by each engine: (python, compiled); ``solver``: law, gain,
    dt in place of the file's; ``row_gain``: the dexterity row's gain (None: the default)."""
    from clik.scenarios import scenario_path
    from clik.scenarios.runner import build

    run = build(scenario_path(name))
    if row_gain is not ...:
        run.tracker.constraints.dexterity.gain = row_gain
    if solver:
        tr = run.tracker
        run.tracker = clik.Tracker(
            run.task, **{"law": tr.law, "gain": tr.K_task, "dt": tr.dt, **solver},
            constraints=tr.constraints,
        )  # fmt: skip
    results = []
    for engine in ("python", "compiled"):
        run.tracker.engine = engine
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results.append(run.execute())
    return results


@pytest.mark.parametrize("name", CASE_STUDY)
def test_case_study_runs_agree(name):
    a, b = scenario_runs(name)
    assert a.status == "completed" and a.info["engine"] == "python"
    assert b.info["engine"] == "compiled"
    assert_same(a, b)
    sa, sb = a.summary(), b.summary()
    for key in ("min_obstacle_distance", "max_task_error"):
        assert sa[key] == pytest.approx(sb[key], abs=TOLERANCE)
    assert sa["events"] == sb["events"] and sa["violations"] == sb["violations"]
    for key in ("active", "witness", "obstacle_distance", "obstacle_link"):
        if key in a.extra:
            np.testing.assert_allclose(a.extra[key], b.extra[key], atol=TOLERANCE, rtol=0)


@pytest.mark.parametrize(
    ("law", "row_gain"), [("transpose", 1000.0), ("pseudoinverse", 1000.0), ("nonlinear", None)]
)
def test_dexterity_scenario_agrees(law, row_gain):
    """case_study_dexterity (the arm past its reach) under each law: the row's events,
    trajectories and the summary's manipulability agree. (Law (8) with the file's row gain
    1000 chatters at its stability edge, where rounding decides a release: the default.)"""
    a, b = scenario_runs("case_study_dexterity", law=law, row_gain=row_gain)
    assert a.events and all(e["constraint"] == "dexterity" for e in a.events)
    if law == "nonlinear":
        # Law (8)'s beta divides by |J^T e|^2, small on the stretched arm, where the joint
        # speed limits hold the row's push and the task's: from the row's activation on, the
        # engines' rounding is amplified about 1.08 times per sample (measured: 1e-12 rad
        # at t = 3.42 s, 1.3e-3 rad at most later). Exact before it, the outcome after.
        n = int(np.searchsorted(a.t, a.events[0]["t"]))
        np.testing.assert_allclose(a.q[:n], b.q[:n], atol=TOLERANCE, rtol=0)
        assert (a.status, a.steps, a.events) == (b.status, b.steps, b.events)
        assert a.max_task_error == pytest.approx(b.max_task_error, rel=1e-3)
        return
    assert_same(a, b)
    sa, sb = a.summary(), b.summary()
    assert sa["min_manipulability"] == pytest.approx(sb["min_manipulability"], abs=TOLERANCE)
    assert sa["dexterity_used"] == sb["dexterity_used"]
    np.testing.assert_allclose(
        a.extra["manipulability"], b.extra["manipulability"], atol=TOLERANCE, rtol=0
    )


@pytest.mark.parametrize("law", ["pseudoinverse", "transpose"])
def test_panda_circle_with_obstacles_and_joint_ranges_agrees(law):
    """The bench's scene: the Panda's circle, 3 spheres against every link, joint ranges."""
    from benchmarks.config import QUICK
    from benchmarks.step_lines import (
        OBSTACLES_ONE_ACTIVE,
        PSEUDOINVERSE,
        TRANSPOSE,
        panda_setup,
        panda_tracker,
    )

    panda = panda_setup(QUICK)
    chosen = PSEUDOINVERSE if law == "pseudoinverse" else TRANSPOSE
    runs = []
    for engine in ("python", "compiled"):
        tracker = panda_tracker(panda, chosen, OBSTACLES_ONE_ACTIVE, engine=engine)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs.append(tracker.run(panda.trajectory, panda.q0))
    a, b = runs
    assert a.events, "a sphere engages a row"
    assert_same(a, b)
    assert a.summary()["min_obstacle_distance"] == pytest.approx(
        b.summary()["min_obstacle_distance"], abs=TOLERANCE
    )


def test_panda_obstacle_conflict_ends_alike(panda):
    """Three spheres across the hand's line: constraints and task conflict."""
    from clik.constraints import ConstraintSet, JointLimits, Obstacle

    task = clik.Task(panda, "panda_hand", "position")
    q0 = panda.q_reference
    p0 = task.placement(q0).translation
    obstacles = [
        Obstacle(f"s{i}", "sphere", position=p0 + [0.12, dy, 0.0], radius=0.04)
        for i, dy in enumerate((-0.06, 0.0, 0.06))
    ]
    runs = []
    for engine in ("python", "compiled"):
        cset = ConstraintSet(
            panda, obstacles=obstacles, joint_limits=JointLimits(panda, threshold=np.radians(2))
        )
        tracker = clik.Tracker(task, law="pseudoinverse", gain=100.0, constraints=cset,
                               engine=engine)  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs.append(tracker.run(Line(p0, p0 + [0.3, 0.0, 0.0], 1.0), q0))
    a, b = runs
    assert a.events
    assert_same(a, b)


def test_cli_and_scenario_choose_the_engine(tmp_path):
    import json

    from clik.cli import main
    from clik.scenarios import scenario_path

    text = scenario_path("case_study_both").read_text()
    scenario = tmp_path / "s.toml"
    scenario.write_text(text.replace("dt = 0.001", 'dt = 0.001\nengine = "python"'))
    for args, expected in (([], "python"), (["--engine", "compiled"], "compiled")):
        out = tmp_path / f"out_{expected}"
        assert main(["solve", str(scenario), "--out", str(out), "--quiet", *args]) == 0
        assert json.loads((out / "summary.json").read_text())["info"]["engine"] == expected
    scenario.write_text(text.replace("dt = 0.001", 'dt = 0.001\nengine = "gpu"'))
    assert main(["solve", str(scenario), "--out", str(tmp_path / "bad"), "--quiet"]) == 2
