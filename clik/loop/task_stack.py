"""The tasks of one run, checked and ordered: the primary task, levels, rows and gains.

docs/method.md, "Several tasks". The goals' rows are stacked into the task part of the
extended task (24)-(25), level by level (priority 1 first); the run's *primary* task
is the first task of the first level that may lead (its kind says: a frame task in the
world, :attr:`~clik.tasks.kind.BaseTask.leads`): its rows come first, its trail is the
run's ``position``, and the constraint kinds that guard "the task" (workspace, cone,
dexterity) read it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.loop.gains import row_gains
from clik.objectives.objective import Objective
from clik.tasks.goal import Goal

if TYPE_CHECKING:
    from clik.tasks.task import Task


class TaskStack:
    """Goals checked against each other and ordered by level.

    Args:
        goals: The goals (at least one).
        gain: The default gain [1/s] of goals without their own (scalar or per row of
            the primary task).

    Raises:
        InputError: No goals, not goals, repeated names, tasks on several robots, or no
            frame task in the first level.

    Attributes:
        goals: The goals in row order: the primary first, then level by level.
        names: Their names.
        levels: Each goal's level index (1 = the first level).
        priorities: The distinct priorities, highest first (level ``l`` is
            ``priorities[l - 1]``).
        offsets: Each goal's first row.
        ends: The end row of each level.
        m: All task rows.
        K: The rows' gains [1/s] (m,).
    """

    def __init__(self, goals: Sequence[Goal], gain: float | Sequence[float] = 1000.0) -> None:
        if isinstance(goals, Goal) or not isinstance(goals, Sequence) or not goals:
            raise InputError("tasks", "a non-empty list of clik.Goal", type(goals).__name__)
        bad = [type(g).__name__ for g in goals if not isinstance(g, Goal)]
        if bad:
            raise InputError("tasks", "a list of clik.Goal", bad[0])
        robot = goals[0].task.robot
        if any(g.task.robot is not robot for g in goals):
            raise InputError("tasks", "tasks on one robot (the same clik.Robot)")
        priorities = sorted({int(g.priority) for g in goals})
        top = [i for i, g in enumerate(goals) if g.priority == priorities[0]]
        first = next((i for i in top if goals[i].task.leads), None)
        if first is None:
            raise InputError(
                "tasks", f"a frame task (clik.Task) at priority {priorities[0]}, the run's "
                "primary task (a relative, posture or com task tracks alongside one)",
            )  # fmt: skip
        names = [g.name or f"task{i + 1}" for i, g in enumerate(goals)]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise InputError("tasks.name", "distinct task names", dup)
        rest = sorted((i for i in range(len(goals)) if i != first), key=lambda i: goals[i].priority)
        order = [first, *rest]
        self.robot = robot
        self.goals = [goals[i] for i in order]
        self.names = [names[i] for i in order]
        self.priorities = priorities
        self.levels = [priorities.index(g.priority) + 1 for g in self.goals]
        sizes = [g.task.m for g in self.goals]
        self.offsets = [int(x) for x in np.cumsum([0, *sizes[:-1]])]
        self.m = int(sum(sizes))
        self.ends = [
            max(
                o + s
                for o, s, lv in zip(self.offsets, sizes, self.levels, strict=True)
                if lv == level
            )
            for level in range(1, len(priorities) + 1)
        ]
        self.K = np.concatenate(
            [self._gains(g, n, gain) for g, n in zip(self.goals, self.names, strict=True)]
        )

    @staticmethod
    def _gains(goal: Goal, name: str, default: float | Sequence[float]) -> np.ndarray:
        m = goal.task.m
        if goal.gain is None:
            K = np.asarray(default, dtype=float)
            return (
                np.full(m, float(np.max(K)))
                if K.ndim and K.shape[0] != m
                else row_gains(default, m)
            )
        return row_gains(goal.gain, m, f"tasks[{name!r}].gain")

    @property
    def primary(self) -> Goal:
        """The primary goal (a frame task of the first level)."""
        return self.goals[0]

    @property
    def extras(self) -> list[Goal]:
        """The goals after the primary, in row order."""
        return self.goals[1:]

    @property
    def n_levels(self) -> int:
        """Number of priority levels."""
        return len(self.priorities)

    def row_labels(self) -> list[str]:
        """Each task row named ``"<task>:<axis>"``, in row order."""
        return [
            f"{n}:{a}" for n, g in zip(self.names, self.goals, strict=True) for a in g.task.axes
        ]

    def duration(self) -> float:
        """The longest of the goals' trajectories [s] (each holds its end after it)."""
        return max(float(g.trajectory.duration) for g in self.goals)


def checked_tasks(
    task: object, tasks: Sequence[Goal] | None, objectives: Sequence[Objective] | None,
    law: str, gain: float | Sequence[float],
) -> tuple[Task, TaskStack | None, list[Objective]]:  # fmt: skip
    """The run's primary task, its stack (None: one task) and objectives, checked.

    Raises:
        InputError: Both or neither of ``task`` and ``tasks``; a primary task that is not
            a frame task; priorities or objectives under laws (9) and (8) (they stack
            every task in one level, each weighted by its gain, and have no null space).
    """
    if (task is None) == (tasks is None):
        raise InputError("tasks", "either task (one frame task) or tasks (a list of clik.Goal)")
    objs = list(objectives or ())
    bad = [type(o).__name__ for o in objs if not isinstance(o, Objective)]
    if bad or isinstance(objectives, Objective):
        raise InputError("objectives", "a list of clik.Objective", bad[0] if bad else "Objective")
    stack = None if tasks is None else TaskStack(tasks, gain)
    primary: Any = task if stack is None else stack.primary.task
    if not primary.leads:
        expected = "a clik.Task (a frame in the world); other kinds go in tasks=[...] beside one"
        raise InputError("task", expected, type(primary).__name__)
    if law != "pseudoinverse":
        if stack is not None and stack.n_levels > 1:
            raise InputError(
                "tasks.priority", "one priority with law "
                f"{law!r} (it stacks every task in one level, weighted by its gain); "
                "priority levels need law 'pseudoinverse' (10)", stack.priorities,
            )  # fmt: skip
        if objs:
            expected = (
                "none with law " + repr(law) + ": eq. (5)'s null space needs law 'pseudoinverse'"
            )
            raise InputError("objectives", expected, [o.kind for o in objs])
    return primary, stack, objs
