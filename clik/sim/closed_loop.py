"""A controller driving MuJoCo at its tick rate, the simulator's joints fed back.

Each tick: the simulated joints go in as ``q_measured`` (docs/method.md, "Measured
joints"), the controller steps on the scenario's reference at this tick, its joints and
velocities go to the servos of eq. (P1) (:mod:`clik.sim.servo`), and MuJoCo steps one
``dt``. The loop a real arm closes, with MuJoCo as the arm: docs/guides/simulate.md,
notebook 09. Run it as ``python -m clik.sim.closed_loop SCENARIO`` (a file, or a shipped
scenario's name).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from clik.control.from_scenario import controller_of, held_target
from clik.errors import InputError
from clik.sim.mujoco_model import robot_spec
from clik.sim.replay import compiled_scene, mujoco_module
from clik.sim.servo import KP, KV, add_servos, servo_control
from clik.sim.tasks import TaskPoint
from clik.tasks.goal import Goal
from clik.tasks.task import Task


@dataclass
class ClosedLoop:
    """What a closed loop reached.

    Attributes:
        t: Tick times (N,) [s].
        errors: Each frame task's distance from its reference on the simulated joints,
            after each tick's step (N,) [m].
        verdicts: Each tick's verdict (N).
        q_sim: The simulated joints at each tick (N, n) [rad or m].
        feedforward: Whether the servos took the controller's joint velocities.
    """

    t: np.ndarray
    errors: dict[str, np.ndarray]
    verdicts: list[str]
    q_sim: np.ndarray
    feedforward: bool

    def summary(self) -> dict[str, Any]:
        """Per task ``max`` and ``median`` [m], and the verdicts seen with their counts."""
        counts = {v: self.verdicts.count(v) for v in sorted(set(self.verdicts))}
        return {
            "position_error_m": {
                n: {"max": float(e.max()), "median": float(np.median(e))}
                for n, e in self.errors.items()
            },
            "verdicts": counts,
            "feedforward": self.feedforward,
        }


def _reference(goal: Goal, t: np.ndarray, q0: np.ndarray) -> tuple[list[Any], list[Any]]:
    """A goal's targets and feed-forward velocities at each tick, in its kind's form."""
    task, trajectory = goal.task, goal.trajectory
    if trajectory is None or not isinstance(task, Task):
        held = held_target(task, q0)
        return [held] * len(t), [None] * len(t)
    ref = trajectory.sample(t)
    if task.has_position and task.has_orientation:
        assert ref.position is not None and ref.rotation is not None
        targets = []
        for p, r in zip(ref.position, ref.rotation, strict=True):
            pose = np.eye(4)
            pose[:3, :3], pose[:3, 3] = r, p
            targets.append(pose)
        lin, ang = ref.linear_velocity, ref.angular_velocity
        assert lin is not None and ang is not None
        return targets, list(np.hstack([lin, ang]))
    if task.has_position:
        assert ref.position is not None and ref.linear_velocity is not None
        return list(ref.position), list(ref.linear_velocity)
    assert ref.rotation is not None and ref.angular_velocity is not None
    return list(ref.rotation), list(ref.angular_velocity)


def drive(
    run: Any, *, feedforward: bool = True, kp: float = KP, kv: float = KV,
    duration: float | None = None,
) -> ClosedLoop:  # fmt: skip
    """Drive MuJoCo with the scenario's controller, the simulated joints as ``q_measured``.

    Args:
        run: The scenario (:func:`clik.scenarios.runner.build`).
        feedforward: Feed the controller's joint velocities to the servos (eq. (P1)).
        kp: Servo stiffness [N m / rad or N / m].
        kv: Servo damping [N m s / rad or N s / m].
        duration: Length [s]; default the scenario's trajectory.

    Raises:
        InputError: A robot MuJoCo cannot drive (see :func:`clik.sim.replay.simulate`),
            or a bad duration.
    """
    mujoco = mujoco_module()
    ctl = controller_of(run)
    dt = ctl.dt
    length = float(run.trajectory.duration) if duration is None else duration
    if not (np.isfinite(length) and length > 0):
        raise InputError("duration", "a positive number of seconds", duration)
    mj = robot_spec(mujoco, run.robot)
    effort = np.asarray(run.robot.model.effortLimit)[mj.joints.idx_v]
    add_servos(mujoco, mj.spec, mj.joints.names, kp, kv, effort)
    constraints = run.tracker.constraints
    scene = compiled_scene(mujoco, mj, list(constraints.obstacles) if constraints else [], dt)
    model, data = scene.model, scene.data
    goals = run.goals or [Goal(run.task, run.trajectory, name="task")]
    t = np.arange(round(length / dt) + 1) * dt
    refs = {name: _reference(g, t, run.q0) for name, g in zip(ctl.names, goals, strict=True)}
    points = {
        name: TaskPoint(name, g.task.frame_id, g.task.rows[g.task.rows < 3], np.empty((0, 3)))
        for name, g in zip(ctl.names, goals, strict=True)
        if isinstance(g.task, Task) and g.task.has_position
    }
    data.qpos[scene.qadr] = mj.joints.angles(run.q0)[0]
    mujoco.mj_forward(model, data)
    reached = np.empty((len(t), len(mj.joints.names)))
    verdicts = []
    single = len(ctl.names) == 1
    for k in range(len(t)):
        measured = mj.joints.configuration(ctl.q, data.qpos[scene.qadr])
        targets = {n: r[0][k] for n, r in refs.items()}
        speeds = {n: r[1][k] for n, r in refs.items() if r[1][k] is not None}
        name = ctl.names[0]
        tick = ctl.step(
            targets[name] if single else targets,
            speeds.get(name) if single else speeds,
            q_measured=measured,
        )  # fmt: skip
        verdicts.append(tick.verdict)
        angles = mj.joints.angles(tick.q)[0]
        rates = np.asarray(tick.qdot)[mj.joints.idx_v]
        data.ctrl[:] = servo_control(angles, rates, kp, kv, feedforward)
        mujoco.mj_step(model, data)
        reached[k] = data.qpos[scene.qadr]
    q_sim = np.array([mj.joints.configuration(run.q0, r) for r in reached])
    errors = {}
    for name, point in points.items():
        shifted = np.vstack([refs_position(refs[name][0][1:]), refs_position(refs[name][0][-1:])])
        point.reference = shifted  # the reference at t_{k+1}, where step k lands
        errors[name] = point.errors(run.robot, q_sim)
    return ClosedLoop(t, errors, verdicts, reached, feedforward)


def refs_position(targets: list[Any]) -> np.ndarray:
    """Positions (N, 3) [m] of targets in a frame task's forms (4x4 pose or (3,))."""
    return np.array([np.asarray(x)[:3, 3] if np.ndim(x) == 2 else x for x in targets])


def main(argv: list[str] | None = None) -> int:
    """``python -m clik.sim.closed_loop SCENARIO``: prints the closed loop's summary."""
    from clik.scenarios import scenario_path
    from clik.scenarios.runner import build

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m clik.sim.closed_loop SCENARIO (a file or a shipped name)")
        return 2
    run = build(scenario_path(args[0]) if not Path(args[0]).is_file() else args[0])
    for feedforward in (True, False):
        s = drive(run, feedforward=feedforward).summary()
        feed = "with" if feedforward else "without"
        for name, e in s["position_error_m"].items():
            print(
                f"{feed} feed-forward: task {name} {1e3 * e['median']:.3g} mm median, "
                f"{1e3 * e['max']:.3g} mm max; verdicts {s['verdicts']}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
