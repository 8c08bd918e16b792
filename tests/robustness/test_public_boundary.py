"""Nothing reaches the C++ unchecked (issue 22, the public API's side).

One test per case found by probing the public API, in both engines where an engine is
involved: each asserts the error type and the field its message names, or the result
the user now gets.

Decisions recorded here:

- ``ConstraintSet.obstacles`` and the other sequences a set and its kinds show are
  read-only (:class:`~clik.constraints.read_only.ReadOnlyList`: equal to the list of the
  same items, an ``InputError`` on any change in place); their arrays are read-only too.
- Every argument of ``Tracker.run`` and ``clik.track`` is checked before the run, in
  its documented range; ``record_every`` beyond the run's sample count keeps the first
  and last samples (it is taken as that count), in both engines alike.
- ``max_active`` above the robot's ``nv`` is taken as ``nv``; solve settings are
  bounded (``clik.bounds.MAX_ITERATIONS``, ``MAX_RESTARTS``).
- A robot whose model changed after loading is refused (``robot.model``) by tasks,
  constraint sets, trackers, runs and solves: load a new robot.
- A run takes the obstacles as they are when it starts: ``set_obstacles`` and
  ``move_obstacle`` during a run (from ``progress``) apply to the next run.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik import InputError, Task
from clik.bounds import MAX_ITERATIONS, MAX_RESTARTS
from clik.constraints import ConstraintSet, JointLimits, Obstacle, Workspace
from clik.model.robot import Robot
from clik.trajectory import Line, Reference, Trajectory

ENGINES = ("compiled", "python")
Q0 = np.radians([180.0, -30.0, -90.0, -30.0])
"""The case study's start of planar4r [rad]."""


@pytest.fixture(scope="module")
def arm(planar4r):
    """planar4r's (x, y) task, a 0.1 s line from the start, and a pin near it."""
    task = Task(planar4r, "tip", "position", axes=["x", "y"])
    p0 = task.placement(Q0).translation
    line = Line(p0, p0 + [0.05, 0.0, 0.0], duration=0.1)
    return task, p0, line


def pin_set(robot: Robot, position: object = (0.7, -0.28, 0.0)) -> ConstraintSet:
    """One point obstacle (a sphere of radius 0)."""
    return ConstraintSet(robot, obstacles=[Obstacle("pin", "sphere", position, radius=0.0)])


def assert_names(info: pytest.ExceptionInfo[InputError], field: str) -> None:
    """The error is about ``field``: its attribute and the start of its message."""
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: expected ")


# -- 1. the set's sequences cannot change behind its back ---------------------------------


@pytest.mark.parametrize(
    "change",
    [
        lambda seq, item: seq.append(item),
        lambda seq, item: seq.extend([item]),
        lambda seq, item: seq.insert(0, item),
        lambda seq, item: seq.remove(seq[0]),
        lambda seq, item: seq.pop(),
        lambda seq, item: seq.clear(),
        lambda seq, item: seq.__setitem__(0, item),
        lambda seq, item: seq.__delitem__(0),
        lambda seq, item: seq.__iadd__([item]),
        lambda seq, item: seq.sort(),
    ],
    ids=[
        "append",
        "extend",
        "insert",
        "remove",
        "pop",
        "clear",
        "setitem",
        "delitem",
        "iadd",
        "sort",
    ],
)
def test_obstacles_cannot_be_changed_in_place(planar4r, arm, change):
    task, _, line = arm
    cset = pin_set(planar4r)
    before = clik.track(task, line, q0=Q0, constraints=cset)
    with pytest.raises(InputError) as info:
        change(cset.obstacles, Obstacle("pin2", "sphere", [0.7, 0.2, 0.0], radius=0.0))
    assert_names(info, "obstacles")
    assert "ConstraintSet.set_obstacles" in str(info.value)
    assert "move_obstacle" in str(info.value)
    assert [o.name for o in cset.obstacles] == ["pin"]
    for engine in ENGINES:  # the set is whole: runs as before
        again = clik.track(task, line, q0=Q0, constraints=cset, engine=engine)
        assert again.status == before.status
        np.testing.assert_allclose(again.q, before.q, atol=1e-9)


def test_the_obstacles_still_read_like_a_list(planar4r):
    ball = Obstacle("pin", "sphere", [0.7, -0.28, 0.0], radius=0.0)
    other = Obstacle("pin2", "sphere", [0.7, 0.2, 0.0], radius=0.0)
    cset = ConstraintSet(planar4r, obstacles=[ball, other])
    obstacles = cset.obstacles
    assert len(obstacles) == 2 and obstacles[0] is ball and obstacles[-1] is other
    assert list(obstacles) == [ball, other] and obstacles == [ball, other]
    assert obstacles == (ball, other) and obstacles != [ball]
    assert ball in obstacles and obstacles.index(other) == 1
    cset.set_obstacles(obstacles + [Obstacle("pin3", "sphere", [0.9, 0.0, 0.0], radius=0.0)])
    assert [o.name for o in cset.obstacles] == ["pin", "pin2", "pin3"]
    assert len(cset.scene.obstacles) == 3


def test_the_kinds_sequences_and_arrays_are_read_only(planar4r):
    limits = JointLimits(planar4r)
    box = Workspace(planar4r, "tip", [-1.0, -1.0, -0.1], [1.0, 1.0, 0.1])
    cset = ConstraintSet(
        planar4r, obstacles=[Obstacle("pin", "sphere", [0.7, -0.28, 0.0], radius=0.0)],
        joint_limits=limits, kinds=[box],
    )  # fmt: skip
    for sequence, field in (
        (cset.joint_limits.names, "JointLimits.names"),
        (cset.joint_limits.joint_names, "JointLimits.joint_names"),
        (box.keys, "Workspace.keys"),
        (cset.scene.obstacles, "scene.obstacles"),
        (cset.scene.link_labels, "scene.link_labels"),
        (cset.scene.self_pairs, "scene.self_pairs"),
    ):
        with pytest.raises(InputError) as info:
            sequence.append("x")
        assert_names(info, field)
    for array in (
        cset.obs_threshold, cset.obs_vel, cset.joint_limits.lower, cset.joint_limits.q_index,
        cset.joint_limits.threshold, box.lower, cset.scene.obstacle_pairs,
        cset.obstacles[0].position,
    ):  # fmt: skip
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 5.0
    with pytest.raises(InputError) as info:
        cset.joint_limits.gain = float("nan")
    assert_names(info, "JointLimits.gain")


def test_an_obstacle_keeps_its_own_copy_of_the_arrays_given(planar4r):
    position = np.array([0.7, -0.28, 0.0])
    ball = Obstacle("pin", "sphere", position, radius=0.0)
    position[0] = 9.0  # the caller's array stays the caller's, writable
    assert ball.position[0] == 0.7


# -- 2. run and set settings are checked before they reach the engine ---------------------

BAD_RUN_SETTINGS = [
    ("deadlock_window", float("inf")),
    ("deadlock_window", float("nan")),
    ("deadlock_window", 1e300),
    ("deadlock_window", -1.0),
    ("deadlock_window", 0.0),
    ("stall_window", float("inf")),
    ("stall_window", float("nan")),
    ("stall_window", 1e300),
    ("stall_window", -0.5),
    ("deadlock_ratio", 2.0),
    ("deadlock_ratio", float("nan")),
    ("deadlock_error", -1e-3),
    ("deadlock_error", float("inf")),
    ("max_joint_step", 0.0),
    ("max_joint_step", float("inf")),
    ("stall_progress", 1.5),
    ("stall_progress", "0.01"),
    ("settle", float("nan")),
    ("settle", -1.0),
    ("settle", 1e300),
    ("record_every", 0),
    ("record_every", 2.0),
    ("record_every", True),
    ("progress", "every second"),
]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(("field", "value"), BAD_RUN_SETTINGS)
def test_run_settings_are_checked_in_both_engines(arm, engine, field, value):
    task, _, line = arm
    tracker = clik.Tracker(task, law="pseudoinverse", engine=engine)
    with pytest.raises(InputError) as info:
        tracker.run(line, Q0, **{field: value})
    assert_names(info, field)


@pytest.mark.parametrize("field", ["record_every", "progress"])
def test_track_checks_its_run_settings_too(arm, field):
    task, _, line = arm
    with pytest.raises(InputError) as info:
        clik.track(task, line, q0=Q0, **{field: -1})
    assert_names(info, field)


def test_a_window_at_its_bound_is_accepted(arm):
    task, _, line = arm
    tracker = clik.Tracker(task, law="pseudoinverse", dt=1e-3)
    result = tracker.run(line, Q0, deadlock_window=clik.bounds.MAX_STEPS * 1e-3)
    assert result.status == "completed", result.reason


def test_a_huge_record_every_keeps_the_first_and_last_samples_in_both_engines(arm):
    task, _, line = arm
    results = {
        (engine, every): clik.track(task, line, q0=Q0, record_every=every, engine=engine)
        for engine in ENGINES
        for every in (2**63, 2**31, 101)  # the run has 101 samples
    }
    for result in results.values():
        assert result.status == "completed", result.reason
        assert result.t.tolist() == [0.0, 0.1]
        assert result.info["record_every"] == 101
    for engine in ENGINES:
        np.testing.assert_array_equal(results[engine, 2**63].q, results[engine, 101].q)
    np.testing.assert_allclose(results["compiled", 2**63].q, results["python", 2**63].q, atol=1e-12)


@pytest.mark.parametrize("engine", ENGINES)
def test_max_active_beyond_nv_is_taken_as_nv(planar4r, arm, engine):
    task, _, line = arm
    huge = ConstraintSet(planar4r, obstacles=pin_set(planar4r).obstacles, max_active=10**12)
    assert huge.max_active == planar4r.nv
    plain = pin_set(planar4r)
    result = clik.track(task, line, q0=Q0, law="pseudoinverse", constraints=huge, engine=engine)
    same = clik.track(task, line, q0=Q0, law="pseudoinverse", constraints=plain, engine=engine)
    assert result.status == same.status == "completed", result.reason
    np.testing.assert_array_equal(result.q, same.q)


@pytest.mark.parametrize("value", [-1, True, 2.5, "3"])
def test_max_active_must_be_an_integer_at_least_zero(planar4r, value):
    with pytest.raises(InputError) as info:
        ConstraintSet(planar4r, max_active=value)
    assert_names(info, "constraints.max_active")
    cset = ConstraintSet(planar4r)
    with pytest.raises(InputError) as info:
        cset.max_active = value  # a setting changed later is checked the same
    assert_names(info, "constraints.max_active")


@pytest.mark.parametrize(
    ("field", "value"),
    [("hysteresis", float("nan")), ("monitor_margin", float("inf")), ("release_rule", "never")],
)
def test_a_set_setting_changed_later_is_checked(planar4r, field, value):
    cset = ConstraintSet(planar4r)
    with pytest.raises(InputError) as info:
        setattr(cset, field, value)
    assert_names(info, "constraints.release" if field == "release_rule" else f"constraints.{field}")


def test_a_set_of_another_robot_or_type_is_refused(ur5, arm):
    task, _, _ = arm
    with pytest.raises(InputError) as info:
        clik.Tracker(task, constraints=ConstraintSet(ur5))
    assert_names(info, "constraints")
    assert "the task's robot" in str(info.value)
    with pytest.raises(InputError) as info:
        clik.Tracker(task, constraints=[Obstacle("pin", "sphere", [0.7, 0.0, 0.0], radius=0.0)])
    assert_names(info, "constraints")


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("max_iterations", 2**40, f"an integer <= {MAX_ITERATIONS}"),
        ("max_iterations", MAX_ITERATIONS + 1, f"an integer <= {MAX_ITERATIONS}"),
        ("restarts", 10**12, f"an integer <= {MAX_RESTARTS}"),
        ("max_iterations", True, "an integer >= 1"),
        ("seed", -1, "an integer >= 0 or None"),
        ("seed", 1.5, "an integer >= 0 or None"),
    ],
)
def test_solve_settings_are_bounded_in_both_engines(arm, engine, field, value, words):
    task, p0, _ = arm
    with pytest.raises(InputError) as info:
        clik.solve(task, p0, Q0, engine=engine, **{field: value})
    assert_names(info, field)
    assert words in str(info.value)


# -- 3. a model changed after loading ------------------------------------------------------


def test_a_model_changed_after_loading_is_refused_everywhere():
    robot = Robot.load("planar4r")  # its own: the model is changed below
    task = Task(robot, "tip", "position", axes=["x", "y"])
    p0 = task.placement(Q0).translation
    line = Line(p0, p0 + [0.05, 0.0, 0.0], duration=0.1)
    cset = pin_set(robot)
    trackers = {
        e: clik.Tracker(task, law="pseudoinverse", constraints=cset, engine=e) for e in ENGINES
    }
    for engine in ENGINES:  # the compiled solver is cached for this task
        assert clik.solve(task, p0, Q0, engine=engine).success
    robot.model.addJoint(4, pin.JointModelRZ(), pin.SE3.Identity(), "extra")
    calls = {
        "Task": lambda: Task(robot, "tip", "position"),
        "ConstraintSet": lambda: ConstraintSet(robot),
        "Tracker": lambda: clik.Tracker(task),
        "Task.placement": lambda: task.placement(Q0),
    }
    for engine in ENGINES:
        calls |= {
            f"solve {engine}": lambda e=engine: clik.solve(task, p0, Q0, engine=e),
            f"solve constrained {engine}": lambda e=engine: clik.solve(
                task, p0, Q0, engine=e, constraints=cset
            ),
            f"track {engine}": lambda e=engine: clik.track(task, line, q0=Q0, engine=e),
            f"Tracker.run {engine}": lambda e=engine: trackers[e].run(line, Q0),
        }
    for name, call in calls.items():
        with pytest.raises(InputError) as info:
            call()
        assert_names(info, "robot.model")
        message = str(info.value)
        assert "nq = 4, nv = 4, 4 joints" in message, name
        assert "nq = 5, nv = 5, 5 joints" in message, name
        assert "load a new Robot" in message, name


def test_a_joint_replaced_after_loading_is_refused():
    robot = Robot.load("planar4r")
    task = Task(robot, "tip", "position", axes=["x", "y"])
    p0 = task.placement(Q0).translation
    robot.model.joints[2] = pin.JointModelRX()  # the same sizes, an unplaced joint
    for call in (
        lambda: clik.track(task, Line(p0, p0 + [0.05, 0.0, 0.0], duration=0.1), q0=Q0),
        lambda: clik.solve(task, p0, Q0, engine="python"),
        lambda: ConstraintSet(robot),
    ):
        with pytest.raises(InputError) as info:
            call()
        assert_names(info, "robot.model")
        assert "joint 2 replaced: JointModelRX" in str(info.value)


# -- 5. obstacles changed during a run apply to the next run ------------------------------


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("change", ["move_obstacle", "set_obstacles"])
def test_obstacles_changed_during_a_run_apply_to_the_next_run(planar4r, arm, engine, change):
    task, p0, _ = arm
    line = Line(p0, [0.8, -0.2, 0.0], duration=0.5, cruise_speed=0.5)
    near = [0.7, -0.28, 0.0]  # the case study's pin: rows activate along this line
    unchanged = clik.track(
        task, line, q0=Q0, law="pseudoinverse", constraints=pin_set(planar4r, near),
        engine=engine,
    )  # fmt: skip
    assert unchanged.events, "the pin must act on the run"
    cset = pin_set(planar4r, near)
    far = Obstacle("far", "sphere", [5.0, 5.0, 0.0], radius=0.1)

    def progress(k: int, n: int) -> None:
        if k:  # after the first sample: mid-run
            if change == "move_obstacle":
                cset.move_obstacle("pin", [5.0, -5.0, 0.0])
            else:
                cset.set_obstacles([far])

    during = clik.track(
        task, line, q0=Q0, law="pseudoinverse", constraints=cset, engine=engine,
        progress=progress,
    )  # fmt: skip
    assert during.events == unchanged.events
    np.testing.assert_array_equal(
        during.extra["obstacle_distance"], unchanged.extra["obstacle_distance"]
    )
    np.testing.assert_array_equal(during.q, unchanged.q)
    assert [o["name"] for o in during.info["obstacles"]] == ["pin"]
    after = clik.track(task, line, q0=Q0, law="pseudoinverse", constraints=cset, engine=engine)
    assert after.events == []  # the change is there at the next run
    assert after.summary()["min_obstacle_distance"] > 1.0
    expected = "pin" if change == "move_obstacle" else "far"
    assert [o["name"] for o in after.info["obstacles"]] == [expected]


# -- 6. what a user trajectory's sample() gives is checked --------------------------------


class _Bad(Trajectory):
    """A trajectory whose ``sample`` gives what ``make(reference, t)`` returns."""

    def __init__(self, line: Line, make: object) -> None:
        self.line, self.make, self.duration = line, make, line.duration

    def sample(self, t: np.ndarray) -> Reference:
        return self.make(self.line.sample(t), t)  # type: ignore[operator,no-any-return]


def _shorter(r: Reference, t: np.ndarray) -> Reference:
    return Reference(r.t[:-5], position=r.position[:-5], linear_velocity=r.linear_velocity[:-5])


def _nan(r: Reference, t: np.ndarray) -> Reference:
    position = r.position.copy()
    position[-1, 0] = np.nan
    return Reference(r.t, position=position, linear_velocity=r.linear_velocity)


BAD_SAMPLES = [
    pytest.param(_shorter, "trajectory.sample", "a Reference of the 101 samples", id="fewer"),
    pytest.param(
        lambda r, t: Reference(r.t, position=r.position[:-5], linear_velocity=r.linear_velocity),
        "trajectory.position",
        "shape (101, 3)",
        id="position-shape",
    ),
    pytest.param(
        lambda r, t: Reference(r.t, position=r.position, linear_velocity=r.linear_velocity[:, :2]),
        "trajectory.linear_velocity",
        "shape (101, 3)",
        id="velocity-shape",
    ),
    pytest.param(
        lambda r, t: Reference(
            r.t,
            position=r.position,
            linear_velocity=r.linear_velocity,
            rotation=np.tile(np.eye(3), (len(t), 1, 1))[:, :2],
            angular_velocity=np.zeros((len(t), 3)),
        ),
        "trajectory.rotation",
        "shape (101, 3, 3)",
        id="rotation-shape",
    ),
    pytest.param(_nan, "trajectory", "finite values", id="non-finite"),
    pytest.param(
        lambda r, t: (r.position, r.linear_velocity),
        "trajectory.sample",
        "a clik.trajectory.Reference",
        id="not-a-reference",
    ),
]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(("make", "field", "words"), BAD_SAMPLES)
def test_a_trajectory_sample_is_checked_in_both_engines(arm, engine, make, field, words):
    task, _, line = arm
    with pytest.raises(InputError) as info:
        clik.track(task, _Bad(line, make), q0=Q0, engine=engine)
    assert_names(info, field)
    assert words in str(info.value)
