"""Joint speeds within the robot's limits at every sample, in the law (docs/method.md (S1)-(S3)).

The runs that once moved joints at 7-16x their limits: a start inside an obstacle's
threshold, a pose line into a ball (a conflict), a reference that outruns the arm. With
the speed step on (the default) every recorded joint speed is within ``scale * vmax``, in
both engines, and the engines agree.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import clik
from clik.constraints import ConstraintSet, Obstacle
from clik.errors import InputError, JointNotFound
from clik.loop.joint_speed import JointSpeed, SpeedLimitWarning
from clik.trajectory import Hold, Line, PoseTrajectory
from tests.joint_speed_runs import inside_run
from tests.limits_check import assert_within_limits

ENGINES = ("python", "compiled")


def _speeds_within(result: clik.TrackingResult, rel: float = 1e-9) -> float:
    """The largest recorded ``|qdot_i| / v_i`` against the law's bounds (asserted <= 1)."""
    bounds = np.array(result.info["joint_speed"]["velocity"])
    ratio = float((np.abs(result.qdot) / bounds).max())
    assert ratio <= 1.0 + rel, f"a joint at {ratio:.6g} x its speed bound"
    return ratio


@pytest.mark.parametrize("engine", ENGINES)
def test_start_inside_a_threshold_recovers_within_the_speed_limits(panda, engine):
    free = inside_run(panda, engine, joint_speed=None)
    assert free.summary()["max_velocity_ratio"] > 5.0  # the jump the speed step removes
    result = inside_run(panda, engine)
    summary = result.summary()
    assert summary["max_velocity_ratio"] == pytest.approx(1.0)  # at a limit, never above
    assert summary["max_velocity_ratio"] <= 1.0 + 1e-9
    assert _speeds_within(result) == pytest.approx(1.0)  # it did run at a limit
    # the row pushed the link out over several samples, then let go
    events = summary["events"]
    assert events[0] == {"t": 0.0, "constraint": "obstacle:ball:panda_link4", "action": "activate"}
    release = [e["t"] for e in events if e["action"] == "release"]
    assert release and release[0] >= 0.01, events
    assert result.min_obstacle_distance[-1] >= 0.03 - 1e-6
    assert result.status == "completed", result.reason
    assert_within_limits(result, panda)
    assert result.max_task_error < 0.005  # the hand leaves its reference by millimetres
    # the recovery is reported: which constraint, how deep, how long, within the limits
    (recovery,) = summary["recovery"]
    assert recovery["constraint"] == "obstacle:ball:panda_link4" and recovery["recovered"]
    assert recovery["depth"] == pytest.approx(0.03 - 0.0212, abs=1e-6)
    assert recovery["duration"] == pytest.approx(release[0])
    assert f"recovered in {release[0]:g} s" in result.reason
    limited = {r["joint"] for r in summary["speed_limited"]}
    assert "panda_joint1" in limited and summary["speed_limited_time"] > 0.0


def test_engines_agree_while_the_limits_act(panda):
    a, b = (inside_run(panda, engine) for engine in ENGINES)
    assert a.status == b.status
    assert a.events == b.events
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)
    np.testing.assert_allclose(a.qdot, b.qdot, atol=1e-7)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_pose_line_into_a_ball_stops_without_a_swing(panda, engine):
    """A 7-joint arm's pose line into a ball: deadlock, every joint within its limit."""
    task = clik.Task(panda, "panda_hand", "pose")
    q0 = panda.q_reference
    P = task.placement(q0)
    p0 = P.translation
    ball = Obstacle("ball", "sphere", position=p0 + [0.2, 0.0, 0.0], radius=0.05)
    cset = ConstraintSet(panda, obstacles=[ball], obstacle_threshold=0.03)
    tracker = clik.Tracker(task, law="pseudoinverse", gain=1000.0, constraints=cset,
                           engine=engine)  # fmt: skip
    line = PoseTrajectory(Line(p0, p0 + [0.4, 0.0, 0.0], duration=1.0), Hold(None, P.rotation, 1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = tracker.run(line, q0)
    assert result.status == "deadlock", result.reason
    assert "in conflict with: obstacle:ball" in result.reason, result.reason
    assert "task rows that cannot follow: " in result.reason
    assert result.summary()["max_velocity_ratio"] <= 1.0 + 1e-9
    _speeds_within(result)
    assert_within_limits(result, panda)


@pytest.mark.parametrize("law", ["transpose", "nonlinear", "pseudoinverse"])
def test_every_law_keeps_the_limits_and_the_engines_agree(planar4r, law):
    """A reference faster than the arm: the task slows down along its path, in both engines."""
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    line = Line(p0, p0 + [0.25, -0.05, 0.0], duration=0.1)
    runs = []
    for engine in ENGINES:
        tracker = clik.Tracker(task, law=law, gain=200.0, engine=engine,
                               joint_speed=JointSpeed(scale=0.5))  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs.append(tracker.run(line, q0, settle=1.0))
    a, b = runs
    for r in runs:
        assert _speeds_within(r) == pytest.approx(1.0)  # the limits acted
        assert r.summary()["max_velocity_ratio"] <= 0.5 + 1e-9
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)
    assert a.status == b.status


@pytest.mark.parametrize("engine", ENGINES)
def test_acceleration_limits(planar4r, engine):
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    p0 = task.placement(q0).translation
    line = Line(p0, p0 + [0.2, 0.0, 0.0], duration=0.5)
    speed = JointSpeed(acceleration=2.0)
    tracker = clik.Tracker(task, law="pseudoinverse", gain=200.0, engine=engine, joint_speed=speed)
    result = tracker.run(line, q0, settle=0.5)
    assert np.abs(result.qddot).max() <= 2.0 * (1 + 1e-6)
    free = clik.Tracker(task, law="pseudoinverse", gain=200.0, engine=engine).run(line, q0)
    assert np.abs(free.qddot).max() > 4.0  # the limit acted
    _speeds_within(result)


def test_within_the_limits_the_law_is_untouched(planar4r):
    """The case study's law (9) run is bit for bit the same with and without the step."""
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    line = Line(task.placement(q0).translation, [0.8, -0.2, 0.0], duration=3.0)
    a = clik.track(task, line, q0=q0)
    b = clik.track(task, line, q0=q0, joint_speed=None)
    assert a.info["joint_speed"] is not None and b.info["joint_speed"] is None
    np.testing.assert_array_equal(a.q, b.q)


def test_a_joint_without_a_limit_gets_the_default_and_a_warning(planar4r):
    import copy

    robot = copy.copy(planar4r)
    model = planar4r.model.copy()
    model.velocityLimit[1] = 0.0
    robot.model = model
    with pytest.warns(SpeedLimitWarning, match="default_velocity = 2"):
        bounds = JointSpeed().bounds(robot)
    assert bounds is not None
    assert bounds.velocity[1] == 2.0 and bounds.unlimited == [robot.model.names[2]]


def test_per_joint_velocity_and_scale(planar4r):
    name = planar4r.model.names[1]
    bounds = JointSpeed(scale=0.5, velocity={name: 1.0}).bounds(planar4r)
    assert bounds is not None
    assert bounds.velocity[0] == 0.5
    assert bounds.velocity[1] == 0.5 * planar4r.model.velocityLimit[1]
    assert JointSpeed(enabled=False).bounds(planar4r) is None


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"scale": 0.0}, "joint_speed.scale"),
        ({"scale": 11.0}, "joint_speed.scale"),
        ({"default_velocity": -1.0}, "joint_speed.default_velocity"),
        ({"velocity": {"j": float("nan")}}, "joint_speed.velocity.j"),
        ({"acceleration": 0.0}, "joint_speed.acceleration"),
        ({"enabled": 1}, "joint_speed.enabled"),
    ],
)
def test_bad_settings_name_the_field(kwargs, field):
    with pytest.raises(InputError) as info:
        JointSpeed(**kwargs)
    assert info.value.field == field


def test_an_unknown_joint_is_named(planar4r):
    with pytest.raises(JointNotFound):
        JointSpeed(velocity={"nope": 1.0}).bounds(planar4r)
    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    with pytest.raises(InputError, match="joint_speed"):
        clik.Tracker(task, joint_speed="fast")  # type: ignore[arg-type]


def test_the_engine_refuses_bad_bounds(planar4r):
    from clik._engine import LawConfig  # the boundary: checked where the run is built

    task = clik.Task(planar4r, "tip", "position", axes=["x", "y"])
    tracker = clik.Tracker(task, law="pseudoinverse")
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    line = Line(task.placement(q0).translation, [0.8, -0.2, 0.0], duration=0.1)
    for vmax in (np.ones(3), np.array([1.0, np.nan, 1.0, 1.0]), np.array([1.0, 0.0, 1.0, 1.0])):
        tracker.speed = type(tracker.speed)(  # type: ignore[misc]
            tracker.speed.names,
            vmax,
            None,
            [],
            tracker.speed.settings,  # type: ignore[union-attr]
            vmax,
            ["urdf"] * vmax.size,
        )
        with pytest.raises(ValueError, match="vmax"):
            tracker.run(line, q0)
    assert LawConfig is not None


def _scenario(tmp_path, table: str):
    from clik.scenarios import scenario_path

    text = scenario_path("case_study_unconstrained").read_text()
    path = tmp_path / "s.toml"
    path.write_text(text + "\n[constraints.joint_speed]\n" + table)
    return path


@pytest.mark.parametrize(
    ("table", "key"),
    [
        ("scale = 0\n", "constraints.joint_speed.scale"),
        ("scale = 20\n", "constraints.joint_speed.scale"),
        ("default_velocity = -1\n", "constraints.joint_speed.default_velocity"),
        ("acceleration = 0\n", "constraints.joint_speed.acceleration"),
        ('velocity = { joint1 = "fast" }\n', "constraints.joint_speed.velocity.joint1"),
        ("enabled = 1\n", "constraints.joint_speed.enabled"),
        ("speed = 1\n", "constraints.joint_speed"),
        ("velocity = { nope = 1.0 }\n", "constraints.joint_speed.velocity"),
        ("acceleration = { nope = 1.0 }\n", "constraints.joint_speed.acceleration"),
    ],
)
def test_scenario_keys_are_checked(tmp_path, table, key):
    from clik.errors import ScenarioError
    from clik.scenarios.runner import build

    with pytest.raises(ScenarioError) as info:
        build(_scenario(tmp_path, table))
    assert key in str(info.value)


def test_scenario_turns_the_limits_off_or_scales_them(tmp_path):
    from clik.scenarios.runner import build

    off = build(_scenario(tmp_path, "enabled = false\n")).execute()
    assert off.info["joint_speed"] is None
    run = build(_scenario(tmp_path, "scale = 0.5\nacceleration = { joint1 = 50.0 }\n"))
    result = run.execute()
    info = result.info["joint_speed"]
    assert info["velocity"] == [1.5, 1.5, 1.5, 1.5]
    assert info["acceleration"][0] == 50.0 and info["acceleration"][1] is None
    _speeds_within(result)
