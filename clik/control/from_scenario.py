"""A controller built from a scenario, and targets that hold each task where it is.

``clik ros`` and the closed-loop simulation (:mod:`clik.sim.closed_loop`) step a
:class:`~clik.control.controller.Controller` with the scenario's tasks, law, constraints
and start, the targets coming from elsewhere (topics, the scenario's trajectories).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from clik.control.controller import Controller
from clik.control.measured import MEASURED_JUMP
from clik.errors import InputError
from clik.tasks.com_task import ComTask
from clik.tasks.goal import Goal
from clik.tasks.posture_task import PostureTask
from clik.tasks.task import Task


def controller_of(run: Any, measured_jump: float = MEASURED_JUMP) -> Controller:
    """The scenario run's controller: its tasks (no trajectories), law, constraints, start.

    ``measured_jump`` is ``c`` of eq. (M3) (``clik ros`` gives its ``[ros]`` setting).
    """
    solver = run.scenario.solver
    goals = None
    if run.goals:
        goals = [Goal(g.task, name=g.name, priority=g.priority, gain=g.gain) for g in run.goals]
    tr = run.tracker
    return Controller(
        None if goals else run.task, tasks=goals, objectives=tr.objectives or None,
        law=solver["law"], gain=solver["gain"], dt=solver["dt"], damping=solver["damping"],
        constraints=tr.constraints, engine=solver["engine"], joint_speed=tr.joint_speed,
        q0=run.q0, tolerance=solver["tolerance"], settling_time=solver["settling_time"],
        measured_jump=measured_jump,
    )  # fmt: skip


def held_target(task: Any, q: np.ndarray) -> np.ndarray:
    """A task's target that holds it where it is at ``q`` (its kind's form).

    Raises:
        InputError: A task kind the node cannot take targets for.
    """
    robot = task.robot
    if isinstance(task, Task):
        data = robot.model.createData()
        pin.framesForwardKinematics(robot.model, data, q)
        placement = data.oMf[task.frame_id]
        if task.has_position and task.has_orientation:
            return np.asarray(placement.homogeneous)
        return np.array(placement.translation if task.has_position else placement.rotation)
    if isinstance(task, ComTask):
        return np.array(pin.centerOfMass(robot.model, robot.model.createData(), q))
    if isinstance(task, PostureTask):
        return np.asarray(task.angles(q), dtype=float)
    raise InputError(
        "tasks", "frame, centre-of-mass or posture tasks for clik ros", type(task).__name__
    )
