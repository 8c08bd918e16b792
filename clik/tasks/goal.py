"""A goal: a task, the trajectory it follows, its gain and its priority, by name."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from clik.errors import InputError
from clik.tasks.kind import BaseTask


@dataclass(frozen=True)
class Goal:
    """One task of several: what it tracks, how hard, and before which others.

    Args:
        task: The task (:class:`~clik.tasks.task.Task`,
            :class:`~clik.tasks.relative_task.RelativeTask`,
            :class:`~clik.tasks.posture_task.PostureTask`,
            :class:`~clik.tasks.com_task.ComTask`).
        trajectory: Its reference: a pose, position or orientation trajectory
            (``clik.trajectory``), or a :class:`~clik.trajectory.JointPath` for a posture;
            None for a :class:`~clik.control.Controller`, given its references tick by
            tick (``clik.track`` refuses it).
        name: Its name in reports (``task_errors``) and reasons; default ``"task<i>"``.
        priority: Its level, an integer >= 1 (1 is the highest): under law (10) a level
            moves in the null space of the constraints and of every level above it.
        gain: Its gain [1/s], a scalar or one per row; None: the tracker's ``gain``.

    Raises:
        InputError: A bad field (named).
    """

    task: BaseTask
    trajectory: Any = None
    name: str | None = None
    priority: int = 1
    gain: float | Sequence[float] | np.ndarray | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.task, BaseTask):
            raise InputError(
                "tasks.task", "a clik task (Task, RelativeTask, PostureTask, ComTask)",
                type(self.task).__name__,
            )  # fmt: skip
        if self.trajectory is not None and not callable(getattr(self.trajectory, "sample", None)):
            raise InputError(
                "tasks.trajectory", "a trajectory (a duration and sample(t))",
                type(self.trajectory).__name__,
            )  # fmt: skip
        if self.name is not None and (not isinstance(self.name, str) or not self.name):
            raise InputError("tasks.name", "a non-empty string", self.name)
        p = self.priority
        if isinstance(p, bool) or not isinstance(p, int | np.integer) or p < 1:
            raise InputError("tasks.priority", "an integer >= 1 (1 is the highest)", p)
