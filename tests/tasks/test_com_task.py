"""The centre-of-mass task: its case for the generic tests of every kind."""

from __future__ import annotations

from clik.tasks.com_task import ComTask
from clik.trajectory import Line
from tests.tasks.kind_case import Q0, Case, linear, panda, point_forms


def case() -> Case:
    """The centre of mass's x and y moving 1 cm."""
    robot = panda()
    task = ComTask(robot, ["x", "y"])
    c0 = task.position(Q0)  # type: ignore[attr-defined]
    traj = Line(c0, c0 + [0.01, 0.0, 0.0], 0.3)
    table = 'kind = "com"\naxes = ["x", "y"]'
    return Case(
        task,
        traj,
        table,
        {"axes": ["w"]},
        point_forms,
        linear,
        task.position,  # type: ignore[attr-defined]
    )
