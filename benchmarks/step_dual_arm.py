"""The dual-arm lines of the step benchmark: two hands and a posture, clik and pink.

``dual_arm``: Baxter (two 7-joint arms, head; 15 joints with the grippers locked), a
6-D pose task on each hand along a shared line (a box carried 10 cm), and a posture
task holding the start one level below (law (10); docs/method.md, "Several tasks").
``pink_dual_arm``: pink on the same three tasks (two ``FrameTask`` of cost 1, a
``PostureTask``), with its ``ConfigurationLimit``, one QP per sample.
"""

from __future__ import annotations

import importlib.metadata
import time
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from benchmarks.config import DT, BenchConfig
from benchmarks.pink_backend import PINK_DAMPING, Pink
from benchmarks.pose_error import pose_errors
from benchmarks.step_variant import RunOutcome, Variant
from clik.trajectory import Hold, JointPath, Line, PoseTrajectory, time_grid

HANDS = ("left_hand_link", "right_hand_link")
"""Baxter's hand frames."""
SHIFT = (0.05, 0.0, 0.1)
"""Where the hands carry the box [m]."""
POSTURE_GAIN = 10.0
"""Gain of clik's posture task (level 2) [1/s]."""
PINK_POSTURE_COST = 1e-3
"""Cost of pink's posture task (its frame tasks' costs are 1)."""
MIN_DURATION = 1.0
"""Shortest line [s] (``--quick``'s too): 10 cm in less would outrun the joints' limits."""
BENT = {"s1": -0.6, "e1": 1.2, "w1": 0.9}
"""Both arms' start (the reference posture is near-singular) [rad]."""


@dataclass(frozen=True)
class DualArm:
    """The dual-arm problem: robot, start, the hands' tasks and trajectories, the posture.

    Attributes:
        robot: Baxter, grippers locked.
        q0: Start configuration.
        hands: The two pose tasks.
        lines: Their references.
        posture: The posture task (every joint).
    """

    robot: clik.Robot
    q0: np.ndarray
    hands: tuple[clik.Task, clik.Task]
    lines: tuple[PoseTrajectory, PoseTrajectory]
    posture: clik.PostureTask

    def goals(self) -> list[clik.Goal]:
        """The hands at priority 1, the posture at 2."""
        return [
            clik.Goal(self.hands[0], self.lines[0], name="left"),
            clik.Goal(self.hands[1], self.lines[1], name="right"),
            clik.Goal(self.posture, JointPath(self.posture.angles(self.q0)), name="posture",
                      priority=2, gain=POSTURE_GAIN),
        ]  # fmt: skip


def dual_arm(duration: float) -> DualArm:
    """Baxter carrying a box along a line of ``duration`` [s]."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its grippers' mimic joints, locked here
        robot = clik.Robot.load(
            "baxter", lock={"l_gripper_l_finger_joint": 0.0, "r_gripper_l_finger_joint": 0.0}
        )
    q0 = robot.q_reference.copy()
    for side in ("left", "right"):
        for joint, value in BENT.items():
            q0[robot.model.joints[robot.joint_id(f"{side}_{joint}")].idx_q] = value
    hands = (clik.Task(robot, HANDS[0], "pose"), clik.Task(robot, HANDS[1], "pose"))
    lines = []
    for hand in hands:
        start = hand.placement(q0)
        line = Line(start.translation, start.translation + np.array(SHIFT), duration)
        lines.append(PoseTrajectory(line, Hold(rotation=start.rotation)))
    return DualArm(robot, q0, hands, (lines[0], lines[1]), clik.PostureTask(robot))


def clik_dual_arm_variant(problem: DualArm, engine: str) -> Variant:
    """The clik line: the three tasks, law (10), in ``engine``."""
    tracker = clik.Tracker(
        tasks=problem.goals(), law="pseudoinverse", gain=100.0, dt=DT, engine=engine
    )

    def run() -> RunOutcome:
        result = tracker.run(q0=problem.q0)
        errors = result.task_errors
        info: dict[str, Any] = {
            "status": result.status,
            "max_task_error": max(errors["left"]["max"], errors["right"]["max"]),
            "law": tracker.law,
            "engine": engine,
        }
        return result.steps, result.wall_time_s, info

    name = "dual_arm" if engine == "compiled" else "python_dual_arm"
    text = (
        f"Baxter ({problem.robot.nv} joints), two 6-D hand tasks on a line + a posture task "
        "at priority 2, law (10)"
    )
    return Variant(name, text if engine == "compiled" else f"Python engine: {text}", run)


def pink_dual_arm_variant(pink: Pink, problem: DualArm) -> Variant:
    """Pink's line: the same hands' references and posture, one QP per sample."""
    from pink.limits import ConfigurationLimit
    from pink.tasks import FrameTask, PostureTask

    model = problem.robot.model
    t = time_grid(problem.lines[0].duration, DT)
    targets = []
    for line in problem.lines:
        ref = line.sample(t)
        assert ref.rotation is not None and ref.position is not None
        targets.append([pin.SE3(R, p) for R, p in zip(ref.rotation, ref.position, strict=True)])
    frames = [FrameTask(h, position_cost=1.0, orientation_cost=1.0) for h in HANDS]
    posture = PostureTask(cost=PINK_POSTURE_COST)
    posture.set_target(problem.q0)
    tasks, limits = [*frames, posture], [ConfigurationLimit(model)]
    configuration = pink.module.Configuration(model, model.createData(), problem.q0)
    check = model.createData()
    fids = [h.frame_id for h in problem.hands]

    def run() -> RunOutcome:
        configuration.update(problem.q0)
        n = steps = t.shape[0]
        q_log = np.zeros((n, model.nq))
        status = "completed"
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            for frame, target in zip(frames, targets, strict=True):
                frame.set_target(target[k])
            try:
                velocity = pink.module.solve_ik(
                    configuration, tasks, DT, solver=pink.solver, damping=PINK_DAMPING,
                    limits=limits,
                )  # fmt: skip
            except Exception as exc:  # NoSolutionFound, NotWithinConfigurationLimits
                status, steps = f"failed: {type(exc).__name__}", k + 1
                break
            configuration.integrate_inplace(velocity, DT)
        wall = time.perf_counter() - start
        worst = max(
            pose_errors(model, check, fid, q_log[k], target[k])[0]
            for k in range(steps)
            for fid, target in zip(fids, targets, strict=True)
        )
        return steps, wall, {"status": status, "max_task_error": float(worst)}

    return Variant(
        "pink_dual_arm",
        f"pink {importlib.metadata.version('pin-pink')}: two FrameTask + PostureTask (cost "
        f"{PINK_POSTURE_COST:g}), ConfigurationLimit, {pink.solver}, solve_ik + integrate",
        run,
    )


def dual_arm_variants(
    config: BenchConfig, engines: tuple[str, ...], pink: Pink | None
) -> list[Variant]:
    """Clik's dual-arm line in each engine, and pink's when installed."""
    problem = dual_arm(max(config.panda_duration, MIN_DURATION))
    variants = [clik_dual_arm_variant(problem, e) for e in engines]
    if pink is not None:
        variants.append(pink_dual_arm_variant(pink, problem))
    return variants
