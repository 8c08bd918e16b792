"""What a run adds for several tasks and eq. (5): the other goals, the levels' parts, ``z``.

One object per run (:class:`~clik.loop.tracking._Run`), empty for a run of one task
without objectives (its attributes are then None and the loop is the one-task loop).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.constraints.dexterity import dexterity_row
from clik.loop.goal_rows import GoalChunks, GoalRows
from clik.loop.reference_stream import rows_at_rest
from clik.objectives import gradients
from clik.objectives.objective import JOINT_CENTERING, POSTURE

if TYPE_CHECKING:
    import pinocchio as pin

    from clik.objectives.objective import Objective
    from clik.tasks.extended_task import ExtendedTask


class GoalState:
    """A run's other goals (:attr:`rows`, :attr:`chunks`) and its objectives of eq. (5).

    Args:
        tracker: The run's tracker (its ``stack``, ``objectives``, ``leveled``, ``task``).
        t: The run's time grid [s].
        size: Samples per reference chunk (None: an open run, its references given
            sample by sample).
        capacity: The record's samples.
        q0: The run's start (a posture objective's default posture).

    Attributes:
        rows: The other goals' rows and errors (None: one task).
        chunks: Their references (None: one task).
        parts: Law (10)'s parts per level (1 + L, nv), when it runs level by level
            (:func:`clik.loop.levels.prioritized_levels`); else None.
        objectives: ``(level, objective, setup)`` of each objective.
    """

    def __init__(
        self, tracker: Any, t: Any, size: int | None, capacity: int, q0: np.ndarray | None
    ) -> None:
        stack = tracker.stack
        extra = stack is not None and len(stack.goals) > 1
        self.chunks = GoalChunks(stack, t, size) if extra and size is not None else None
        self.rows = GoalRows(stack, capacity) if extra else None
        robot, task = tracker.robot, tracker.task
        self.task = task
        nv = robot.nv
        self.parts = np.zeros((1 + len(tracker.ends), nv)) if tracker.leveled else None
        priorities = [1] if stack is None else stack.priorities
        start = robot.q_reference if q0 is None else q0
        self.objectives: list[tuple[int, Objective, dict[str, Any]]] = [
            (o.level(priorities), o, o.setup(robot, start)) for o in tracker.objectives
        ]
        self._z = [np.zeros(nv) for _ in self.objectives]

    def load(
        self, k: int, at_rest: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray]:
        """The other goals' chunk at sample ``k``, and ``at_rest`` with their references."""
        if self.chunks is None:
            return None, None, at_rest
        ref, ff = self.chunks.load(k)
        return ref, ff, at_rest & rows_at_rest(ff)

    def objective_gradients(
        self, model: pin.Model, data: pin.Data, ext: ExtendedTask, q: np.ndarray
    ) -> list[tuple[int, np.ndarray]]:
        """Each objective's ``(level, z)`` at ``q`` (:mod:`clik.objectives.gradients`).

        ``data`` holds every joint's Jacobian at ``q`` (manipulability reads the primary
        task's rows of ``ext``).
        """
        out = []
        for (level, obj, setup), z in zip(self.objectives, self._z, strict=True):
            if obj.kind == JOINT_CENTERING:
                gradients.joint_centering(
                    q, setup["idx_q"], setup["idx_v"], setup["center"], setup["half_range"],
                    obj.gain, z,
                )  # fmt: skip
            elif obj.kind == POSTURE:
                gradients.posture(model, q, setup["q_ref"], obj.gain, z)
            else:
                task = self.task
                dexterity_row(model, data, task.frame_id, task.rows, ext.J[: task.m], z)
                z *= obj.gain
            out.append((level, z))
        return out
