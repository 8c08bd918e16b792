"""Single-pose IK with constraints: every pose returned is checked with coal and the joints.

The checks here do not use clik's own collision scene: each pose is placed with
``pin.updateGeometryPlacements`` on the robot's collision model, and ``coal.distance``
measures every link geometry against the obstacle.
"""

from __future__ import annotations

import math

import coal
import numpy as np
import pinocchio as pin
import pytest

from clik import InputError, Task, solve
from clik.constraints import ConstraintSet, JointLimits, Obstacle
from clik.model.robot import Robot

N_CASES = 30
"""Random targets and obstacles (seeded)."""

DISTANCE_TOLERANCE = 1e-9
"""Accepted shortfall of a link-obstacle distance below the threshold [m]."""

JOINT_TOLERANCE = 1e-9
"""Accepted shortfall of a joint inside its threshold band or beyond a limit [rad]."""

FINGERS_AND_HAND = "panda_hand"


def coal_clearance(robot: Robot, q: np.ndarray, obstacle: Obstacle) -> tuple[float, str]:
    """Smallest coal distance [m] from the robot's collision geometries at ``q`` to ``obstacle``."""
    model, gmodel = robot.model, robot.collision_model
    data, gdata = model.createData(), pin.GeometryData(gmodel)
    pin.framesForwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, gmodel, gdata)
    placed = coal.Transform3s(obstacle.rotation, obstacle.position)
    best = (math.inf, "")
    for i, go in enumerate(gmodel.geometryObjects):
        M = gdata.oMg[i]
        d = coal.distance(
            go.geometry,
            coal.Transform3s(M.rotation, M.translation),
            obstacle.geometry,
            placed,
            coal.DistanceRequest(),
            coal.DistanceResult(),
        )
        best = min(best, (float(d), go.name))
    return best


def assert_clear(robot: Robot, cset: ConstraintSet, q: np.ndarray) -> None:
    """``q`` keeps every link at or beyond each obstacle's threshold, joints in range."""
    for o, obstacle in enumerate(cset.obstacles):
        threshold = float(cset.obs_threshold[o])
        d, link = coal_clearance(robot, q, obstacle)
        assert d >= threshold - DISTANCE_TOLERANCE, (obstacle.name, link, d, threshold)
    assert np.all(q >= robot.lower - JOINT_TOLERANCE)
    assert np.all(q <= robot.upper + JOINT_TOLERANCE)
    jl = cset.joint_limits
    if jl is not None:
        qi = q[jl.q_index]
        assert np.all(qi >= jl.lower + jl.threshold - JOINT_TOLERANCE)
        assert np.all(qi <= jl.upper - jl.threshold + JOINT_TOLERANCE)


def assert_on_target(task: Task, q: np.ndarray, target: object) -> None:
    """The task's frame is at ``target`` within the default tolerances."""
    reached = task.placement(q)
    if isinstance(target, pin.SE3):
        assert np.linalg.norm(reached.translation - target.translation) <= 1e-4
        assert np.linalg.norm(pin.log3(target.rotation @ reached.rotation.T)) <= 1e-3
    else:
        assert np.linalg.norm(reached.translation - np.asarray(target)) <= 1e-4


def random_case(
    panda: Robot, rng: np.random.Generator, k: int
) -> tuple[Task, object, ConstraintSet]:
    """A reachable target, and an obstacle near the arm that reaches it (sphere or box)."""
    kind = "pose" if k % 2 == 0 else "position"
    task = Task(panda, FINGERS_AND_HAND, kind)
    q_true = panda.random_configuration(rng)
    placement = task.placement(q_true)
    target = placement if kind == "pose" else placement.translation.copy()
    joint = int(rng.integers(3, 8))  # near the forearm, the wrist or the hand
    center = panda.data.oMi[joint].translation + rng.normal(0.0, 0.08, 3)
    threshold = float(rng.uniform(0.02, 0.05))
    if k % 4 < 2:
        obstacle = Obstacle("ball", "sphere", center, radius=float(rng.uniform(0.03, 0.08)),
                            threshold=threshold)  # fmt: skip
    else:
        obstacle = Obstacle("crate", "box", center, rng.uniform(-1, 1, 3),
                            size=rng.uniform(0.04, 0.12, 3), threshold=threshold)  # fmt: skip
    joint_limits = JointLimits(panda) if k % 3 else None
    return task, target, ConstraintSet(panda, obstacles=[obstacle], joint_limits=joint_limits)


def test_random_targets_and_obstacles_are_solved_clear_or_blocked_by_name(panda):
    rng = np.random.default_rng(14)
    outcomes = {"fast": 0, "around": 0, "blocked": 0}
    for k in range(N_CASES):
        task, target, cset = random_case(panda, rng, k)
        result = solve(task, target, constraints=cset, seed=k)
        if result.success:
            assert_clear(panda, cset, result.q)
            assert_on_target(task, result.q, target)
            around = result.reason.startswith("converged with the constraints")
            outcomes["around" if around else "fast"] += 1
            continue
        assert result.blocked, result.reason  # every target is reachable without constraints
        names = [f"obstacle {o.name!r}" for o in cset.obstacles] + ["joint range of panda_joint"]
        assert any(result.blocked_by.startswith(n) for n in names), result.blocked_by
        assert result.reason.startswith(f"{result.blocked_by} blocks: ")
        outcomes["blocked"] += 1
    # Every branch is taken: the unconstrained pose, a pose found around the obstacle, a block.
    assert all(n >= 3 for n in outcomes.values()), outcomes


def test_a_target_inside_an_obstacle_is_blocked_by_it(panda):
    task = Task(panda, FINGERS_AND_HAND, "pose")
    target = pin.SE3(pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0), np.array([0.5, 0.2, 0.3]))
    ball = Obstacle("ball", "sphere", [0.5, 0.2, 0.3], radius=0.05)
    cset = ConstraintSet(panda, obstacles=[ball])
    result = solve(task, target, constraints=cset)
    assert not result.success and result.blocked
    assert result.blocked_by == "obstacle 'ball'"
    assert result.reason.startswith("obstacle 'ball' blocks: link panda_")
    assert "< threshold 0.03 m in the unconstrained solution" in result.reason
    assert_clear(panda, cset, result.q)  # the closest pose found keeps clear of it
    assert solve(task, target).success  # without the ball the target is reached


def test_a_target_reached_only_around_an_obstacle(panda):
    """A ball where the unconstrained solution has its elbow: the arm goes around it."""
    task = Task(panda, FINGERS_AND_HAND, "pose")
    target = pin.SE3(pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0), np.array([0.5, 0.2, 0.3]))
    free = solve(task, target)
    data = panda.model.createData()
    pin.forwardKinematics(panda.model, data, free.q)
    elbow = data.oMi[panda.model.getJointId("panda_joint4")].translation
    ball = Obstacle("ball", "sphere", elbow, radius=0.05, threshold=0.03)
    cset = ConstraintSet(panda, obstacles=[ball], joint_limits=JointLimits(panda))
    assert coal_clearance(panda, free.q, ball)[0] < 0.0  # the unconstrained pose is inside
    result = solve(task, target, constraints=cset)
    assert result.success, result.reason
    assert result.reason.startswith("converged with the constraints")
    assert_clear(panda, cset, result.q)
    assert_on_target(task, result.q, target)
    again = solve(task, target, constraints=cset)  # deterministic
    np.testing.assert_array_equal(again.q, result.q)
    assert again.iterations == result.iterations


def test_a_joint_range_blocks_by_name(panda):
    task = Task(panda, FINGERS_AND_HAND, "position")
    jl = JointLimits(panda, override={"panda_joint1": {"lower": -0.1, "upper": 0.1}})
    result = solve(task, [0.0, 0.6, 0.3], constraints=ConstraintSet(panda, joint_limits=jl))
    assert not result.success and result.blocked_by == "joint range of panda_joint1"
    assert result.reason.startswith("joint range of panda_joint1 blocks: panda_joint1 = ")
    assert "beyond its lower limit -0.1 rad" in result.reason


def test_an_unreachable_target_is_not_blamed_on_the_constraints(panda):
    task = Task(panda, FINGERS_AND_HAND, "position")
    cset = ConstraintSet(panda, obstacles=[Obstacle("ball", "sphere", [0.5, 0, 0.5], radius=0.1)])
    result = solve(task, [3.0, 0.0, 0.5], constraints=cset, restarts=1, max_iterations=30)
    assert not result.success and not result.blocked and result.blocked_by is None
    assert "no convergence after 2 attempt(s)" in result.reason
    assert "no constraint was checked" in result.reason


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_clear_poses_and_constraints_none_are_unchanged(panda, engine):
    """A pose clear of the constraints is the unconstrained one; ``None`` is no constraint."""
    task = Task(panda, FINGERS_AND_HAND, "pose")
    rng = np.random.default_rng(3)
    far = ConstraintSet(panda, obstacles=[Obstacle("far", "sphere", [3.0, 3.0, 3.0], radius=0.1)])
    for seed in range(5):
        target = task.placement(panda.random_configuration(rng))
        plain = solve(task, target, seed=seed, engine=engine)
        none = solve(task, target, seed=seed, engine=engine, constraints=None)
        clear = solve(task, target, seed=seed, engine=engine, constraints=far)
        for other in (none, clear):
            np.testing.assert_array_equal(other.q, plain.q)
            assert (other.success, other.iterations, other.attempts, other.reason) == (
                plain.success, plain.iterations, plain.attempts, plain.reason,
            )  # fmt: skip
        assert plain.blocked_by is None and not plain.blocked


def test_bad_constraint_inputs(panda, planar4r):
    task = Task(panda, FINGERS_AND_HAND, "position")
    moving = Obstacle("cart", "sphere", [0.5, 0, 0.5], velocity=[0.1, 0, 0], radius=0.05)
    with pytest.raises(InputError, match=r"constraints: expected obstacles at rest .*'cart'"):
        solve(task, [0.4, 0, 0.4], constraints=ConstraintSet(panda, obstacles=[moving]))
    with pytest.raises(InputError, match="tracking_attempts: expected an integer >= 0"):
        solve(task, [0.4, 0, 0.4], constraints=ConstraintSet(panda), tracking_attempts=-1)
    with pytest.raises(InputError, match="constraints: expected a ConstraintSet built on the"):
        solve(task, [0.4, 0, 0.4], constraints=ConstraintSet(planar4r))
    with pytest.raises(InputError, match="constraints: expected a ConstraintSet or None"):
        solve(task, [0.4, 0, 0.4], constraints=[moving])  # type: ignore[arg-type]
