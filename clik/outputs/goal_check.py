"""A several-task result's goals, checked against the run's: by name.

A result of ``tasks=[...]`` names its tasks (``info["tasks"]``); what draws or exports
each task's reference (the views, the bag export) is given the goals and checks they are
the run's.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from clik.errors import InputError
from clik.tasks.goal import Goal

if TYPE_CHECKING:
    from clik.outputs.result import TrackingResult


def goal_names(goals: Sequence[Goal]) -> list[str]:
    """The goals' names as a run names them: ``goal.name``, else ``"task<i>"`` (1-based)."""
    return [g.name or f"task{i + 1}" for i, g in enumerate(goals)]


def checked_goals(result: TrackingResult, goals: Sequence[Goal]) -> list[str]:
    """The goals' names, checked against the run's (``result.info["tasks"]``).

    Raises:
        InputError: Not a list of goals, or not the goals the run was given.
    """
    if isinstance(goals, Goal) or not isinstance(goals, Sequence) or not goals:
        raise InputError("tasks", "the list of clik.Goal the run was given", type(goals).__name__)
    bad = [type(g).__name__ for g in goals if not isinstance(g, Goal)]
    if bad:
        raise InputError("tasks", "a list of clik.Goal", bad[0])
    names = goal_names(goals)
    ran = result.info.get("tasks")
    if ran is None:
        raise InputError(
            "tasks",
            "a result of a run with tasks=[...] (its info['tasks'] names them)",
            "a one-task result",
        )
    if sorted(names) != sorted(ran):
        raise InputError("tasks", f"the goals the run was given, named {list(ran)}", names)
    return names
