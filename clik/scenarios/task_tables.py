"""The ``[[tasks]]`` and ``[[objectives]]`` tables: several tasks at once.

docs/method.md, "Several tasks". Each ``[[tasks]]`` table is one goal
(:class:`~clik.tasks.goal.Goal`): ``name`` and ``kind`` (required), ``priority`` (an
integer >= 1, default 1: the highest), ``gain`` (default ``[solver] gain``), and the
keys of its kind with its own ``[tasks.trajectory]``, read by the kind
(:meth:`~clik.tasks.kind.BaseTask.read_table`; the kinds: :mod:`clik.tasks.registry`,
their keys: docs/guides/scenarios.md).

The run's *primary* task (the constraint kinds that read "the task" read it) is the
first task of the highest priority that may lead (a frame task in the world).
``[[objectives]]`` (eq. (5), law (10) only): ``kind`` (``"joint_centering"``,
``"manipulability"``, ``"posture"``), ``gain`` (> 0, required), ``priority`` (the
level below which it acts; default: the lowest) and, for ``"posture"``, ``posture``
(every configuration value, ``unit`` as for ``[initial]``; default: the start).
Joint values are kept as written with their unit (converted with the robot, as
``initial.q``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from clik.errors import ScenarioError
from clik.objectives.objective import OBJECTIVE_KINDS, POSTURE
from clik.scenarios.fields import gain_value
from clik.schema import MAX_JOINT_VALUE, Table
from clik.tasks.registry import kind_class, kind_names
from clik.trajectory.tables import UNITS, angle_scale


def read_tasks(tables: list[Table], folder: Path) -> list[dict[str, Any]]:
    """The ``[[tasks]]`` tables, but for their gains (:func:`finish_tasks` reads those).

    Raises:
        ScenarioError: A bad key (named), repeated names, or no task that may lead (a
            frame task in the world) at the highest priority.
    """
    tasks = [_task(t, folder) for t in tables]
    names = [t["name"] for t in tasks]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise tables[i].error("name", "a name no other task has", name)
    top = min(t["priority"] for t in tasks)
    if not any(leads(t) and t["priority"] == top for t in tasks):
        raise ScenarioError(
            tables[0].file, "tasks", f"a frame task in the world (kind position, orientation "
            f"or pose, no relative_to) at priority {top}: the run's primary task",
        )  # fmt: skip
    return tasks


def leads(task: dict[str, Any]) -> bool:
    """Whether a ``[[tasks]]`` entry may be the run's primary task (its kind says)."""
    return kind_class(task["kind"]).leads_spec(task)


def primary(tasks: list[dict[str, Any]]) -> dict[str, Any]:
    """The primary task: the first that may lead, of the highest priority."""
    top = min(t["priority"] for t in tasks)
    return next(t for t in tasks if leads(t) and t["priority"] == top)


def _task(t: Table, folder: Path) -> dict[str, Any]:
    kind = t.string("kind", choices=kind_names())
    out: dict[str, Any] = {
        "name": t.string("name"),
        "kind": kind,
        "priority": t.number("priority", 1, minimum=1, integer=True),
    }
    if not out["name"]:
        raise t.error("name", "a non-empty string", "")
    out.update(kind_class(kind).read_table(t, folder))
    return out


def finish_tasks(tables: list[Table], tasks: list[dict[str, Any]], solver: dict[str, Any]) -> None:
    """Read the tasks' gains (``gain * solver.dt`` bounded), refuse unknown keys, check the law.

    Laws (9) and (8) stack every task in one level, weighted by its gain: several
    priorities need law (10) (``"pseudoinverse"``).
    """
    for t, task in zip(tables, tasks, strict=True):
        task["gain"] = gain_value(t, "gain", solver["dt"])
        t.done()
    top = min(task["priority"] for task in tasks)
    law = solver["law"]
    for t, task in zip(tables, tasks, strict=True):
        if law != "pseudoinverse" and task["priority"] != top:
            raise t.error(
                "priority", f"{top}, the other tasks' priority, with solver.law = {law!r} (it "
                "stacks every task in one level; priority levels need law 'pseudoinverse')",
                task["priority"],
            )  # fmt: skip


def read_objectives(tables: list[Table], law: str) -> list[dict[str, Any]]:
    """The ``[[objectives]]`` tables (eq. (5)); none unless ``law`` is ``"pseudoinverse"``."""
    out = []
    for t in tables:
        kind = t.string("kind", choices=OBJECTIVE_KINDS)
        objective = {
            "kind": kind,
            "gain": float(t.number("gain", minimum=0.0, strict=True)),
            "priority": t.number("priority", None, minimum=1, integer=True),
            "posture": None,
            "unit": "rad",
        }
        if kind == POSTURE:
            objective["unit"] = t.string("unit", "rad", UNITS)
            bound = MAX_JOINT_VALUE / angle_scale(t)
            objective["posture"] = t.vector("posture", None, None, bound=bound)
        t.done()
        if law != "pseudoinverse":
            raise ScenarioError(
                t.file, t.path, f"no objective with solver.law = {law!r}: eq. (5)'s null "
                "space needs law 'pseudoinverse' (10)",
            )  # fmt: skip
        out.append(objective)
    return out
