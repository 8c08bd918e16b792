"""Measured joints (docs/method.md, "Measured joints", (M1)-(M3)), in both engines.

A controller given the joints its robot reached (``q_measured``) runs each tick from
them: a simulated robot that lags (first order, 5 ms, plus two ticks of delay) follows
the shipped Panda circle within 2 mm with every verdict ``ok``. A measurement that
jumped further than the robot can move is refused with the ``measurement_jump``
verdict; malformed ones raise :class:`clik.InputError` naming the field. The compiled
engine gives the ticks and the record the Python engine gives.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import pinocchio as pin
import pytest

import clik
from clik.control.measured import MEASURED_JUMP, MEASUREMENT_JUMP
from clik.scenarios import scenario_path
from clik.scenarios.runner import Run, build
from tests.limits_check import assert_completed

ENGINES = ("python", "compiled")
TAU = 5e-3  # the simulated robot's time constant [s]
DELAY = 2  # its delay [ticks]
LAG_BOUND = 2e-3  # the acceptance bound on the task error [m]
LAG_GAIN = 200.0  # [1/s]: K dt = 0.2, within (M4)'s bound for this robot (0.36)


class LaggingRobot:
    """A joint-space robot whose joints follow the command with a first-order lag.

    A command reaches the servo ``delay`` ticks after it is sent; the joints then move
    as ``tau qdot_r = u - q_r``, integrated exactly over a tick:
    ``q_r <- q_r + (1 - exp(-dt / tau)) (u - q_r)``.
    """

    def __init__(self, q0: np.ndarray, dt: float, tau: float = TAU, delay: int = DELAY) -> None:
        self.q = np.array(q0, dtype=float)
        self.qdot = np.zeros_like(self.q)
        self.a = 1.0 - math.exp(-dt / tau)
        self.dt = dt
        self.pending: deque[np.ndarray] = deque([self.q.copy()] * delay)

    def command(self, q: np.ndarray) -> None:
        """Send ``q``; the servo moves one tick towards the command sent ``delay`` ago."""
        self.pending.append(np.array(q, dtype=float))
        u = self.pending.popleft()
        step = self.a * (u - self.q)
        self.q = self.q + step
        self.qdot = step / self.dt


def panda_circle() -> Run:
    return build(scenario_path("panda_circle"))


def circle_targets(run: Run, n: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The circle's first ``n`` ticks: each target a 4x4 pose, each velocity (6,)."""
    ref = run.trajectory.sample(np.arange(n) * run.tracker.dt)
    targets = [pin.SE3(ref.rotation[k], ref.position[k]).homogeneous for k in range(n)]
    velocities = [
        np.concatenate([ref.linear_velocity[k], ref.angular_velocity[k]]) for k in range(n)
    ]
    return targets, velocities


def controller(run: Run, engine: str, **more: object) -> clik.Controller:
    """The circle's controller (its law and tick) with the gain :data:`LAG_GAIN`.

    The scenario's own gain, 1000 1/s (``K dt = 1``), is (M4)'s unstable side with a
    loop of 5 ms and 2 ticks (docs/method.md, "Measured joints").
    """
    tr = run.tracker
    return clik.Controller(
        run.task, law=tr.law, gain=LAG_GAIN, dt=tr.dt, engine=engine, q0=run.q0,
        **more,  # type: ignore[arg-type]
    )  # fmt: skip


def closed_loop(
    ctl: clik.Controller, run: Run, n: int, jumps: dict[int, np.ndarray] | None = None
) -> tuple[list[clik.Tick], list[np.ndarray]]:
    """``n`` ticks on the circle with the lagging robot's joints as ``q_measured``.

    ``jumps``: at these ticks, this offset is added to the measurement (a glitch).
    Returns the ticks and the measurements given.
    """
    robot = LaggingRobot(run.q0, ctl.dt)
    targets, velocities = circle_targets(run, n)
    ticks, given = [], []
    for k in range(n):
        q_m = robot.q + (jumps or {}).get(k, 0.0)
        given.append(q_m)
        tick = ctl.step(targets[k], velocities[k], q_measured=q_m, qdot_measured=robot.qdot)
        ticks.append(tick)
        robot.command(tick.q)
    return ticks, given


@pytest.mark.parametrize("engine", ENGINES)
def test_a_lagging_robot_tracks_the_panda_circle(engine: str) -> None:
    """The acceptance test: the whole circle (3 s), a robot lagging 5 ms plus 2 ticks."""
    run = panda_circle()
    n = round(run.trajectory.duration / run.tracker.dt) + 1
    ctl = controller(run, engine, record_size=n)
    ticks, given = closed_loop(ctl, run, n)
    assert [t.verdict for t in ticks] == ["ok"] * n, next(t.reason for t in ticks if not t.ok)
    errors = np.array([t.errors["task"] for t in ticks])
    print(
        f"{engine}: max position error {errors[:, 0].max():.4g} m, "
        f"orientation {errors[:, 1].max():.4g} rad, final {errors[-1, 0]:.3g} m"
    )
    assert errors[:, 0].max() <= LAG_BOUND
    result = ctl.result()
    assert_completed(result, run.robot)  # joint ranges, speeds, tolerance, no violation
    assert result.max_task_error == pytest.approx(errors[:, 0].max(), abs=1e-15)
    # the record: the joints each tick ran from (the measured), the commanded, both
    commanded = np.array([run.q0] + [t.q for t in ticks[:-1]])
    np.testing.assert_array_equal(result.q, np.array(given))
    np.testing.assert_array_equal(result.extra["q_measured"], np.array(given))
    np.testing.assert_array_equal(result.extra["q_commanded"], commanded)
    assert np.isfinite(result.extra["qdot_measured"]).all()
    assert result.info["measurement_jumps"] == 0
    # the commanded joints within the ranges too, the robot's speeds within its limits
    lower, upper = run.robot.lower - 1e-9, run.robot.upper + 1e-9
    assert np.all((commanded >= lower) & (commanded <= upper))
    vmax = np.asarray(run.robot.model.velocityLimit)
    assert np.all(np.abs(result.extra["qdot_measured"]) <= vmax)
    # the loop is closed: the commanded joints run ahead of the lagging robot
    assert np.abs(result.extra["q_commanded"] - result.extra["q_measured"]).max() > 1e-4


def test_the_engine_gives_the_ticks_the_python_engine_gives() -> None:
    """The same lagging loop with glitches, in both engines: the same ticks and record."""
    run = panda_circle()
    jumps = {300: np.eye(run.robot.nq)[3] * 0.2, 301: np.eye(run.robot.nq)[0] * -0.5}
    ticks, results = {}, {}
    for engine in ENGINES:
        ctl = controller(run, engine, record_size=400, record_every=2)
        ticks[engine], _ = closed_loop(ctl, run, 600, jumps)
        results[engine] = ctl.result()
    for a, b in zip(ticks["compiled"], ticks["python"], strict=True):
        assert (a.k, a.t, a.verdict, a.reason) == (b.k, b.t, b.verdict, b.reason)
        assert np.abs(a.q - b.q).max() <= 1e-9 and np.abs(a.qdot - b.qdot).max() <= 1e-9
        assert np.allclose(a.errors["task"], b.errors["task"], rtol=0.0, atol=1e-9)
    verdicts = [t.verdict for t in ticks["compiled"]]
    assert verdicts[300] == verdicts[301] == MEASUREMENT_JUMP
    assert verdicts.count(MEASUREMENT_JUMP) == 2
    fast, spec = results["compiled"], results["python"]
    assert (fast.status, fast.reason) == (spec.status, spec.reason)
    assert fast.info["measurement_jumps"] == spec.info["measurement_jumps"] == 2
    for key in ("q_commanded", "q_measured", "qdot_measured"):
        assert fast.extra[key].shape == spec.extra[key].shape == (300, run.robot.nv)
        np.testing.assert_allclose(fast.extra[key], spec.extra[key], rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(fast.q, spec.q, rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_jump_is_refused_and_the_tick_runs_from_the_commanded_joints(engine: str) -> None:
    run = panda_circle()
    ctl = controller(run, engine)
    robot = LaggingRobot(run.q0, ctl.dt)
    targets, velocities = circle_targets(run, 60)
    for k in range(50):
        robot.command(ctl.step(targets[k], velocities[k], q_measured=robot.q).q)
    commanded = ctl.q
    glitch = robot.q + np.eye(run.robot.nq)[3] * 0.2  # panda_joint4, 0.2 rad in one tick
    tick = ctl.step(targets[50], velocities[50], q_measured=glitch)
    assert tick.verdict == MEASUREMENT_JUMP and not tick.ok
    assert "panda_joint4" in tick.reason and "measured_jump 3" in tick.reason
    # (M3) refused it: the law ran from the controller's own q_50
    expected = pin.integrate(run.robot.model, commanded, tick.qdot * ctl.dt)
    np.testing.assert_allclose(tick.q, expected, rtol=0.0, atol=1e-12)
    # the next good measurement is accepted (n = 2 ticks since the last accepted one)
    robot.command(tick.q)
    assert ctl.step(targets[51], velocities[51], q_measured=robot.q).verdict == "ok"
    result = ctl.result()
    assert result.status == "completed", result.reason
    assert "1 measurement(s) refused (measurement_jump" in result.reason
    assert result.info["measurement_jumps"] == 1
    assert np.isnan(result.extra["qdot_measured"]).all()  # none given


@pytest.mark.parametrize("engine", ENGINES)
def test_the_bound_grows_with_the_ticks_since_the_last_accepted_measurement(engine: str) -> None:
    """(M3): ``|q_m (-) q_a|_i <= c vmax_i dt n``, n ticks since q_a was accepted."""
    run = panda_circle()
    ctl = controller(run, engine)
    b = ctl.measured.bound
    vmax = np.asarray(run.robot.model.velocityLimit)
    np.testing.assert_allclose(b, MEASURED_JUMP * vmax * ctl.dt, rtol=1e-15)
    targets, velocities = circle_targets(run, 40)
    q0 = run.q0.copy()
    ctl.step(targets[0], velocities[0], q_measured=q0)  # accepted at tick 0
    for k in range(1, 30):  # no measurement: the controller's own joints
        ctl.step(targets[k], velocities[k])
    within = q0 + np.eye(run.robot.nq)[1] * 0.99 * b[1] * 30  # n = 30
    assert ctl.step(targets[30], velocities[30], q_measured=within).verdict == "ok"
    beyond = within + np.eye(run.robot.nq)[2] * 1.01 * b[2]  # n = 1 since tick 30
    tick = ctl.step(targets[31], velocities[31], q_measured=beyond)
    assert tick.verdict == MEASUREMENT_JUMP, tick.reason
    assert "panda_joint3" in tick.reason and "1 tick(s)" in tick.reason


@pytest.mark.parametrize("engine", ENGINES)
def test_bad_measurements_are_refused_by_name(engine: str) -> None:
    run = panda_circle()
    ctl = controller(run, engine)
    target, velocity = (x[0] for x in circle_targets(run, 1))
    q = run.q0
    bad_q = {
        "shape (6,)": q[:6],
        "shape (7, 1)": q[:, None],
        "finite numbers": np.where(np.arange(7) == 2, np.nan, q),
        "got [": np.where(np.arange(7) == 0, np.inf, q),
        "<U1 values": np.array(["a"] * 7),
        "complex": q.astype(complex),
        "'object'": object(),
    }
    for words, value in bad_q.items():
        with pytest.raises(clik.InputError, match=r"q_measured: expected") as caught:
            ctl.step(target, velocity, q_measured=value)
        assert words in str(caught.value), str(caught.value)
        assert "7 finite joint values (nq,)" in str(caught.value)
    for value in (np.zeros(6), np.full(7, np.nan), [1.0] * 8):
        with pytest.raises(clik.InputError, match=r"qdot_measured: expected") as caught:
            ctl.step(target, velocity, q_measured=q, qdot_measured=value)
        assert "7 finite joint velocities (nv,)" in str(caught.value)
    with pytest.raises(clik.InputError, match="qdot_measured: expected given with q_measured"):
        ctl.step(target, velocity, qdot_measured=np.zeros(7))
    assert ctl.k == 0  # nothing ran
    # other forms are converted once, as a target is: the same tick as float64
    ticks = []
    q32 = q.astype(np.float32).astype(float)
    strided = np.zeros(14)
    strided[::2] = q32
    for form in (q32, list(q32), q32.astype(np.float32), q32.astype(">f8"), strided[::2]):
        fresh = controller(run, engine)
        ticks.append(fresh.step(target, velocity, q_measured=form))
    assert all(np.array_equal(t.q, ticks[0].q) for t in ticks)


def test_the_engines_refuse_with_the_same_messages() -> None:
    run = panda_circle()
    target, velocity = (x[0] for x in circle_targets(run, 1))
    cases = [
        {"q_measured": run.q0[:3]},
        {"q_measured": np.full(7, np.inf)},
        {"q_measured": ["x"] * 7},
        {"q_measured": run.q0, "qdot_measured": np.ones((7, 2))},
        {"qdot_measured": np.zeros(7)},
    ]
    for case in cases:
        messages = []
        for engine in ENGINES:
            with pytest.raises(clik.InputError) as caught:
                controller(run, engine).step(target, velocity, **case)
            messages.append(str(caught.value))
        assert messages[0] == messages[1], case


@pytest.mark.parametrize("engine", ENGINES)
def test_a_floating_base_measurement_has_a_unit_quaternion(engine: str) -> None:
    """q has nq = nv + 1 entries: the quaternion is checked, normalised, and (M3) uses
    ``q_m (-) q_a`` (nv), not ``q_m - q_a``."""
    robot = clik.Robot.load("panda", base="floating", lock={"panda_finger_joint1": 0.0,
                                                          "panda_finger_joint2": 0.0})  # fmt: skip
    task = clik.Task(robot, "panda_hand", "position")
    ctl = clik.Controller(task, engine=engine, q0=robot.q_reference)
    q = robot.q_reference.copy()
    assert q.shape == (robot.nv + 1,)
    target = np.array([0.3, 0.1, 0.6])
    off = q.copy()
    off[3:7] *= 1.1
    with pytest.raises(clik.InputError, match=r"q_measured: expected a quaternion") as caught:
        ctl.step(target, q_measured=off)
    assert "q_measured[3:7]" in str(caught.value)
    near = q.copy()
    near[3:7] *= 1.0 + 1e-4  # within QUATERNION_TOLERANCE: normalised
    tick = ctl.step(target, q_measured=near)
    assert tick.verdict == "ok", tick.reason
    assert np.linalg.norm(tick.q[3:7]) == pytest.approx(1.0, abs=1e-12)
    flipped = tick.q.copy()
    flipped[3:7] *= -1.0  # the same rotation: q (-) q_a is zero, no jump
    assert ctl.step(target, q_measured=flipped).verdict == "ok"


def test_the_jump_setting_is_checked() -> None:
    run = panda_circle()
    for bad in (0.0, -1.0, math.nan, math.inf, True, "3"):
        with pytest.raises(clik.InputError, match="measured_jump: expected a finite number > 0"):
            controller(run, "python", measured_jump=bad)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_reset_starts_the_jump_check_at_its_joints(engine: str) -> None:
    """After ``reset(q)``, ``q`` is the accepted joints of tick 0 (M3)."""
    run = panda_circle()
    ctl = controller(run, engine)
    targets, velocities = circle_targets(run, 2)
    moved = run.q0 + 0.3  # 0.3 rad on every joint: within the Panda's ranges at q0
    run.robot.check_within_limits(moved, "q")
    ctl.reset(moved)
    assert ctl.step(targets[0], velocities[0], q_measured=moved).verdict == "ok"
    tick = ctl.step(targets[1], velocities[1], q_measured=run.q0)  # the old joints: a jump
    assert tick.verdict == MEASUREMENT_JUMP, tick.reason
    result = ctl.result()
    np.testing.assert_array_equal(result.extra["q_measured"], [moved, run.q0])
    np.testing.assert_array_equal(result.extra["q_commanded"][0], moved)
    np.testing.assert_array_equal(result.q[1], result.extra["q_commanded"][1])  # refused
