"""Boundary fuzz: hypothesis drives the engine's own functions with wrong shapes, dtypes,
strides, empty and huge arrays, NaN and inf; and the public API with adversarial but
well-typed values.

The engine must answer each call with a result or a clear Python exception (``TypeError``
or ``ValueError``), never a crash, a hang or a write past an array (under ``make
sanitize`` any such write is a report, and the target fails). The public API must give
the same answer in both engines: the same ``InputError`` (same field) or the same status.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import clik
from clik.engine import load
from clik.errors import InputError
from clik.trajectory import Line

E = load()

CLEAR = (TypeError, ValueError)
"""What the engine may raise at its boundary (nanobind: a refused argument; a check)."""

FUZZ = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)

N = 20
"""Samples of the fuzzed runs."""

DTYPES = [np.float64, np.float32, np.int64, np.int16, np.bool_, np.complex128]
FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)


def arrays(shapes: list[tuple[int, ...]]) -> st.SearchStrategy[Any]:
    """Arrays of any listed shape (empty, huge, wrong) and dtype, maybe strided or
    Fortran-ordered; or None, or something that is not an array."""
    base = st.builds(
        lambda dtype, shape, order: np.zeros(shape, dtype=dtype, order=order),
        st.sampled_from(DTYPES),
        st.sampled_from(shapes),
        st.sampled_from(["C", "F"]),
    )
    filled = hnp.arrays(np.float64, st.sampled_from(shapes), elements=FLOATS)
    strided = filled.map(lambda a: np.repeat(a, 2, axis=0)[::2] if a.ndim and a.size else a)
    return st.one_of(base, filled, strided, st.none(), st.just([1.0, 2.0]), st.just("q"))


def _planar_run() -> Any:
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    n, nq = N, robot.nq
    record = E.RecordArrays(
        N=n, every=1, idx=np.zeros(n, dtype=np.intp), q=np.zeros((n, nq)),
        qdot=np.zeros((n, nq)), qddot=np.zeros((n, nq)), position=np.zeros((n, 3)),
        reference=np.zeros((n, 3)), error=np.zeros(n), orientation_error=None, active=None,
        distance=None, joint_min=np.zeros(nq), joint_max=np.zeros(nq), qdot_prev=np.zeros(nq),
    )  # fmt: skip
    return E.TrackingRun(
        model=robot.model,
        task=E.TaskConfig(frame=task.frame_id, rows=[0, 1], has_position=True,
                          has_orientation=False),
        law=E.LawConfig(law="transpose", damping=0.0, dt=1e-3, beta_max=2000.0,
                        K_task=np.full(2, 1000.0), rows=2, alpha=1000.0),
        stop=E.StopConfig(deadlock_window=0.1, deadlock_ratio=1e-4, deadlock_error=1e-3,
                          max_joint_step=1.0, stall_window=0.5, stall_progress=0.01),
        t=np.arange(n) * 1e-3, record=record,
        joints=E.JointMonitorConfig(index=[], lower=np.zeros(0), upper=np.zeros(0), names=[]),
        constraints=None,
    )  # fmt: skip


@FUZZ
@given(
    c0=st.sampled_from([0, 0, 0, -1, 5, N, 2**40]),
    c1=st.sampled_from([N, N, 0, 1, N + 1, -3, 2**40]),
    P_d=arrays([(N, 3), (N, 2), (3,), (0, 3), (10**5, 3), (N, 3, 1)]),
    R_d=arrays([(N, 3, 3), (N, 9), (0,), (N, 3, 3, 1)]),
    FF=arrays([(N, 2), (N, 3), (2 * N,), (0,), (10**5, 2)]),
    at_rest=arrays([(N,), (1,), (0,), (N, 2)]),
    q=arrays([(4,), (3,), (5,), (0,), (4, 1)]),
)
def test_advance_answers_any_chunk_clearly(c0, c1, P_d, R_d, FF, at_rest, q):
    run = _planar_run()
    try:
        out = run.advance(c0, c1, P_d, R_d, FF, at_rest, q)
    except CLEAR:
        assert run.steps == 0
        return
    assert 0 <= out[0] <= N and run.steps == out[0]
    assert run.kept <= N


@FUZZ
@given(
    rows=st.integers(0, 8),
    nv=st.integers(0, 8),
    sizes=st.tuples(st.integers(0, 9), st.integers(0, 9), st.integers(0, 9)),
    m=st.integers(-2, 10),
    law=st.sampled_from(["transpose", "pseudoinverse", "nonlinear", "other"]),
    numbers=st.tuples(FLOATS, FLOATS, FLOATS),
    fill=FLOATS,
)
def test_law_velocity_answers_any_sizes_clearly(rows, nv, sizes, m, law, numbers, fill):
    J = np.full((rows, nv), fill)
    e, K, ff = (np.full(s, fill) for s in sizes)
    damping, dt, beta_max = numbers
    try:
        qdot, _blocked = E.law_velocity(law, J, e, K, ff, m, damping, dt, beta_max)
    except CLEAR:
        return
    assert qdot.shape == (nv,)


@FUZZ
@given(
    position=arrays([(3,), (2,), (0,), (3, 1)]),
    rotation=arrays([(3, 3), (9,), (2, 2), (0,)]),
    q0=arrays([(4,), (3,), (0,), (10**5,)]),
    q=arrays([(4,), (3,), (0,), (4, 1)]),
)
def test_solver_answers_any_target_clearly(position, rotation, q0, q):
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    solver = E.Solver(
        robot.model, task.frame_id, [0, 1], robot.q_reference, law="pseudoinverse", step=1.0,
        damping=1e-6, mu=1e-2, tolerance=1e-4, orientation_tolerance=1e-3, max_iterations=20,
    )  # fmt: skip
    try:
        out = solver.start(position, rotation, q0, q)
    except CLEAR:
        return
    assert out is None or isinstance(out[0], bool)


# ---------------------------------------------------------------- the public API


def _outcome(engine: str, task: clik.Task, line: Line, tracker: dict, run: dict) -> tuple:
    """("error", type, field) or ("result", status, steps) of one run in ``engine``."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = clik.Tracker(task, engine=engine, **tracker).run(line, **run)
    except InputError as error:
        return ("error", type(error).__name__, error.field)
    return ("result", result.status, result.steps)


HOSTILE = st.sampled_from([0.0, -1.0, 1e-300, 1e300, np.inf, -np.inf, np.nan, 1e-9, 0.5])


@settings(max_examples=40, deadline=None)
@given(
    gain=st.sampled_from([1000.0, 0.0, -5.0, np.inf, np.nan, 1e300]),
    dt=st.sampled_from([1e-3, 0.0, -1e-3, np.inf, np.nan, 1e-300, 0.5]),
    window=HOSTILE,
    stall=HOSTILE,
    step=HOSTILE,
    every=st.sampled_from([1, 0, -1, 7, 2**31, 2**63, 2**80]),
)
def test_both_engines_answer_hostile_settings_alike(planar4r, gain, dt, window, stall, step,
                                                    every):  # fmt: skip
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    start = task.placement(q0).translation
    line = Line(start, start + [0.02, 0.0, 0.0], 0.05)
    tracker = {"gain": gain, "dt": dt, "law": "transpose"}
    run = {"q0": q0, "deadlock_window": window, "stall_window": stall, "max_joint_step": step,
           "record_every": every}  # fmt: skip
    python = _outcome("python", task, line, tracker, run)
    compiled = _outcome("compiled", task, line, tracker, run)
    assert python == compiled


@pytest.mark.parametrize("max_active", [0, 1, 7, 10**12, -1, 2**70])
def test_both_engines_answer_any_max_active_alike(panda, max_active):
    from clik.constraints import ConstraintSet, Obstacle

    task = clik.Task(panda, "panda_hand", "position")
    start = task.placement(panda.q_reference).translation
    line = Line(start, start + [0.05, 0.0, 0.0], 0.05)
    ball = Obstacle("ball", "sphere", start + [0.0, 0.15, 0.0], radius=0.05)
    outcomes = []
    for engine in ("python", "compiled"):
        try:
            cset = ConstraintSet(panda, obstacles=[ball], max_active=max_active)
            result = clik.track(task, line, constraints=cset, engine=engine)
            outcomes.append(("result", result.status, result.steps))
        except InputError as error:
            outcomes.append(("error", error.field))
    assert outcomes[0] == outcomes[1]
