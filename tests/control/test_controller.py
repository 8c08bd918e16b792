"""The online controller (docs/method.md, "Online control"), in both engines.

A controller stepped tick by tick on a trajectory's samples runs what ``clik.track``
runs on it (the same per-sample code): the same joints, events and errors. A target
out of reach gives ``deadlock`` verdicts, and ``ok`` again when it comes back, the
joints within their limits throughout.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest

import clik
from benchmarks.step_lines import OBSTACLES_ONE_ACTIVE, Prefix, obstacle_set
from clik.scenarios import scenario_path
from clik.scenarios.runner import Run, build
from tests.limits_check import assert_completed, assert_within_limits

ENGINES = ("python", "compiled")
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def twin(tracker: clik.Tracker, q0: np.ndarray, **more: object) -> clik.Controller:
    """A controller with ``tracker``'s task, law, gains, constraints and speed limits."""
    return clik.Controller(
        tracker.task, law=tracker.law, gain=[float(g) for g in tracker.K_task], dt=tracker.dt,
        damping=tracker.damping, constraints=tracker.constraints, engine=tracker.engine,
        joint_speed=tracker.joint_speed, q0=q0, **more,  # type: ignore[arg-type]
    )  # fmt: skip


def stepped(
    ctl: clik.Controller, trajectory: object, t: np.ndarray, matrix: bool = False
) -> tuple[np.ndarray, list]:
    """Step ``ctl`` on the trajectory's samples at ``t``; the joints q_0 .. q_{N-1}, events.

    ``matrix``: a pose target as a 4x4 array (read as it is), else a ``pin.SE3``
    (converted to its matrix first).
    """
    ref = trajectory.sample(t)  # type: ignore[attr-defined]
    qs, events = [ctl.q], []
    for k in range(t.shape[0]):
        targets, velocity = ref.position[k], ref.linear_velocity[k]
        if ref.rotation is not None:
            targets = pin.SE3(ref.rotation[k], ref.position[k])
            targets = targets.homogeneous if matrix else targets
            velocity = np.concatenate([velocity, ref.angular_velocity[k]])
        tick = ctl.step(targets, velocity)
        assert tick.verdict == "ok", tick.reason
        assert tick.k == k and tick.t == pytest.approx(t[k], abs=1e-12)
        events += tick.events
        qs.append(tick.q)
    return np.array(qs[:-1]), events


def case_study_run_4(engine: str) -> tuple[Run, clik.Tracker, clik.TrackingResult]:
    """The case study's run 4 (obstacle and joint-range rows), built and run offline."""
    run = build(scenario_path("case_study_both"))
    run.tracker.engine = engine
    return run, run.tracker, run.tracker.run(run.trajectory, run.q0)


@pytest.mark.parametrize("engine", ENGINES)
def test_case_study_run_4_tick_by_tick_is_track(engine: str) -> None:
    run, tracker, offline = case_study_run_4(engine)
    assert_completed(offline, run.robot)
    assert len(offline.events) >= 2  # the obstacle and joint-range rows switch on and off
    ctl = twin(tracker, run.q0, record_size=offline.t.shape[0])
    q, events = stepped(ctl, run.trajectory, offline.t)
    assert np.abs(q - offline.q).max() <= 1e-12
    assert events == offline.events
    online = ctl.result()
    assert online.status == "completed", online.reason
    assert np.abs(online.q - offline.q).max() <= 1e-12
    assert online.max_task_error == pytest.approx(offline.max_task_error, abs=1e-12)
    assert np.abs(online.min_obstacle_distance - offline.min_obstacle_distance).max() <= 1e-12


@pytest.mark.parametrize(("engine", "matrix"), [(e, m) for e in ENGINES for m in (False, True)])
def test_panda_obstacle_scene_tick_by_tick_is_track(engine: str, matrix: bool) -> None:
    run = build(scenario_path("panda_circle"))
    line = Prefix(run.trajectory, 1.0)
    tracker = clik.Tracker(
        run.task, law="pseudoinverse", gain=1000.0, dt=1e-3, engine=engine,
        constraints=obstacle_set(run.robot, OBSTACLES_ONE_ACTIVE),
    )  # fmt: skip
    offline = tracker.run(line, run.q0)
    assert_completed(offline, run.robot)
    assert offline.events, "a sphere's row should switch on along the circle"
    ctl = twin(tracker, run.q0)
    q, events = stepped(ctl, line, offline.t, matrix)
    assert np.abs(q - offline.q).max() <= 1e-12
    assert events == offline.events
    online = ctl.result()
    assert online.status == "completed", online.reason
    assert_within_limits(online, run.robot)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_target_out_of_reach_and_back(engine: str) -> None:
    """Deadlock verdicts while the target is out of reach, ``ok`` again once it is back."""
    robot = clik.Robot.load(
        "panda", lock={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
    )
    task = clik.Task(robot, "panda_hand", "position")
    q0 = robot.q_reference.copy()
    home = task.placement(q0).translation.copy()
    far = home + np.array([2.0, 0.0, 0.0])  # 2 m away: beyond the arm's reach
    ctl = clik.Controller(task, gain=100.0, engine=engine, q0=q0)
    vmax = np.asarray(robot.model.velocityLimit)
    verdicts = []
    qs = []
    for k in range(3000):
        target = far if 200 <= k < 1500 else home  # two jumps of 2 m
        tick = ctl.step(target)
        verdicts.append(tick.verdict)
        qs.append(tick.q)
        assert np.all(np.isfinite(tick.q))
        assert np.all(np.abs(tick.qdot) <= vmax * (1 + 1e-9)), k  # the correction within them
    qs_a = np.array(qs)
    assert np.all(qs_a >= robot.lower - 1e-9) and np.all(qs_a <= robot.upper + 1e-9)
    assert "deadlock" in verdicts[200:1500], sorted(set(verdicts))
    first = verdicts.index("deadlock")
    assert 200 < first < 1500
    assert all(v == "ok" for v in verdicts[:200])
    assert all(v == "ok" for v in verdicts[-500:]), sorted(set(verdicts[-500:]))
    assert tick.errors["task"][0] <= 1e-6  # back on the target
    result = ctl.result()
    assert result.status == "deadlock"
    assert "deadlock at t = " in result.reason


def circle_ticks(ctl: clik.Controller, line: object, n: int) -> list:
    """``n`` ticks on the line's samples, each target a 4x4 array with its velocity."""
    ref = line.sample(np.arange(n) * ctl.dt)  # type: ignore[attr-defined]
    out = []
    for k in range(n):
        target = pin.SE3(ref.rotation[k], ref.position[k]).homogeneous
        velocity = np.concatenate([ref.linear_velocity[k], ref.angular_velocity[k]])
        out.append(ctl.step(target, velocity))
    return out


def test_the_engine_gives_the_ticks_the_python_engine_gives() -> None:
    """The engine makes the tick itself: a Tick, its own q, the same joints, events, active
    rows and errors as the specification's."""
    run = build(scenario_path("panda_circle"))
    line = Prefix(run.trajectory, 1.0)
    constraints = obstacle_set(run.robot, OBSTACLES_ONE_ACTIVE)
    ticks = {}
    for engine in ENGINES:
        ctl = clik.Controller(
            run.task, gain=1000.0, engine=engine, constraints=constraints, q0=run.q0
        )
        ticks[engine] = circle_ticks(ctl, line, 1000)
    fast, spec = ticks["compiled"], ticks["python"]
    assert type(fast[0]).__module__ == "clik._engine"  # the engine's own tick
    assert all(isinstance(t, clik.Tick) for t in fast + spec)
    assert not any(np.shares_memory(a.q, b.q) for a, b in itertools.pairwise(fast))
    assert any(t.events for t in fast) and any(t.active for t in fast)
    for a, b in zip(fast, spec, strict=True):
        assert (a.k, a.t, a.verdict, a.reason, a.ok) == (b.k, b.t, "ok", "", True)
        assert np.abs(a.q - b.q).max() <= 1e-9 and np.abs(a.qdot - b.qdot).max() <= 1e-9
        assert a.events == b.events and a.active == b.active
        assert a.errors.keys() == b.errors.keys() == {"task"}
        assert np.allclose(a.errors["task"], b.errors["task"], rtol=0.0, atol=1e-9)


def test_every_form_of_target_runs_in_the_engine() -> None:
    """A pin.SE3, a list, another dtype or layout, moved obstacles: each converted once and
    run by the engine, on the same clock, as a float64 array would be; a verdict other
    than ok gets its reason; a dropped controller is freed (no reference cycle)."""
    import gc
    import weakref

    run = build(scenario_path("panda_circle"))
    constraints = obstacle_set(run.robot, OBSTACLES_ONE_ACTIVE)
    ctl = clik.Controller(run.task, gain=1000.0, constraints=constraints, q0=run.q0)
    pose = run.task.placement(run.q0)
    a = ctl.step(pose.homogeneous)
    b = ctl.step(pose)  # pin.SE3: its matrix
    c = ctl.step(pose.homogeneous.tolist())
    name = constraints.obstacles[0].name
    d = ctl.step(pose.homogeneous, obstacles={name: [2.0, 2.0, 2.0]})
    assert [t.k for t in (a, b, c, d)] == [0, 1, 2, 3] and ctl.k == 4
    with pytest.raises(clik.errors.InputError, match="targets"):
        ctl.step(pose.homogeneous.ravel())  # 16 numbers, not a 4x4: named, nothing run
    assert ctl.k == 4
    e = ctl.step(np.asfortranarray(pose.homogeneous))  # not C-contiguous: converted
    f = ctl.step(pose.homogeneous.astype(np.float32))  # not float64: converted
    assert ctl.k == 6
    assert all(type(t).__module__ == "clik._engine" for t in (a, b, c, d, e, f))
    twin = clik.Controller(run.task, gain=1000.0, constraints=constraints, q0=run.q0)
    same = [twin.step(pose.homogeneous) for _ in range(3)]
    assert all(np.array_equal(t.q, u.q) for t, u in zip((a, b, c), same, strict=True))
    assert np.all(np.isfinite(d.q))
    far = pose.homogeneous.copy()
    far[:3, 3] += [2.0, 0.0, 0.0]
    verdicts = [ctl.step(far) for _ in range(1500)]
    stuck = [t for t in verdicts if t.verdict != "ok"]
    assert stuck and all(t.reason and not t.ok for t in stuck)
    assert stuck[0].verdict in ("deadlock", "off_track"), stuck[0].reason
    gone = weakref.ref(ctl)
    del ctl, verdicts, stuck, a, d
    gc.collect()
    assert gone() is None


@pytest.mark.parametrize("engine", ENGINES)
def test_the_record_is_a_ring_of_the_last_ticks(engine: str) -> None:
    run, tracker, offline = case_study_run_4(engine)
    ctl = twin(tracker, run.q0, record_size=500)
    stepped(ctl, run.trajectory, offline.t)
    online = ctl.result()
    assert online.q.shape == (500, run.robot.nq)
    assert np.abs(online.q - offline.q[-500:]).max() <= 1e-12
    assert np.abs(online.t - offline.t[-500:]).max() <= 1e-12
    assert online.events == offline.events  # the session's, not only the ring's
    assert np.array_equal(online.extra["active"], offline.extra["active"][-500:])
    assert np.allclose(online.joint_min, offline.joint_min, atol=1e-12)


@pytest.mark.parametrize("engine", ENGINES)
def test_bad_targets_are_refused_by_name(engine: str) -> None:
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    ctl = clik.Controller(task, engine=engine, q0=np.radians([180, -30, -90, -30]))
    for bad in (np.array([np.nan, 0.0, 0.0]), np.zeros(2), np.eye(4)[:3], np.zeros((4, 4))):
        with pytest.raises(clik.InputError, match=r"targets\['task'\]"):
            ctl.step(bad)
    with pytest.raises(clik.InputError, match=r"targets\['task'\]"):
        ctl.step([1.0, 2.0])
    with pytest.raises(clik.InputError, match=r"targets\['task'\]"):
        ctl.step([np.nan, 0.0, 0.0])
    with pytest.raises(clik.InputError, match=r"velocities\['task'\]"):
        ctl.step([0.5, 0.5, 0.0], velocity_bad := np.zeros(7))  # noqa: F841
    with pytest.raises(clik.InputError, match=r"velocities\['task'\]: expected finite"):
        ctl.step(np.array([0.5, 0.5, 0.0]), np.array([np.nan, 0.0, 0.0]))  # the velocity named
    with pytest.raises(clik.InputError, match="targets"):
        ctl.step({"hand": [0.5, 0.5, 0.0]})
    with pytest.raises(clik.InputError, match="record_size"):
        clik.Controller(task, record_size=0)
    with pytest.raises(clik.InputError, match="Controller"):
        clik.Controller(task, deadlock_windw=0.1)  # type: ignore[arg-type]
    assert ctl.k == 0  # nothing ran


@pytest.mark.parametrize("engine", ENGINES)
def test_several_tasks_tick_by_tick_are_track(engine: str) -> None:
    """A pose task and a posture at priority 2, with joint-range centring (eq. (5))."""
    robot = clik.Robot.load(
        "panda", lock={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
    )
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    hand = clik.Task(robot, "panda_hand", "pose")
    posture = clik.PostureTask(robot, ["panda_joint3"])
    start = hand.placement(q0)
    line = clik.trajectory.PoseTrajectory(
        clik.trajectory.Line(start.translation, start.translation + [0.2, 0.1, -0.1], 1.0),
        clik.trajectory.Hold(rotation=start.rotation),
    )
    held = clik.trajectory.JointPath(posture.angles(q0))
    objectives = [clik.Objective("joint_centering", gain=0.5)]
    goals = [
        clik.Goal(hand, line, name="hand"),
        clik.Goal(posture, held, name="elbow", priority=2, gain=10),
    ]
    offline = clik.track(
        tasks=goals, objectives=objectives, q0=q0, law="pseudoinverse", gain=100, engine=engine
    )
    assert_completed(offline, robot)
    ctl = clik.Controller(
        tasks=[clik.Goal(hand, name="hand"), clik.Goal(posture, name="elbow", priority=2, gain=10)],
        objectives=objectives, q0=q0, gain=100, engine=engine,
    )  # fmt: skip
    ref, joints = line.sample(offline.t), held.sample(offline.t)
    qs = [ctl.q]
    for k in range(offline.t.shape[0]):
        pose = pin.SE3(ref.rotation[k], ref.position[k])
        v = np.concatenate([ref.linear_velocity[k], ref.angular_velocity[k]])
        tick = ctl.step({"hand": pose, "elbow": joints.q[k]}, {"hand": v, "elbow": joints.qdot[k]})
        assert tick.verdict == "ok", tick.reason
        qs.append(tick.q)
    assert np.abs(np.array(qs[:-1]) - offline.q).max() <= 1e-12
    assert set(tick.errors) == {"hand", "elbow"}
    online = ctl.result()
    for name in ("hand", "elbow"):
        assert online.task_errors[name]["max"] == pytest.approx(
            offline.task_errors[name]["max"], abs=1e-12
        )


@pytest.mark.parametrize("engine", ENGINES)
def test_targets_without_velocity_track_with_a_lag(engine: str) -> None:
    """A line streamed as positions only: no false stall, the error the lag |v| / K."""
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180, -30, -90, -30])
    line = clik.trajectory.Line(task.placement(q0).translation, [0.8, -0.2, 0.0], 3.0, 0.12)
    targets = line.sample(np.arange(3001) * 1e-3).position
    ctl = clik.Controller(task, gain=100.0, engine=engine, q0=q0)
    verdicts = {ctl.step(target).verdict for target in targets}
    assert verdicts == {"ok"}
    result = ctl.result()
    assert_completed(result, robot)
    assert 0.5 * 0.12 / 100 <= result.max_task_error <= 1.5 * 0.12 / 100  # |v| / K = 1.2 mm
    for _ in range(300):  # the target held: the lag closes
        tick = ctl.step(targets[-1])
    assert tick.errors["task"][0] <= 1e-6


def test_obstacles_moved_tick_by_tick_in_both_engines() -> None:
    """A ball put beside the hand pushes it off its target; taken away, the hand returns."""
    from clik.constraints import ConstraintSet, JointLimits, Obstacle

    robot = clik.Robot.load("panda", lock=FINGERS)
    task = clik.Task(robot, "panda_hand", "position")
    q0 = robot.q_reference.copy()
    home = task.placement(q0).translation.copy()
    ball = Obstacle("ball", "sphere", home + [0.0, 1.0, 0.0], radius=0.03)  # far at first
    runs = {}
    for engine in ENGINES:
        cset = ConstraintSet(
            robot, obstacles=[ball], obstacle_threshold=0.04, joint_limits=JointLimits(robot)
        )
        ctl = clik.Controller(task, gain=100.0, engine=engine, constraints=cset, q0=q0)
        ticks = []
        for k in range(1500):
            moved = None
            if k == 200:  # 20 cm beside the hand, coming toward it at 0.1 m/s
                moved = {"ball": (home + [0.0, 0.2, 0.0], np.array([0.0, -0.1, 0.0]))}
            elif k == 900:  # taken away
                moved = {"ball": home + [0.0, 1.0, 0.0]}
            ticks.append(ctl.step(home, obstacles=moved))
        runs[engine] = (ticks, ctl.result())
        with pytest.raises(clik.InputError, match="obstacles"):
            ctl.move_obstacle("wall", [0.0, 0.0, 0.0])
    ticks, result = runs["compiled"]
    actions = [(e["action"], e["constraint"]) for e in result.events]
    assert ("activate", "obstacle:ball:panda_hand") in actions
    first = next(t.k for t in ticks if t.events)
    assert 200 < first < 900  # only once the ball was put there and came near
    assert max(t.errors["task"][0] for t in ticks[200:900]) > 1e-3  # the hand gives way
    # taken away, its rows are released at once (not held at their threshold: pulled)
    assert {(e["action"], e["t"]) for e in ticks[900].events} == {("release", 0.9)}
    assert ticks[-1].errors["task"][0] <= 1e-6 and ticks[-1].verdict == "ok"  # and returns
    assert result.violations == []  # never inside the ball
    python, compiled = runs["python"][0], runs["compiled"][0]
    assert [t.events for t in python] == [t.events for t in compiled]
    assert max(np.abs(a.q - b.q).max() for a, b in zip(python, compiled, strict=True)) <= 1e-9
