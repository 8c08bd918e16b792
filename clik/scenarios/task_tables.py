"""The ``[[tasks]]`` and ``[[objectives]]`` tables: several tasks at once.

docs/method.md, "Several tasks". Each ``[[tasks]]`` table is one goal
(:class:`~clik.tasks.goal.Goal`): ``name`` and ``kind`` (required), ``priority`` (an
integer >= 1, default 1: the highest), ``gain`` (default ``[solver] gain``) and its own
``[tasks.trajectory]``. The kinds and their keys:

- ``"position"``, ``"orientation"``, ``"pose"``: ``frame`` and ``axes`` as in ``[task]``;
  ``relative_to`` makes it a relative task (the frame's pose in that frame, and the
  trajectory expressed there). ``[tasks.trajectory]`` takes the keys of
  ``[trajectory]`` (its start: the frame's pose at the start, in ``relative_to``'s axes
  for a relative task).
- ``"posture"``: ``joints`` (default: every one-DoF joint) and a joint-space
  ``[tasks.trajectory]`` (optional: default, hold the start): ``kind = "hold"`` with
  ``values`` (one value per joint; default, the start) and ``duration`` (default 0), or
  ``kind = "waypoints"`` with ``waypoints`` (the joints move from the start through
  them) and ``duration`` or ``times`` (when each is reached [s], increasing, > 0);
  ``unit`` as for ``[initial]``.
- ``"com"``: ``axes`` (default ``["x", "y", "z"]``) and a position
  ``[tasks.trajectory]`` (optional: default, hold the centre of mass of the start).

The run's *primary* task (the constraint kinds that read "the task" read it) is the
first frame task in the world (no ``relative_to``) of the highest priority.
``[[objectives]]`` (eq. (5), law (10) only): ``kind`` (``"joint_centering"``,
``"manipulability"``, ``"posture"``), ``gain`` (> 0, required), ``priority`` (the
level below which it acts; default: the lowest) and, for ``"posture"``, ``posture``
(every configuration value, ``unit`` as for ``[initial]``; default: the start).
Joint values are kept as written with their unit (converted with the robot, as
``initial.q``).
"""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path
from typing import Any

from clik.errors import ScenarioError
from clik.objectives.objective import OBJECTIVE_KINDS
from clik.scenarios.fields import UNITS, angle_scale, gain_value, strings, trajectory_table
from clik.schema import MAX_JOINT_VALUE, MIN_DURATION, Table
from clik.tasks.com_task import COM_AXES

FRAME_KINDS = ("position", "orientation", "pose")
"""Kinds of a frame task (in the world, or relative to another frame)."""
TASK_KINDS = (*FRAME_KINDS, "posture", "com")
"""Every ``[[tasks]] kind``."""
JOINT_TRAJECTORY_KINDS = ("hold", "waypoints")
"""``[tasks.trajectory] kind`` of a posture task."""


def read_tasks(tables: list[Table], folder: Path) -> list[dict[str, Any]]:
    """The ``[[tasks]]`` tables, but for their gains (:func:`finish_tasks` reads those).

    Raises:
        ScenarioError: A bad key (named), repeated names, or no frame task in the world
            at the highest priority.
    """
    tasks = [_task(t, folder) for t in tables]
    names = [t["name"] for t in tasks]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise tables[i].error("name", "a name no other task has", name)
    top = min(t["priority"] for t in tasks)
    if not any(is_world_frame(t) and t["priority"] == top for t in tasks):
        raise ScenarioError(
            tables[0].file, "tasks", f"a frame task in the world (kind position, orientation "
            f"or pose, no relative_to) at priority {top}: the run's primary task",
        )  # fmt: skip
    return tasks


def is_world_frame(task: dict[str, Any]) -> bool:
    """Whether a ``[[tasks]]`` entry is a frame task in the world (a primary candidate)."""
    return task["kind"] in FRAME_KINDS and task["relative_to"] is None


def primary(tasks: list[dict[str, Any]]) -> dict[str, Any]:
    """The primary task: the first frame task in the world of the highest priority."""
    top = min(t["priority"] for t in tasks)
    return next(t for t in tasks if is_world_frame(t) and t["priority"] == top)


def _task(t: Table, folder: Path) -> dict[str, Any]:
    kind = t.string("kind", choices=TASK_KINDS)
    out: dict[str, Any] = {
        "name": t.string("name"),
        "kind": kind,
        "priority": t.number("priority", 1, minimum=1, integer=True),
        "frame": None,
        "relative_to": None,
        "axes": None,
        "joints": None,
    }
    if not out["name"]:
        raise t.error("name", "a non-empty string", "")
    tr = t.table("trajectory", required=kind in FRAME_KINDS)
    if kind in FRAME_KINDS:
        out["frame"] = t.string("frame")
        out["relative_to"] = t.string("relative_to", None)
        out["axes"] = _axes(t)
        has_orientation = kind != "position" and (
            out["axes"] is None or any(a.startswith("r") for a in out["axes"])
        )
        out["trajectory"] = trajectory_table(tr, folder, has_orientation)
    elif kind == "posture":
        out["joints"] = _axes(t, "joints")
        out["trajectory"] = joint_trajectory(tr)
    else:
        out["axes"] = _axes(t)
        if out["axes"] is not None and (
            not set(out["axes"]) <= set(COM_AXES) or len(set(out["axes"])) != len(out["axes"])
        ):
            raise t.error("axes", f"distinct names among {list(COM_AXES)}", out["axes"])
        out["trajectory"] = trajectory_table(tr, folder, False) if tr.data else _hold_start()
    return out


def _axes(t: Table, name: str = "axes") -> list[str] | None:
    """A non-empty list of names, or None when absent (every axis, every joint)."""
    value = strings(t, name) or None
    if t.has(name) and value is None:
        raise t.error(name, f"a non-empty list of names (omit it for every {name[:-1]})", [])
    return value


def _hold_start() -> dict[str, Any]:
    """A position trajectory holding the start (a com task's default)."""
    return {"kind": "hold", "start": None, "goal": None, "duration": 0.0, "goal_rpy": None}


def joint_trajectory(tr: Table) -> dict[str, Any]:
    """A posture task's ``[tasks.trajectory]`` (an empty table: hold the start).

    Values are kept as written, with ``unit`` (revolute joints; prismatic ones in
    metres): the robot converts them.
    """
    if not tr.data:
        return {"kind": "hold", "values": None, "waypoints": None, "duration": 0.0,
                "times": None, "unit": "rad"}  # fmt: skip
    kind = tr.string("kind", choices=JOINT_TRAJECTORY_KINDS)
    unit = tr.string("unit", "rad", UNITS)
    bound = MAX_JOINT_VALUE / angle_scale(tr)
    out: dict[str, Any] = {"kind": kind, "unit": unit, "values": None, "waypoints": None}
    if kind == "hold":
        out["values"] = tr.vector("values", None, None, bound=bound)
        out["duration"] = tr.number("duration", 0.0, minimum=0.0, unit="[s]")
        out["times"] = None
    else:
        out["waypoints"] = _rows(tr, "waypoints", bound)
        _timing(tr, out)
    tr.done()
    return out


def _rows(tr: Table, name: str, bound: float) -> list[list[float]]:
    """A non-empty list of joint vectors, all of one length."""
    value = tr.raw(name)
    if not isinstance(value, list) or not value or not isinstance(value[0], list):
        raise tr.error(name, "a non-empty list of joint vectors [[...], ...]", value)
    size = len(value[0])
    rows = Table({f"{name}[{i}]": row for i, row in enumerate(value)}, tr.file, tr.path)
    return [rows.vector(f"{name}[{i}]", size, bound=bound) for i in range(len(value))]


def _timing(tr: Table, out: dict[str, Any]) -> None:
    """``duration`` or ``times`` of posture waypoints (the start at t = 0)."""
    k = len(out["waypoints"])
    if tr.has("times") == tr.has("duration"):
        raise tr.error("duration", "a duration [s] or times (one per waypoint), not both")
    if tr.has("times"):
        times = tr.vector("times", k, unit="[s]")
        if times[0] < MIN_DURATION or any(b <= a for a, b in pairwise(times)):
            raise tr.error("times", f"{k} increasing times > 0 [s] (the start is at t = 0)", times)
        out["times"], out["duration"] = times, times[-1]
    else:
        out["duration"] = tr.number("duration", minimum=MIN_DURATION, unit="[s]")
        out["times"] = None


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
        if kind == "posture":
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
