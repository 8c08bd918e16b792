"""The kinds of task, listed once: each one class, the loop and the scenarios ask them.

A new kind of task is its module in ``clik/tasks/`` (one :class:`~clik.tasks.kind.BaseTask`
class: its scenario table, rows, reference, target forms, norms and drawing), its C++
type in ``src/engine/tasks/`` (a header, listed in ``task_kinds.hpp``), its line here,
its export from ``clik``, its derivation in docs/method.md, an example scenario and its
tests in ``tests/tasks/test_<its module>.py``, whose ``case()``
``tests/tasks/test_task_kinds.py`` runs every generic check on. The docs' lists of kinds
(the scenario guide's table, the API page) are made from the registry.
"""

from __future__ import annotations

from typing import Any

from clik.errors import InputError
from clik.tasks.com_task import ComTask
from clik.tasks.distance_task import DistanceTask
from clik.tasks.gaze_task import GazeTask
from clik.tasks.kind import BaseTask
from clik.tasks.posture_task import PostureTask
from clik.tasks.relative_task import RelativeTask
from clik.tasks.task import Task

TASK_KINDS: tuple[type[BaseTask], ...] = (
    Task,
    RelativeTask,
    PostureTask,
    ComTask,
    DistanceTask,
    GazeTask,
)
"""Every kind of task (a :class:`~clik.tasks.relative_task.RelativeTask` is read from a
frame task's table with ``relative_to``: it names no ``[[tasks]] kind`` of its own)."""


def kind_names() -> tuple[str, ...]:
    """Every ``[[tasks]] kind`` name, in the registry's order."""
    return tuple(name for cls in TASK_KINDS for name in cls.names)


def kind_class(name: str) -> type[BaseTask]:
    """The kind whose ``[[tasks]]`` table ``kind = name`` is.

    Raises:
        InputError: No kind of that name (``kind``).
    """
    for cls in TASK_KINDS:
        if name in cls.names:
            return cls
    raise InputError("kind", "one of " + ", ".join(repr(n) for n in kind_names()), name)


def kind_of_spec(spec: dict[str, Any]) -> type[BaseTask]:
    """The kind that builds the task of a table read.

    The first kind whose :meth:`~clik.tasks.kind.BaseTask.builds` says so (a frame table
    naming ``relative_to`` builds a relative task), else the kind its name reads.
    """
    return next((cls for cls in TASK_KINDS if cls.builds(spec)), kind_class(spec["kind"]))
