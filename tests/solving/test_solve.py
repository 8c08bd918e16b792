"""Solve mode: reach single target poses by iterating the law to tolerance."""

from __future__ import annotations

import numpy as np
import pytest

from clik import InputError, Task, solve

N_TARGETS = 200


def test_reaches_random_reachable_panda_poses(panda):
    task = Task(panda, "panda_hand", "pose")
    rng = np.random.default_rng(2026)
    targets = [task.placement(panda.random_configuration(rng)) for _ in range(N_TARGETS)]
    results = [solve(task, target, seed=i) for i, target in enumerate(targets)]
    success = sum(r.success for r in results)
    assert success / N_TARGETS >= 0.99
    for r, target in zip(results, targets, strict=True):
        if r.success:
            reached = task.placement(r.q)
            assert np.linalg.norm(reached.translation - target.translation) <= 1e-4
            assert np.all(r.q >= panda.lower - 1e-12) and np.all(r.q <= panda.upper + 1e-12)


def test_failure_says_why(panda):
    task = Task(panda, "panda_hand", "position")
    result = solve(task, [3.0, 0.0, 0.5], restarts=1, max_iterations=30)
    assert not result.success
    assert result.status == "max_iterations"
    assert "no convergence after 2 attempt(s)" in result.reason and "best attempt" in result.reason
    assert result.position_error > 1.0


def test_position_only_target(planar4r):
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    result = solve(task, [0.5, 0.3, 0.0], q0=np.radians([10, 20, 30, 40]))
    assert result.success and result.position_error <= 1e-4


@pytest.mark.parametrize(
    ("target", "kwargs", "message"),
    [
        ([1.0, 2.0], {}, "target: expected a pin.SE3, a (4, 4) pose"),
        ([np.nan, 0.0, 0.0], {}, "target: expected finite values"),
        ([0.3, 0.0, 0.5], {"law": "nonlinear"}, "law: expected 'pseudoinverse' or 'transpose'"),
        ([0.3, 0.0, 0.5], {"tolerance": 0.0}, "tolerance: expected a positive finite number"),
        ([0.3, 0.0, 0.5], {"max_iterations": 0}, "max_iterations: expected an integer >= 1"),
    ],
)
def test_bad_solve_input(panda, target, kwargs, message):
    task = Task(panda, "panda_hand", "position")
    with pytest.raises(InputError) as info:
        solve(task, target, **kwargs)
    assert message in str(info.value)
