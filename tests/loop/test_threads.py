"""Runs and solves on shared robots, tasks and constraint sets, from several threads.

Every run and solve writes only its own state (Pinocchio data, collision geometry data,
extended task, the law's scratch arrays, records); robots, tasks, trackers and sets are
only read. So runs started from four threads at once give, bit for bit, what each gives
alone, in both engines (issue 22).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import pytest

import clik
from clik import Task
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.trajectory import Line

ENGINES = ("compiled", "python")
THREADS = 4
RUNS = 8
"""Runs per case: two per thread, each with its own line."""


SWITCH_INTERVAL = 1e-5
"""Seconds between the interpreter's thread switches while the threads run (the default
5 ms lets a short run finish before another thread starts: threads would not meet)."""


def in_threads(job: Callable[[int], Any], n: int) -> list[Any]:
    """``job(i)`` for ``i < n`` from :data:`THREADS` threads at once, in order of ``i``."""
    default = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL)
    try:
        with ThreadPoolExecutor(THREADS) as pool:
            return list(pool.map(job, range(n)))
    finally:
        sys.setswitchinterval(default)


def assert_same_runs(serial: list[clik.TrackingResult], threaded: list[clik.TrackingResult]):
    """The same runs, bit for bit: joint trajectories, statuses, events, distances."""
    for i, (a, b) in enumerate(zip(serial, threaded, strict=True)):
        assert np.array_equal(a.q, b.q), f"run {i}: q differs"
        assert (a.status, a.reason) == (b.status, b.reason), i
        assert a.events == b.events, i
        for key in ("obstacle_distance", "active"):
            if key in a.extra:
                assert np.array_equal(a.extra[key], b.extra[key]), (i, key)


@pytest.fixture(scope="module")
def panda_case(panda):
    """The Panda's hand along lines past a ball, a moving ball, a tighter joint 4."""
    task = Task(panda, "panda_hand", "position")
    p0 = task.placement(panda.q_reference).translation
    cset = ConstraintSet(
        panda,
        obstacles=[
            Obstacle("ball", "sphere", p0 + [0.1, 0.12, 0.0], radius=0.04),
            Obstacle(
                "passing", "sphere", p0 + [0.0, 0.3, 0.0], [0, 0, 0], [0, -0.2, 0], radius=0.03
            ),
        ],
        joint_limits=JointLimits(panda, override={"panda_joint4": {"upper": -2.1}}),
        obstacle_threshold=0.05,
    )
    lines = [
        Line(p0, p0 + [0.2, 0.02 * (i % 4) - 0.03, 0.05 * (i % 3) - 0.05], duration=0.1)
        for i in range(RUNS)
    ]
    return task, cset, lines


@pytest.mark.parametrize("engine", ENGINES)
def test_panda_runs_with_obstacles_and_joint_ranges_in_threads(panda_case, engine):
    task, cset, lines = panda_case
    tracker = clik.Tracker(task, law="pseudoinverse", constraints=cset, engine=engine)

    def job(i: int) -> clik.TrackingResult:
        if i % 2:  # the one-call form, a tracker of its own, on the same task and set
            return clik.track(task, lines[i], law="pseudoinverse", constraints=cset, engine=engine)
        return tracker.run(lines[i])

    serial = [job(i) for i in range(RUNS)]
    assert any(r.events for r in serial), "the constraints must act on the runs"
    assert len({r.q.tobytes() for r in serial}) == RUNS  # the runs differ from each other
    assert_same_runs(serial, in_threads(job, RUNS))


@pytest.mark.parametrize("engine", ENGINES)
def test_planar4r_runs_in_threads(planar4r, engine):
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    cset = ConstraintSet(
        planar4r, obstacles=[Obstacle("pin", "sphere", [0.7, -0.28, 0.0], radius=0.0)],
        joint_limits=JointLimits(planar4r),
    )  # fmt: skip
    laws = ("pseudoinverse", "transpose", "nonlinear")

    def job(i: int) -> clik.TrackingResult:
        line = Line(p0, [0.8, -0.2 + 0.01 * i, 0.0], duration=0.3)
        return clik.track(task, line, q0=q0, law=laws[i % 3], constraints=cset, engine=engine)

    serial = [job(i) for i in range(RUNS)]
    assert any(r.events for r in serial)
    assert_same_runs(serial, in_threads(job, RUNS))


@pytest.mark.parametrize("engine", ENGINES)
def test_solves_in_threads(panda, engine):
    task = Task(panda, "panda_hand", "pose")
    rng = np.random.default_rng(22)
    targets = [task.placement(panda.random_configuration(rng, margin=0.2)) for _ in range(RUNS)]
    for target in targets[1::2]:  # out of reach: every restart runs, the solve lasts
        target.translation += [1.0, 0.0, 0.0]

    def job(i: int) -> clik.SolveResult:
        return clik.solve(task, targets[i], engine=engine, seed=i, restarts=3)

    serial = [job(i) for i in range(RUNS)]
    assert [r.success for r in serial] == [True, False] * (RUNS // 2)
    assert_same_solves(serial, in_threads(job, RUNS))


@pytest.mark.parametrize("engine", ENGINES)
def test_constrained_solves_in_threads(planar4r, engine):
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    cset = ConstraintSet(
        planar4r, obstacles=[Obstacle("pin", "sphere", [0.7, -0.28, 0.0], radius=0.05)],
        joint_limits=JointLimits(planar4r),
    )  # fmt: skip
    targets = [[0.8 + 0.025 * (i % 4), -0.2 - 0.1 * (i // 4 + i % 2), 0.0] for i in range(RUNS)]

    def job(i: int) -> clik.SolveResult:
        return clik.solve(task, targets[i], engine=engine, constraints=cset, seed=i)

    serial = [job(i) for i in range(RUNS)]
    assert all(r.success for r in serial)
    assert any(r.reason.startswith("converged with the constraints") for r in serial)
    assert any(r.reason.startswith("converged in") for r in serial)  # clear at once
    assert_same_solves(serial, in_threads(job, RUNS))


def assert_same_solves(serial: list[clik.SolveResult], threaded: list[clik.SolveResult]):
    """The same solves, bit for bit."""
    for i, (a, b) in enumerate(zip(serial, threaded, strict=True)):
        assert np.array_equal(a.q, b.q), f"solve {i}: q differs"
        assert (a.success, a.reason, a.iterations, a.attempts) == (
            b.success, b.reason, b.iterations, b.attempts,
        ), i  # fmt: skip
