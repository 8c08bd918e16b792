"""Several tasks, levels and objectives: the compiled engine against the Python loop.

Random chains (as :mod:`tests.loop.test_engine_tracking` builds them) carry a stack of
1-3 tasks (the primary frame task, then a frame, relative or posture task at priority 1
or 2) and at most one objective of eq. (5); both engines must give the same status,
events, trajectories (within :data:`~tests.loop.test_engine_tracking.TOLERANCE` while
the primary task is regular) and each task's errors.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import clik
from clik.trajectory import Hold, JointPath, PoseTrajectory
from tests.loop.test_engine_tracking import (
    TOLERANCE,
    assert_same,
    chain_urdf,
    joint_st,
    pose_line,
    regular_samples,
)


def holding(task, q0):
    """The frame (or relative frame) held where it is at ``q0``."""
    M = task.placement(q0)
    return PoseTrajectory(Hold(position=M.translation), Hold(rotation=M.rotation))


def extra_goal(robot, kind, q0, priority, n):
    """An extra goal of ``kind`` on a chain of ``n`` joints, held at its value at ``q0``."""
    tip, mid = f"l{n + 1}", f"l{max(1, n // 2)}"
    if kind == "frame":
        task = clik.Task(robot, mid, "position")
        return clik.Goal(task, holding(task, q0), name="mid", priority=priority, gain=20.0)
    if kind == "relative":
        task = clik.RelativeTask(robot, tip, mid, "position")
        trajectory = Hold(position=task.placement(q0).translation)
        return clik.Goal(task, trajectory, name="relative", priority=priority, gain=20.0)
    task = clik.PostureTask(robot)
    return clik.Goal(task, JointPath(task.angles(q0)), name="posture", priority=priority, gain=5.0)


def both_stacks(goals, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tuple(clik.track(tasks=goals, engine=e, **kwargs) for e in ("python", "compiled"))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    joints=st.lists(joint_st, min_size=3, max_size=8),
    kind=st.sampled_from(["position", "pose"]),
    extras=st.lists(
        st.tuples(st.sampled_from(["frame", "relative", "posture"]), st.integers(1, 2)),
        max_size=2,
        unique_by=lambda e: e[0],
    ),
    objective=st.sampled_from([None, "joint_centering", "posture", "manipulability"]),
    law=st.sampled_from(["pseudoinverse", "pseudoinverse", "pseudoinverse", "transpose"]),
    offset=st.tuples(*[st.floats(-0.05, 0.05)] * 3),
    seed=st.integers(0, 2**16),
)
def test_random_stacks(tmp_path_factory, joints, kind, extras, objective, law, offset, seed):
    path = tmp_path_factory.mktemp("chain") / "chain.urdf"
    path.write_text(chain_urdf(joints))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = clik.Robot.load(str(path))
    n = len(joints)
    task = clik.Task(robot, f"l{n + 1}", kind)
    rng = np.random.default_rng(seed)
    q0 = np.clip(rng.uniform(-1.0, 1.0, robot.nq), robot.lower + 0.05, robot.upper - 0.05)
    goals = [clik.Goal(task, pose_line(task, q0, offset, 0.15), name="tip")]
    if law != "pseudoinverse":  # laws (9) and (8): one level, no objective
        extras = [(k, 1) for k, _ in extras]
        objective = None
    goals += [extra_goal(robot, k, q0, p, n) for k, p in extras]
    objectives = [] if objective is None else [clik.Objective(objective, gain=0.5)]
    try:
        a, b = both_stacks(goals, q0=q0, law=law, gain=50.0, objectives=objectives)
    except clik.InputError:  # a stack the Python side refuses
        return
    assert_same(a, b, task)
    if regular_samples(task, a) == len(a.q) and a.status != "deadlock":
        for name, errors in a.task_errors.items():
            for key, value in errors.items():
                if isinstance(value, float):
                    other = b.task_errors[name][key]
                    assert other == pytest.approx(value, abs=1e3 * TOLERANCE), (name, key)
