"""Several tasks per tick: the dual-arm and the humanoid scenes of the whole-body lines.

``dual_arm``: Baxter (15 joints, grippers locked), a 6-D pose task on each hand along a
shared line (a box carried 10 cm), a posture task one level below (gain 10 1/s) and
joint-range rows. ``humanoid``: Talos on a floating base (38 velocities), both soles
held (6-D each), the centre of mass held in x and y, the right hand on a circle (its
orientation held) at level 1, a posture task at level 2, joint-range rows. Law (10),
gain 100 1/s, 1 ms ticks (docs/method.md, "Several tasks").

A scene holds its goals with their trajectories (the offline run, ``step_us.humanoid``)
and the same references sampled at every tick as a user's loop holds them: one mapping
of float64 arrays per tick, ``{name: target}`` and ``{name: velocity}``
(``Controller.step``'s fast path). Its :meth:`WholeBody.quality` checks any tool's
joints by Pinocchio's forward kinematics against the references.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from benchmarks.config import DT
from benchmarks.step_dual_arm import POSTURE_GAIN, dual_arm
from benchmarks.step_variant import RunOutcome, Variant
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.joint_limits import JointLimits
from clik.trajectory import Circle, Hold, JointPath, Line, PoseTrajectory, time_grid

GAIN = 100.0
"""Gain of the level-1 tasks [1/s]."""
DURATION = 2.0
"""Length of both scenes [s] (2,001 ticks)."""
TALOS_SOLES = ("left_sole_link", "right_sole_link")
TALOS_HAND = "gripper_right_base_link"
HAND_RADIUS = 0.05
"""Radius of the hand's circle [m] (10 cm across), in the robot's y-z plane."""
GRIPPERS_OPEN = -0.1
"""Talos' gripper joints at the start [rad] (their upper limit 0 is their reference)."""


@dataclass(frozen=True)
class WholeBody:
    """One scene: the robot, its goals and the references of every tick.

    Attributes:
        name: ``dual_arm`` or ``humanoid``.
        robot: The robot.
        q0: Start joints.
        goals: The goals with their trajectories (offline).
        t: Tick times (n,) [s].
        targets: Per tick, each task's target (a 4x4 pose, a position (3,), joint values).
        velocities: Per tick, each task's velocity (6,), (3,) or per joint.
        poses: Each 6-D task's desired pose at every tick (n, 4, 4), by name.
        com: The centre of mass's desired position at every tick (n, 3), or None.
        text: One sentence for ``bench.md``.
    """

    name: str
    robot: clik.Robot
    q0: np.ndarray
    goals: list[clik.Goal]
    t: np.ndarray
    targets: list[dict[str, np.ndarray]]
    velocities: list[dict[str, np.ndarray]]
    poses: dict[str, np.ndarray]
    com: np.ndarray | None
    text: str

    @property
    def ticks(self) -> int:
        """Ticks of a run (one per sample)."""
        return int(self.t.shape[0])

    def frame(self, name: str) -> str:
        """The frame of the pose task ``name``."""
        goal = next(g for g in self.goals if g.name == name)
        return str(goal.task.frame)  # type: ignore[attr-defined]

    def constraints(self) -> ConstraintSet:
        """Joint-range rows on every joint with limits (their defaults)."""
        return ConstraintSet(self.robot, joint_limits=JointLimits(self.robot))

    def controller(self, engine: str = "compiled") -> clik.Controller:
        """A controller of the scene: its goals without trajectories, its constraints."""
        goals = [
            clik.Goal(g.task, name=g.name, priority=g.priority, gain=g.gain) for g in self.goals
        ]
        return clik.Controller(
            tasks=goals, law="pseudoinverse", gain=GAIN, dt=DT, constraints=self.constraints(),
            engine=engine, q0=self.q0,
        )  # fmt: skip

    def tracker(self, engine: str = "compiled") -> clik.Tracker:
        """The offline tracker of the same goals and constraints."""
        return clik.Tracker(
            tasks=self.goals, law="pseudoinverse", gain=GAIN, dt=DT,
            constraints=self.constraints(), engine=engine,
        )  # fmt: skip

    def quality(self, joints: np.ndarray, lead: int = 0) -> dict[str, Any]:
        """Each task's largest error over a run's joints, by Pinocchio's forward kinematics.

        Args:
            joints: ``q_k`` at every tick time (m, nq), ``q_0`` first.
            lead: 0 when row k is compared with the reference at ``t_k``.

        Returns:
            ``max_position_error_m`` and ``max_orientation_error_rad`` over the 6-D tasks,
            ``max_error_m.<name>`` (each 6-D task's largest position error [m]),
            ``max_joint_range_excess`` (rad past a limit, 0 within), ``velocity_ratio``
            (largest joint speed over its limit), and with a centre of mass task
            ``com_error_m`` (x, y) [m].
        """
        model = self.robot.model
        data = model.createData()
        n = min(len(joints), self.ticks + lead)
        errors = {name: 0.0 for name in self.poses}
        rotation, com = 0.0, 0.0
        ids = {name: model.getFrameId(self.frame(name)) for name in self.poses}
        for k in range(lead, n):
            q = joints[k]
            pin.framesForwardKinematics(model, data, q)
            for name, poses in self.poses.items():
                placement = data.oMf[ids[name]]
                want = poses[k - lead]
                errors[name] = max(
                    errors[name], float(np.linalg.norm(placement.translation - want[:3, 3]))
                )
                gap = pin.log3(want[:3, :3] @ placement.rotation.T)
                rotation = max(rotation, float(np.linalg.norm(gap)))
            if self.com is not None:
                c = pin.centerOfMass(model, data, q)
                com = max(com, float(np.linalg.norm(c[:2] - self.com[k - lead][:2])))
        q = np.asarray(joints[:n])
        lower, upper = model.lowerPositionLimit, model.upperPositionLimit
        limited = np.isfinite(lower) & np.isfinite(upper) & (upper - lower < 1e10)
        excess = np.maximum(q[:, limited] - upper[limited], lower[limited] - q[:, limited])
        speeds = np.array([pin.difference(model, a, b) for a, b in itertools.pairwise(q)]) / DT
        vmax = np.asarray(model.velocityLimit)
        ratio = (
            float(np.max(np.abs(speeds) / np.where(vmax > 0, vmax, np.inf))) if len(speeds) else 0.0
        )
        out: dict[str, float] = {
            "max_position_error_m": max(errors.values()),
            "max_orientation_error_rad": rotation,
            **{f"max_error_m.{name}": error for name, error in errors.items()},
            "max_joint_range_excess": max(0.0, float(excess.max())) if excess.size else 0.0,
            "velocity_ratio": ratio,
        }
        if self.com is not None:
            out["com_error_m"] = com
        return out


def _samples(goal: clik.Goal, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A goal's targets and velocities at every tick, in its kind's tick forms."""
    ref: Any = goal.trajectory.sample(t)
    if hasattr(ref, "q"):  # a joint path: the posture's values and speeds
        return np.ascontiguousarray(ref.q), np.ascontiguousarray(ref.qdot)
    if ref.rotation is None:
        return np.ascontiguousarray(ref.position), np.ascontiguousarray(ref.linear_velocity)
    n = t.shape[0]
    poses = np.zeros((n, 4, 4))
    poses[:, :3, :3], poses[:, :3, 3], poses[:, 3, 3] = ref.rotation, ref.position, 1.0
    w = np.zeros((n, 3)) if ref.angular_velocity is None else ref.angular_velocity
    return poses, np.ascontiguousarray(np.hstack([ref.linear_velocity, w]))


def _scene(
    name: str, robot: clik.Robot, q0: np.ndarray, goals: list[clik.Goal], text: str
) -> WholeBody:
    t = time_grid(DURATION, DT)
    sampled = {str(g.name): _samples(g, t) for g in goals}
    targets = [{g: np.array(s[0][k]) for g, s in sampled.items()} for k in range(len(t))]
    velocities = [{g: np.array(s[1][k]) for g, s in sampled.items()} for k in range(len(t))]
    poses = {g: s[0] for g, s in sampled.items() if s[0].ndim == 3}
    com = next((s[0] for g, s in sampled.items() if g == "com"), None)
    return WholeBody(name, robot, q0, goals, t, targets, velocities, poses, com, text)


def _held(task: clik.Task, q0: np.ndarray) -> PoseTrajectory:
    """The task's frame held where it is at ``q0``."""
    start = task.placement(q0)
    return PoseTrajectory(
        Line(start.translation, start.translation, DURATION), Hold(rotation=start.rotation)
    )


def _joint(robot: clik.Robot, q: np.ndarray, name: str, value: float) -> None:
    q[robot.model.joints[robot.joint_id(name)].idx_q] = value


def dual_arm_scene() -> WholeBody:
    """Baxter carrying a box along a 10 cm line: two hands, a posture, joint ranges.

    The ``dual_arm`` step line's problem (:func:`benchmarks.step_dual_arm.dual_arm`).
    """
    problem = dual_arm(DURATION)
    robot, q0 = problem.robot, problem.q0
    goals = [
        clik.Goal(hand, line, name=side)
        for side, hand, line in zip(("left", "right"), problem.hands, problem.lines, strict=True)
    ]
    posture = problem.posture
    goals.append(clik.Goal(posture, JointPath(posture.angles(q0)), name="posture", priority=2,
                           gain=POSTURE_GAIN))  # fmt: skip
    text = (
        f"Baxter ({robot.nv} joints): two 6-D hands on a 10 cm line (level 1), posture "
        f"(level 2, gain {POSTURE_GAIN:g} 1/s), joint-range rows, law (10)"
    )
    return _scene("dual_arm", robot, q0, goals, text)


def humanoid_scene() -> WholeBody:
    """Talos on a floating base: soles held, CoM x, y held, right hand on a circle."""
    robot = clik.Robot.load("talos", base="floating")
    q0 = robot.q_reference.copy()
    for gripper in ("gripper_left_joint", "gripper_right_joint"):
        _joint(robot, q0, gripper, GRIPPERS_OPEN)
    goals = []
    for side, sole in zip(("left_foot", "right_foot"), TALOS_SOLES, strict=True):
        foot = clik.Task(robot, sole, "pose")
        goals.append(clik.Goal(foot, _held(foot, q0), name=side))
    com = clik.ComTask(robot, axes=["x", "y"])
    c0 = np.asarray(pin.centerOfMass(robot.model, robot.model.createData(), q0))
    goals.append(clik.Goal(com, Line(c0, c0, DURATION), name="com"))
    hand = clik.Task(robot, TALOS_HAND, "pose")
    start = hand.placement(q0)
    circle = Circle(
        start.translation - np.array([0.0, HAND_RADIUS, 0.0]), HAND_RADIUS,
        normal=(1.0, 0.0, 0.0), start_angle=0.0, duration=DURATION,
    )  # fmt: skip
    goals.append(
        clik.Goal(hand, PoseTrajectory(circle, Hold(rotation=start.rotation)), name="hand")
    )
    posture = clik.PostureTask(robot)
    goals.append(clik.Goal(posture, JointPath(posture.angles(q0)), name="posture", priority=2,
                           gain=POSTURE_GAIN))  # fmt: skip
    text = (
        f"Talos on a floating base ({robot.nv} velocities): both soles held (6-D), CoM x, y "
        f"held, right hand on a {2 * HAND_RADIUS * 100:g} cm circle (orientation held) at "
        f"level 1, posture (level 2, gain {POSTURE_GAIN:g} 1/s), joint-range rows, law (10)"
    )
    return _scene("humanoid", robot, q0, goals, text)


def step_variant(scene: WholeBody, engine: str = "compiled") -> Variant:
    """The scene offline (``step_us.<name>``): one ``Tracker.run`` over its trajectories."""
    tracker = scene.tracker(engine)

    def run() -> RunOutcome:
        result = tracker.run(q0=scene.q0)
        errors = result.task_errors
        worst = max(errors[name]["max"] for name in scene.poses)
        info = {"status": result.status, "max_task_error": worst, "law": tracker.law,
                "engine": engine}  # fmt: skip
        return result.steps, result.wall_time_s, info

    text = f"offline (clik.Tracker.run): {scene.text}"
    if engine == "compiled":
        return Variant(scene.name, text, run)
    return Variant(f"python_{scene.name}", f"Python engine: {text}", run)
