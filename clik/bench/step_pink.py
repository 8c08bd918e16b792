"""pink's tracking step, the comparison line of the step benchmark.

pink (``FrameTask`` + ``PostureTask``, ``ConfigurationLimit`` or its default
limits, ``solve_ik`` + ``integrate_inplace``) tracks the same reference from the
same start on the same model as clik's Panda lines, one QP per sample.
"""

from __future__ import annotations

import importlib.metadata
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from clik.bench.config import DT
from clik.bench.pink_backend import PINK_DAMPING, Pink
from clik.bench.pose_error import pose_errors
from clik.bench.step_variant import RunOutcome, Variant
from clik.trajectory import Trajectory

PINK_POSTURE_COST = 1e-3
"""Cost of pink's posture task in the step benchmark (the frame task's costs are 1)."""


def reference_poses(trajectory: Trajectory) -> list[pin.SE3]:
    """The trajectory's desired poses, one per sample at :data:`~clik.bench.config.DT`.

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
class _PinkTracking:
    """pink's loop over the reference, its tasks and configuration built once."""

    pink: Pink
    model: pin.Model
    frame_id: int
    targets: list[pin.SE3]
    q0: np.ndarray
    frame_task: Any
    tasks: list[Any]
    limits: list[Any] | None
    configuration: Any = field(init=False)
    check_data: pin.Data = field(init=False)
    q_log: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        model = self.model
        self.configuration = self.pink.module.Configuration(model, model.createData(), self.q0)
        self.check_data = model.createData()
        self.q_log = np.zeros((len(self.targets), model.nq))

    def run(self) -> RunOutcome:
        """One whole run: the timed loop, then the position error of every sample."""
        pink, solver, limits, tasks = self.pink.module, self.pink.solver, self.limits, self.tasks
        configuration, frame_task, targets, q_log = (
            self.configuration,
            self.frame_task,
            self.targets,
            self.q_log,
        )
        configuration.update(self.q0)
        status = "completed"
        n = steps = len(targets)
        start = time.perf_counter()
        for k in range(n):
            q_log[k] = configuration.q
            frame_task.set_target(targets[k])
            try:
                velocity = pink.solve_ik(
                    configuration, tasks, DT, solver=solver, damping=PINK_DAMPING, limits=limits
                )
            except Exception as exc:  # NoSolutionFound, NotWithinConfigurationLimits
                status, steps = f"failed: {type(exc).__name__}", k + 1
                break
            configuration.integrate_inplace(velocity, DT)
        wall = time.perf_counter() - start
        errors = [
            pose_errors(self.model, self.check_data, self.frame_id, q_log[k], targets[k])[0]
            for k in range(steps)
        ]
        return steps, wall, {"status": status, "max_task_error": float(max(errors))}


def pink_step_variant(
    pink: Pink,
    robot: clik.Robot,
    task: clik.Task,
    trajectory: Trajectory,
    q0: np.ndarray,
    default_limits: bool = False,
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
    """
    from pink.limits import ConfigurationLimit
    from pink.tasks import FrameTask, PostureTask

    model = robot.model
    targets = reference_poses(trajectory)
    frame_task = FrameTask(task.frame, position_cost=1.0, orientation_cost=1.0)
    posture_task = PostureTask(cost=PINK_POSTURE_COST)
    posture_task.set_target(q0)
    limits = None if default_limits else [ConfigurationLimit(model)]
    tracking = _PinkTracking(
        pink, model, task.frame_id, targets, q0, frame_task, [frame_task, posture_task], limits
    )
    limits_text = (
        "pink's default limits (configuration + velocity)"
        if default_limits
        else "ConfigurationLimit"
    )
    return Variant(
        "pink_panda_pose_default_limits" if default_limits else "pink_panda_pose",
        f"pink {importlib.metadata.version('pin-pink')}: FrameTask + PostureTask "
        f"(cost {PINK_POSTURE_COST:g}), {limits_text}, {pink.solver}, solve_ik + integrate",
        tracking.run,
    )
