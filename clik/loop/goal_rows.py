"""The extra goals of a run: their references chunk by chunk, their rows, their errors.

A run's task part is its primary task's rows (:mod:`clik.loop.tracking`) then the
extra goals' (:class:`~clik.loop.task_stack.TaskStack`), level by level. Each sample,
:meth:`GoalRows.fill` writes the extra goals' rows (error (6), Jacobian (3),
feed-forward) after the primary's, and :meth:`GoalRows.errors` keeps their error norms:
at the recorded samples, their largest over every sample and the last.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.loop.reference_stream import KEEP_SAMPLES

if TYPE_CHECKING:
    import pinocchio as pin

    from clik.loop.task_stack import TaskStack
    from clik.tasks.extended_task import ExtendedTask
    from clik.tasks.kind import BaseTask

GoalChunk = tuple[np.ndarray, np.ndarray]


class GoalChunks:
    """The extra goals' references on the run's time grid, in chunks of ``size``.

    Every chunk is sampled once before the run (a trajectory that yields NaN or lacks
    what its task reads is refused then, naming the task); a run of at most
    :data:`~clik.loop.reference_stream.KEEP_SAMPLES` samples keeps them.

    Args:
        stack: The run's tasks.
        t: The run's time grid [s].
        size: Samples per chunk (the primary's).
    """

    def __init__(self, stack: TaskStack, t: np.ndarray, size: int) -> None:
        self.goals, self.names = stack.extras, stack.names[1:]
        self.t, self.size = t, size
        self.D = sum(g.task.reference_size for g in self.goals)
        self.M = sum(g.task.ff_size for g in self.goals)
        self._kept: dict[int, GoalChunk] = {}
        keep = t.shape[0] <= KEEP_SAMPLES
        for c0 in range(0, t.shape[0], size):
            chunk = self._sample(c0)
            if keep or c0 == 0:
                self._kept[c0] = chunk

    def _sample(self, c0: int) -> GoalChunk:
        c1 = min(c0 + self.size, self.t.shape[0])
        n = c1 - c0
        REF, FF = np.empty((n, self.D)), np.empty((n, self.M))
        d = mm = 0
        for goal, name in zip(self.goals, self.names, strict=True):
            task = goal.task
            try:
                ref, ff = task.reference_arrays(goal.trajectory.sample(self.t[c0:c1]))
            except InputError as exc:
                raise InputError(f"tasks[{name!r}].{exc.field}", exc.expected, exc.got) from None
            if ref.shape != (n, task.reference_size) or not np.isfinite(ref).all():
                shape = f"shape {ref.shape}, finite"
                raise InputError(
                    f"tasks[{name!r}].trajectory",
                    f"{task.reference_size} finite values per sample", shape,
                )  # fmt: skip
            REF[:, d : d + task.reference_size] = ref
            FF[:, mm : mm + task.ff_size] = ff
            d += task.reference_size
            mm += task.ff_size
        return REF, FF

    def load(self, c0: int) -> GoalChunk:
        """The chunk starting at sample ``c0``: references (n, D), feed-forward (n, M)."""
        kept = self._kept.get(c0)
        return kept if kept is not None else self._sample(c0)


class GoalRows:
    """One run's extra goals: their rows each sample and their errors.

    Args:
        stack: The run's tasks.
        capacity: The record's samples.

    Attributes:
        record: Each extra goal's ``(first, second)`` error norms at the recorded
            samples (capacity, G, 2) (:meth:`~clik.tasks.kind.BaseTask.error_norms`).
        largest: Their largest over every sample (G, 2); ``last``: the last sample's.
    """

    def __init__(self, stack: TaskStack, capacity: int) -> None:
        self.goals = stack.extras
        self.G = len(self.goals)
        self.rows = [(o, o + g.task.m) for o, g in zip(stack.offsets[1:], self.goals, strict=True)]
        self.refs = _spans([g.task.reference_size for g in self.goals])
        self.ffs = _spans([g.task.ff_size for g in self.goals])
        self.first_level = [lv == 1 for lv in stack.levels[1:]]
        self.record = np.zeros((capacity, self.G, 2))
        self.largest = np.zeros((self.G, 2))
        self.last = np.zeros((self.G, 2))

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, ext: ExtendedTask,
    ) -> None:  # fmt: skip
        """Write each extra goal's rows (J, e, feed-forward) at ``q`` (this sample's ``ref``)."""
        spans = zip(self.goals, self.rows, self.refs, self.ffs, strict=True)
        for goal, (a, b), (ra, rb), (fa, fb) in spans:
            goal.task.fill(
                model, data, q, ref[ra:rb], ff[fa:fb], ext.J[a:b], ext.e[a:b], ext.ff[a:b]
            )

    def errors(self, ext: ExtendedTask) -> float:
        """Keep this sample's error norms; returns the largest of the first level's."""
        worst = 0.0
        for i, (goal, (a, b)) in enumerate(zip(self.goals, self.rows, strict=True)):
            first, second = goal.task.error_norms(ext.e[a:b])
            self.last[i] = first, second
            if self.first_level[i]:
                worst = max(worst, first)
        np.maximum(self.largest, self.last, out=self.largest)
        return worst

    def keep(self, j: int) -> None:
        """Record this sample's errors in slot ``j``."""
        self.record[j] = self.last


def task_errors(
    stack: TaskStack | None, task: BaseTask, primary: dict[str, Any], rows: GoalRows | None
) -> dict[str, Any]:
    """``{name: {max, final, ...}}`` of every task of a run (the ``task_errors`` summary key).

    Each entry has its numbers and the words of its kind (:func:`norm_words`).

    Args:
        stack: The run's tasks (None: one task, named ``"task"``).
        task: The primary task.
        primary: The primary task's ``max``, ``final`` (and orientation) numbers.
        rows: The extra goals' errors (None without).
    """
    if stack is None:
        return {"task": {**primary, **norm_words(task)}}
    out = {stack.names[0]: {**primary, **_about(stack, 0)}}
    if rows is None:
        return out
    for i in range(rows.G):
        entry: dict[str, Any] = {"max": float(rows.largest[i, 0]), "final": float(rows.last[i, 0])}
        if stack.goals[i + 1].task.norms[1] is not None:
            entry["max_orientation"] = float(rows.largest[i, 1])
            entry["final_orientation"] = float(rows.last[i, 1])
        out[stack.names[i + 1]] = {**entry, **_about(stack, i + 1)}
    return out


def _about(stack: TaskStack, i: int) -> dict[str, Any]:
    """A task's words in ``task_errors``: kind, priority, what it is, what its norms measure."""
    goal = stack.goals[i]
    about = {"kind": goal.task.kind, "priority": int(goal.priority), "task": goal.task.describe()}
    return {**about, **norm_words(goal.task)}


def norm_words(task: BaseTask) -> dict[str, str]:
    """What a task's error norms measure, as ``task_errors`` says it.

    ``error`` and ``unit``; ``second_error`` and ``second_unit`` for a second norm.
    """
    first, second = task.norms
    out = {"error": first.what, "unit": first.unit}
    if second is not None:
        out.update(second_error=second.what, second_unit=second.unit)
    return out


def _spans(sizes: list[int]) -> list[tuple[int, int]]:
    """``[start, end)`` of consecutive blocks of ``sizes``."""
    starts = np.cumsum([0, *sizes])
    return [(int(a), int(b)) for a, b in itertools.pairwise(starts)]
