"""The compiled engine's goals, levels and objectives (issue 24), at the binding.

- ``_engine.levels_velocity`` (law (10) by levels) against its specification,
  :func:`clik.loop.levels.prioritized_levels`, on random stacks;
- the goals' configs refused with a message naming the field;
- a relative frame goal's and a CoM goal's Jacobian rows against finite differences of
  their errors; the goals' error norms recorded and kept (``goal_max``, ``goal_last``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.engine import load

E = load()

LEVELS_TOLERANCE = 1e-9
"""Largest difference of the engines' joint velocities by levels, relative to their size
(measured: 4e-11 over 3000 random stacks of at most nv rows)."""


@pytest.fixture(scope="module")
def panda():
    return clik.Robot.load("panda")


def random_stack(rng):
    """J, b, ends, C, b_c, objectives of a random stack of at most n rows (full rank)."""
    n = int(rng.integers(2, 12))
    while True:
        sizes = [int(rng.integers(1, 8)) for _ in range(int(rng.integers(1, 4)))]
        v = int(rng.integers(0, min(n, 4) + 1))
        if sum(sizes) + v <= n:
            break
    m = sum(sizes)
    ends = [int(e) for e in np.cumsum(sizes)]
    J = rng.normal(size=(m, n))
    b = rng.normal(size=m) * rng.choice([0.01, 1.0, 100.0])
    C = rng.normal(size=(v, n))
    bc = rng.normal(size=v)
    objectives = [
        (int(rng.integers(1, len(ends) + 1)), rng.normal(size=n) * rng.choice([0.1, 100.0]))
        for _ in range(int(rng.integers(0, 3)))
    ]
    return J, b, ends, C, bc, objectives


def branch_stack(rng):
    """A random stack whose rows touch only some joints, as tasks on a tree's branches do.

    Each row is zero outside a window of joints (two hands: disjoint windows; a posture
    row: one joint), a row may be zero, and a row may nearly repeat another's (a level
    near the damping band: the regularity bound inconclusive).
    """
    J, b, ends, C, bc, objectives = random_stack(rng)
    m, n = J.shape
    split = int(rng.integers(1, n))
    for i in range(m):
        kind = rng.random()
        if kind < 0.4:  # the first or the second branch
            lo, hi = (0, split) if rng.random() < 0.5 else (split, n)
        elif kind < 0.6:  # one joint
            lo = int(rng.integers(0, n))
            hi = lo + 1
        elif kind < 0.65:
            lo = hi = 0
        else:
            lo, hi = 0, n
        J[i, :lo] = 0.0
        J[i, hi:] = 0.0
    if m > 1 and rng.random() < 0.3:  # a row within 1e-3 of another's direction
        i, j = rng.choice(m, size=2, replace=False)
        J[i] = J[j] + 1e-3 * rng.normal(size=n) * (J[j] != 0.0)
    return J, b, ends, C, bc, objectives


def assert_engines_agree(levels, stack, rng):
    """The engine's joint velocity, parts and unrealised fraction against the spec's."""
    J, b, ends, C, bc, objectives = stack
    damping = float(rng.choice([0.0, 0.01]))
    budget_blocks = bool(rng.random() < 0.7)
    out = np.zeros(J.shape[1])
    parts = np.zeros((1 + len(ends), J.shape[1]))
    blocked = levels.prioritized_levels(
        J, b, ends, C, bc, out, damping, 1e-3, parts, objectives, budget_blocks
    )
    qdot, engine_parts, engine_blocked = E.levels_velocity(
        J, b, ends, C, bc, damping, 1e-3, objectives, budget_blocks
    )
    scale = max(1.0, float(np.abs(out).max()))
    np.testing.assert_allclose(qdot, out, rtol=0, atol=LEVELS_TOLERANCE * scale)
    if engine_parts.size:  # the run's by-levels path (else law (10)'s one-level path)
        np.testing.assert_allclose(engine_parts, parts, rtol=0, atol=LEVELS_TOLERANCE * scale)
    # the fraction |b_1 - J_1 qdot| / |b_1|: rounding of J_1 qdot relative to |b_1|
    demand = float(np.linalg.norm(b[: ends[0]]))
    relative = np.abs(J[: ends[0]]).sum(axis=1).max() * scale / demand if demand else 1.0
    tolerance = LEVELS_TOLERANCE * max(1.0, relative)
    assert engine_blocked == pytest.approx(blocked, abs=tolerance)


def test_levels_velocity_is_prioritized_levels():
    levels = pytest.importorskip("clik.loop.levels")
    rng = np.random.default_rng(24)
    for _ in range(500):
        assert_engines_agree(levels, random_stack(rng), rng)


def test_levels_velocity_on_branches_is_prioritized_levels():
    """Rows with zero blocks: the engine's sums over where rows may be nonzero."""
    levels = pytest.importorskip("clik.loop.levels")
    rng = np.random.default_rng(2024)
    for _ in range(800):
        assert_engines_agree(levels, branch_stack(rng), rng)


def test_levels_velocity_refuses_bad_stacks():
    J = np.eye(2, 3)
    with pytest.raises(ValueError, match="levels_velocity"):
        E.levels_velocity(J, np.zeros(2), [1, 1], np.zeros((0, 3)), np.zeros(0), 0.0, 1e-3, [])
    with pytest.raises(ValueError, match="levels_velocity"):
        E.levels_velocity(J, np.zeros(2), [2], np.zeros((0, 3)), np.zeros(0), 0.0, 1e-3,
                          [(2, np.zeros(3))])  # fmt: skip


# -- runs built at the binding ------------------------------------------------------------


def law_config(K, law="pseudoinverse", rows=None, **kw):
    K = np.asarray(K, dtype=float)
    rows = len(K) if rows is None else rows
    return E.LawConfig(
        law=law, damping=0.0, dt=1e-3, beta_max=100.0, K_task=K, rows=rows, alpha=float(K.max()),
        **kw,
    )  # fmt: skip


def record(N, nq, nv, goals=0):
    """The record's arrays at the binding, and its goal_error array (N, goals, 2) or None."""
    goal_error = np.zeros((N, goals, 2)) if goals else None
    return goal_error, E.RecordArrays(
        N=N, every=1, idx=np.zeros(N, dtype=np.intp), q=np.zeros((N, nq)),
        qdot=np.zeros((N, nv)), qddot=np.zeros((N, nv)), position=np.zeros((N, 3)),
        reference=None, error=np.zeros(N), orientation_error=None, active=None, distance=None,
        joint_min=np.zeros(nq), joint_max=np.zeros(nq), qdot_prev=np.zeros(nv),
        goal_error=goal_error,
    )  # fmt: skip


def make_run(robot, goals, law, N=1, frame="panda_hand", rows=(0, 1, 2), goal_record=None):
    model = robot.model
    t = np.arange(N) * 1e-3
    task = E.TaskConfig(frame=robot.frame_id(frame), rows=list(rows),
                        has_position=any(r < 3 for r in rows),
                        has_orientation=any(r >= 3 for r in rows))  # fmt: skip
    stop = E.StopConfig(deadlock_window=0.1, deadlock_ratio=1e-4, deadlock_error=1e-3,
                        max_joint_step=1.0, stall_window=0.5, stall_progress=0.01)  # fmt: skip
    joints = E.JointMonitorConfig(index=[], lower=np.zeros(0), upper=np.zeros(0), names=[])
    G = len(goals) if goal_record is None else goal_record
    goal_error, rec = record(N, model.nq, model.nv, G)
    run = E.TrackingRun(model=model, task=task, law=law, stop=stop, t=t, record=rec,
                        joints=joints, constraints=None, goals=goals)  # fmt: skip
    return run, goal_error


def test_goal_configs_are_refused_with_the_field(panda):
    hand, link4 = panda.frame_id("panda_hand"), panda.frame_id("panda_link4")
    cases = [
        ([E.FrameGoal(10**6, [0])], [1.0] * 4, "FrameGoal: frame"),
        ([E.FrameGoal(hand, [0, 7])], [1.0] * 5, "FrameGoal: rows"),
        ([E.FrameGoal(hand, [])], [1.0] * 3, "FrameGoal: rows"),
        ([E.FrameGoal(hand, [0], relative_to=hand)], [1.0] * 4, "FrameGoal: relative_to"),
        ([E.PostureGoal([0, 1], [0], [False, False])], [1.0] * 5, "PostureGoal"),
        ([E.PostureGoal([panda.nq - 1], [0], [True])], [1.0] * 4, "PostureGoal: idx_q"),
        ([E.ComGoal([3])], [1.0] * 4, "ComGoal: rows"),
        ([E.FrameGoal(link4, [0, 1])], [1.0] * 4, "K_task"),
    ]
    for goals, K, message in cases:
        with pytest.raises(ValueError, match=message):
            make_run(panda, goals, law_config(K))
    goals = [E.FrameGoal(link4, [0, 1, 2]), E.PostureGoal([0], [0], [False])]
    for levels in ([6], [4, 7], [3, 6, 7, 7], [2, 7]):
        with pytest.raises(ValueError, match="levels"):
            make_run(panda, goals, law_config([1.0] * 7, levels=levels))
    with pytest.raises(ValueError, match="pseudoinverse"):
        make_run(panda, goals, law_config([1.0] * 7, law="transpose", levels=[3, 7]))
    objective = E.ObjectiveConfig("posture", 1.0, 3, q_ref=np.zeros(panda.nq))
    with pytest.raises(ValueError, match="level"):
        make_run(panda, goals, law_config([1.0] * 7, levels=[6, 7], objectives=[objective]))
    with pytest.raises(ValueError, match="q_ref"):
        bad = E.ObjectiveConfig("posture", 1.0, 1, q_ref=np.zeros(panda.nq + 1))
        make_run(panda, goals, law_config([1.0] * 7, objectives=[bad]))
    with pytest.raises(ValueError, match="kind"):
        E.ObjectiveConfig("curiosity", 1.0, 1)
    with pytest.raises(ValueError, match="half_range"):
        E.ObjectiveConfig("joint_centering", 1.0, 1, idx_q=[0], idx_v=[0])
    with pytest.raises(ValueError, match="goal_error"):
        make_run(panda, goals, law_config([1.0] * 7), goal_record=3)
    make_run(panda, goals, law_config([1.0] * 7), goal_record=0)  # no goal_error: allowed


def test_advance_requires_the_goals_reference(panda):
    goals = [E.PostureGoal([0, 1], [0, 1], [False, False])]
    run, goal_error = make_run(panda, goals, law_config([1.0] * 5), N=3)
    q = panda.q_reference.copy()
    args = (np.zeros((3, 3)), None, np.zeros((3, 3)), np.zeros(3, dtype=bool), q)
    with pytest.raises(ValueError, match="goal_ref"):
        run.advance(0, 3, *args)
    with pytest.raises(ValueError, match="goal_ref"):
        run.advance(0, 3, *args, goal_ref=np.zeros((3, 3)), goal_ff=np.zeros((3, 2)))
    run.advance(0, 3, *args, goal_ref=np.zeros((3, 2)), goal_ff=np.zeros((3, 2)))
    assert run.goal_max.shape == (1, 2) and run.goal_last.shape == (1, 2)
    expected = np.linalg.norm(q[:2])  # the last sample's posture error |0 - q|
    assert goal_error[-1, 0, 0] == pytest.approx(expected, rel=1e-2)
    np.testing.assert_allclose(goal_error[-1], run.goal_last)


def relative_error(model, data, a, b, ref_p, ref_R, q):
    pin.framesForwardKinematics(model, data, q)
    bMa = data.oMf[b].actInv(data.oMf[a])
    return np.concatenate([ref_p - bMa.translation, pin.log3(ref_R @ bMa.rotation.T)])


def test_relative_goal_and_com_jacobians_are_the_errors_derivatives(panda):
    model = panda.model
    data = model.createData()
    a, b = panda.frame_id("panda_hand"), panda.frame_id("panda_link3")
    rng = np.random.default_rng(3)
    q = panda.q_reference + np.r_[rng.uniform(-0.3, 0.3, 7), np.zeros(panda.nq - 7)]
    pin.framesForwardKinematics(model, data, q)
    bMa = data.oMf[b].actInv(data.oMf[a])
    ref_p, ref_R = bMa.translation.copy(), bMa.rotation.copy()
    c = pin.centerOfMass(model, data, q).copy()
    goals = [E.FrameGoal(a, [0, 1, 2, 3, 4, 5], relative_to=b), E.ComGoal([0, 2])]
    run, _ = make_run(panda, goals, law_config([1.0] * 11))
    ref = np.concatenate([ref_p, ref_R.ravel(), c])[None]
    run.advance(0, 1, np.zeros((1, 3)), None, np.zeros((1, 3)), np.zeros(1, dtype=bool),
                q.copy(), goal_ref=ref, goal_ff=np.zeros((1, 8)))  # fmt: skip
    J, e = run.ext_J, run.ext_e
    np.testing.assert_allclose(e[3:11], 0.0, atol=1e-12)
    h = 1e-6
    for i in range(model.nv):
        dq = np.zeros(model.nv)
        dq[i] = h
        qp, qm = pin.integrate(model, q, dq), pin.integrate(model, q, -dq)
        d_rel = (relative_error(model, data, a, b, ref_p, ref_R, qp)
                 - relative_error(model, data, a, b, ref_p, ref_R, qm)) / (2 * h)  # fmt: skip
        np.testing.assert_allclose(-d_rel, J[3:9, i], atol=1e-6)
        d_com = (pin.centerOfMass(model, data, qp) - pin.centerOfMass(model, data, qm)) / (2 * h)
        np.testing.assert_allclose(d_com[[0, 2]], J[9:11, i], atol=1e-6)
    assert run.goal_last.shape == (2, 2)


def test_a_stack_converges_and_records_goal_errors(panda):
    """Hand position (primary) + link 4 position (level 1) + posture (level 2) reached."""
    model = panda.model
    N = 1500
    q0 = panda.q_reference.copy()
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    hand, link4 = panda.frame_id("panda_hand"), panda.frame_id("panda_link4")
    p_hand = data.oMf[hand].translation + np.array([0.03, -0.02, 0.02])
    p4 = data.oMf[link4].translation.copy()
    goals = [E.FrameGoal(link4, [0, 1, 2]), E.PostureGoal([6], [6], [False])]
    objective = E.ObjectiveConfig("joint_centering", 1.0, 2, idx_q=[0], idx_v=[0],
                                  center=np.zeros(1), half_range=np.ones(1))  # fmt: skip
    law = law_config([20.0] * 7, levels=[6, 7], objectives=[objective])
    run, goal_error = make_run(panda, goals, law, N=N)
    ref = np.tile(np.concatenate([p4, np.eye(3).ravel(), [q0[6] + 0.3]]), (N, 1))
    q = q0.copy()
    P_d, at_rest = np.tile(p_hand, (N, 1)), np.ones(N, dtype=bool)
    out = run.advance(
        0, N, P_d, None, np.zeros((N, 3)), at_rest, q, goal_ref=ref, goal_ff=np.zeros((N, 4))
    )
    assert out[1] == "", out
    assert run.last_error < 1e-4
    assert run.goal_last[0, 0] < 1e-4  # link 4 held where it was
    assert run.goal_last[1, 0] < 0.3  # the posture goal gives way, but moves toward its target
    assert (run.goal_max >= run.goal_last).all()
    np.testing.assert_allclose(goal_error[-1], run.goal_last)
    np.testing.assert_allclose(goal_error.max(axis=0), run.goal_max)


# -- nothing allocated per sample ---------------------------------------------------------

COUNTER = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
static void* (*real_malloc)(size_t) = 0;
static long counting = 0, count = 0;
void* malloc(size_t n) {
  if (!real_malloc) real_malloc = dlsym(RTLD_NEXT, "malloc");
  if (counting) __atomic_add_fetch(&count, 1, __ATOMIC_RELAXED);
  return real_malloc(n);
}
void count_start(void) { count = 0; counting = 1; }
long count_stop(void) { counting = 0; return count; }
"""

ALLOCATIONS = r"""
import ctypes, sys
import numpy as np
import pinocchio as pin
import clik
from clik.engine import load
from tests.loop.test_levels_engine import law_config, make_run

E = load()
lib = ctypes.CDLL(sys.argv[1])
lib.count_stop.restype = ctypes.c_long
robot = clik.Robot.load("panda")
model, q0 = robot.model, robot.q_reference.copy()
data = model.createData()
pin.framesForwardKinematics(model, data, q0)
hand, link4 = robot.frame_id("panda_hand"), robot.frame_id("panda_link4")
bMa = data.oMf[link4].actInv(data.oMf[hand])
c = pin.centerOfMass(model, data, q0)
goals = [E.FrameGoal(hand, [0, 1, 2], relative_to=link4), E.ComGoal([0, 1]),
         E.PostureGoal(list(range(7)), list(range(7)), [False] * 7)]
objectives = [E.ObjectiveConfig("manipulability", 0.1, 2),
              E.ObjectiveConfig("posture", 1.0, 1, q_ref=q0),
              E.ObjectiveConfig("joint_centering", 1.0, 2, idx_q=[0], idx_v=[0],
                                center=np.zeros(1), half_range=np.ones(1))]
ref = np.concatenate([bMa.translation, bMa.rotation.ravel(), c, q0[:7] + 0.2])
counts = []
for N in (50, 100, 200):  # the first: a warm-up (first calls allocate caches)
    vmax = np.full(model.nv, 0.3)
    law = law_config([10.0] * 15, levels=[8, 15], objectives=objectives, vmax=vmax)
    run, _ = make_run(robot, goals, law, N=N)
    q = q0.copy()
    args = (np.tile(data.oMf[hand].translation + 0.02, (N, 1)), None, np.zeros((N, 3)),
            np.ones(N, dtype=bool), q)
    lib.count_start()
    out = run.advance(0, N, *args, goal_ref=np.tile(ref, (N, 1)), goal_ff=np.zeros((N, 12)))
    counts.append(lib.count_stop())
    assert out[1] == "", out
print(counts[2] - counts[1])
"""


def test_nothing_is_allocated_per_sample(tmp_path):
    """Two levels, a relative, a CoM and a posture goal, three objectives, speed limits."""
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    if shutil.which("gcc") is None or os.environ.get("LD_PRELOAD"):
        pytest.skip("needs gcc and no other LD_PRELOAD (the sanitizer's)")
    source = tmp_path / "count.c"
    source.write_text(COUNTER)
    library = tmp_path / "libcount.so"
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", str(source), "-o", str(library), "-ldl"],
                   check=True)  # fmt: skip
    script = tmp_path / "allocations.py"
    script.write_text(ALLOCATIONS)
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "LD_PRELOAD": str(library), "PYTHONPATH": str(root)}
    done = subprocess.run([sys.executable, str(script), str(library)], env=env, cwd=root,
                          capture_output=True, text=True, check=True)  # fmt: skip
    assert int(done.stdout.split()[-1]) == 0, done.stdout
