"""pink's single-pose solve: its full step iterated to convergence (capped), dt = 1."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from benchmarks.pink_backend import PINK_DAMPING, Pink
from benchmarks.pose_error import ORIENTATION_TOLERANCE, POSITION_TOLERANCE

PINK_LM_DAMPING = 1e-3
"""Levenberg-Marquardt damping of pink's frame task in the solve benchmark."""

PinkSolve = Callable[[pin.SE3], tuple[np.ndarray, int]]
"""Solve one target: returns (configuration reached, iterations)."""


def pink_setup_text(pink: Pink) -> str:
    """How pink is set up for the solve benchmark, in one sentence for ``bench.md``.

    Args:
        pink: The installed pink and its QP solver.
    """
    return (
        f"FrameTask (lm_damping {PINK_LM_DAMPING:g}) + ConfigurationLimit, {pink.solver}, "
        f"damping {PINK_DAMPING:g}, dt = 1, from the reference configuration, "
        "no restarts"
    )


@dataclass
class _PinkSolver:
    """pink's frame task, limits and configuration, built once for every target."""

    pink: Pink
    model: pin.Model
    task: clik.Task
    q_ref: np.ndarray
    cap: int
    frame_task: Any = field(init=False)
    limits: list[Any] = field(init=False)
    configuration: Any = field(init=False)

    def __post_init__(self) -> None:
        from pink.limits import ConfigurationLimit
        from pink.tasks import FrameTask

        self.frame_task = FrameTask(
            self.task.frame, position_cost=1.0, orientation_cost=1.0, lm_damping=PINK_LM_DAMPING
        )
        self.limits = [ConfigurationLimit(self.model)]
        self.configuration = self.pink.module.Configuration(
            self.model, self.model.createData(), self.q_ref
        )

    def solve(self, target: pin.SE3) -> tuple[np.ndarray, int]:
        """Iterate pink's full step (dt = 1, so the velocity is the displacement)."""
        pink, solver, limits, cap = self.pink.module, self.pink.solver, self.limits, self.cap
        configuration, frame_task, fid = self.configuration, self.frame_task, self.task.frame_id
        configuration.update(self.q_ref)
        frame_task.set_target(target)
        p_d, R_d = target.translation, target.rotation
        for it in range(cap + 1):
            placement = configuration.data.oMf[fid]
            dp = p_d - placement.translation
            rot = pin.log3(R_d @ placement.rotation.T)
            if (
                math.sqrt(float(dp @ dp)) <= POSITION_TOLERANCE
                and math.sqrt(float(rot @ rot)) <= ORIENTATION_TOLERANCE
            ) or it == cap:
                break
            try:
                velocity = pink.solve_ik(
                    configuration,
                    [frame_task],
                    1.0,
                    solver=solver,
                    damping=PINK_DAMPING,
                    limits=limits,
                )
            except Exception:  # NoSolutionFound: counted as a failure
                break
            configuration.integrate_inplace(velocity, 1.0)
        return configuration.q, it


def pink_solver(
    pink: Pink, model: pin.Model, task: clik.Task, q_ref: np.ndarray, cap: int
) -> PinkSolve:
    """Solve with pink to convergence of ``task``'s frame from ``q_ref``, at most ``cap`` steps.

    Args:
        pink: The installed pink and its QP solver.
        model: The robot model.
        task: clik's pose task (its frame is pink's frame task's).
        q_ref: Start configuration of every solve.
        cap: Iteration cap.
    """
    return _PinkSolver(pink, model, task, q_ref, cap).solve
