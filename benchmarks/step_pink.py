"""pink's tracking step, the comparison line of the step benchmark.

pink (``FrameTask`` + ``PostureTask``, ``ConfigurationLimit`` or its default
limits, ``solve_ik`` + ``integrate_inplace``) tracks the same reference from the
same start on the same model as clik's Panda lines, one QP per sample; with the
spheres, its collision barrier too (:mod:`benchmarks.pink_barrier`).
"""

from __future__ import annotations

import importlib.metadata
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from benchmarks.config import DT
from benchmarks.pink_backend import PINK_DAMPING, Pink
from benchmarks.pink_barrier import PinkObstacles
from benchmarks.pose_error import pose_errors
from benchmarks.step_variant import RunOutcome, Variant
from clik.trajectory import Trajectory

PINK_POSTURE_COST = 1e-3
"""Cost of pink's posture task in the step benchmark (the frame task's costs are 1)."""


def reference_poses(trajectory: Trajectory) -> list[pin.SE3]:
    """The trajectory's desired poses, one per sample at :data:`~benchmarks.config.DT`.

    Args:
        trajectory: A pose reference (position and rotation).

    Raises:
        ValueError: The trajectory lacks the position or the rotation.
    """
    ref = trajectory.sample(clik.trajectory.time_grid(trajectory.duration, DT))
    if ref.rotation is None or ref.position is None:
        raise ValueError("pink's step line needs a pose reference (position and rotation)")
    return [pin.SE3(R, p) for R, p in zip(ref.rotation, ref.position, strict=True)]


@dataclass
class PinkTracking:
    """pink's loop over the reference, its tasks, limits, barriers and configuration built once.

    Attributes:
        lead: Which sample's target the step at ``t_k`` is given: ``x_d(t_k + lead dt)``.
            0 (the step lines) or 1 (the tick lines: the look-ahead target
            ``x_d(t_k+1)``, as pink's examples set the target, then solve for the next
            configuration; the run has one step fewer than samples).
        q_log: ``q_k`` at every step and, after the last, the final joints (``recorded``
            rows of the last run are valid).
    """

    pink: Pink
    model: pin.Model
    frame_id: int
    targets: list[pin.SE3]
    q0: np.ndarray
    frame_task: Any
    tasks: list[Any]
    limits: list[Any] | None
    obstacles: PinkObstacles | None = None
    lead: int = 0
    configuration: Any = field(init=False)
    check_data: pin.Data = field(init=False)
    q_log: np.ndarray = field(init=False)
    recorded: int = field(init=False, default=0)

    def __post_init__(self) -> None:
        model, obstacles = self.model, self.obstacles
        collision = {} if obstacles is None else obstacles.configuration_arguments()
        self.configuration = self.pink.module.Configuration(
            model, model.createData(), self.q0, **collision
        )
        self.check_data = model.createData()
        self.q_log = np.zeros((len(self.targets) + 1, model.nq))

    def run(self) -> RunOutcome:
        """One whole run: the timed loop, then the position error of every step."""
        pink, solver, limits, tasks = self.pink.module, self.pink.solver, self.limits, self.tasks
        configuration, frame_task, targets, q_log, lead = (
            self.configuration, self.frame_task, self.targets, self.q_log, self.lead,
        )  # fmt: skip
        barriers = None if self.obstacles is None else self.obstacles.barriers
        configuration.update(self.q0)
        status = "completed"
        n = steps = len(targets) - lead
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            frame_task.set_target(targets[k + lead])
            try:
                velocity = pink.solve_ik(
                    configuration, tasks, DT, solver=solver, damping=PINK_DAMPING,
                    limits=limits, barriers=barriers,
                )  # fmt: skip
            except Exception as exc:  # NoSolutionFound, NotWithinConfigurationLimits
                status, steps = f"failed: {type(exc).__name__}", k + 1
                break
            configuration.integrate_inplace(velocity, DT)
        wall = time.perf_counter() - start
        self.recorded = steps
        if status == "completed":  # the joints the last step commands
            q_log[n] = configuration.q
            self.recorded = n + 1
        errors = [
            pose_errors(self.model, self.check_data, self.frame_id, q_log[k], targets[k])[0]
            for k in range(steps)
        ]
        return steps, wall, {"status": status, "max_task_error": float(max(errors))}

    def joints(self) -> np.ndarray:
        """The joints of the last run, ``q_0`` to the final one (recorded, nq) [rad]."""
        return self.q_log[: self.recorded]


def pink_tracking(
    pink: Pink,
    robot: clik.Robot,
    task: clik.Task,
    trajectory: Trajectory,
    q0: np.ndarray,
    default_limits: bool = False,
    obstacles: PinkObstacles | None = None,
    lead: int = 0,
) -> PinkTracking:
    """Pink's loop on the same model, reference and start as clik's Panda lines.

    Args:
        pink: The installed pink and its QP solver.
        robot: The Panda.
        task: clik's pose task (its frame is pink's frame task's).
        trajectory: The reference.
        q0: Start configuration (also the posture task's target).
        default_limits: pink's own default (``limits=None``: configuration and
            velocity limits) instead of the configuration limits alone.
        obstacles: The spheres as pink's collision barrier, or None.
        lead: 0: the step at ``t_k`` is given ``x_d(t_k)``; 1: ``x_d(t_k+1)``.
    """
    from pink.limits import ConfigurationLimit
    from pink.tasks import FrameTask, PostureTask

    model = robot.model
    frame_task = FrameTask(task.frame, position_cost=1.0, orientation_cost=1.0)
    posture_task = PostureTask(cost=PINK_POSTURE_COST)
    posture_task.set_target(q0)
    limits = None if default_limits else [ConfigurationLimit(model)]
    return PinkTracking(
        pink, model, task.frame_id, reference_poses(trajectory), q0, frame_task,
        [frame_task, posture_task], limits, obstacles, lead,
    )  # fmt: skip


def pink_setup_text(pink: Pink, default_limits: bool = False) -> str:
    """Pink's version, tasks, limits and solver in words.

    Args:
        pink: The installed pink and its QP solver.
        default_limits: Whether the line runs pink's default limits.
    """
    limits_text = (
        "pink's default limits (configuration + velocity)"
        if default_limits
        else "ConfigurationLimit"
    )
    return (
        f"pink {importlib.metadata.version('pin-pink')}: FrameTask + PostureTask "
        f"(cost {PINK_POSTURE_COST:g}), {limits_text}, {pink.solver}, solve_ik + integrate"
    )


def pink_step_variant(
    pink: Pink,
    robot: clik.Robot,
    task: clik.Task,
    trajectory: Trajectory,
    q0: np.ndarray,
    default_limits: bool = False,
    obstacles: PinkObstacles | None = None,
) -> Variant:
    """The tracking step of pink on the same model, reference and start as clik's Panda lines.

    Args:
        pink: The installed pink and its QP solver.
        robot: The Panda.
        task: clik's pose task (its frame is pink's frame task's).
        trajectory: The reference.
        q0: Start configuration (also the posture task's target).
        default_limits: pink's own default (``limits=None``: configuration and
            velocity limits) instead of the configuration limits alone.
        obstacles: The spheres as pink's collision barrier (the line
            ``pink_panda_pose_obstacles``), or None.
    """
    tracking = pink_tracking(pink, robot, task, trajectory, q0, default_limits, obstacles)
    name = "pink_panda_pose" + ("_default_limits" if default_limits else "")
    text = pink_setup_text(pink, default_limits)
    if obstacles is not None:
        name, text = "pink_panda_pose_obstacles", f"{text}; {obstacles.description}"
    return Variant(name, text, tracking.run)
