"""The relative frame task (``relative_to``): its case for the generic tests of every kind."""

from __future__ import annotations

from clik.tasks.relative_task import RelativeTask
from clik.trajectory import Line
from tests.tasks.kind_case import Q0, Case, linear, panda, point_forms, pose_row


def case() -> Case:
    """The hand's position relative to link 3 moving 1 cm."""
    robot = panda()
    task = RelativeTask(robot, "panda_hand", "panda_link3", "position")
    start = task.placement(Q0)  # type: ignore[attr-defined]
    traj = Line(start.translation, start.translation + [0.0, 0.01, 0.0], 0.3)
    table = (
        'kind = "position"\nframe = "panda_hand"\nrelative_to = "panda_link3"\n'
        '[tasks.trajectory]\nkind = "hold"\nduration = 0.3'
    )
    return Case(
        task, traj, table, {"relative_to": 1}, point_forms, linear,
        lambda q: pose_row(task.placement(q)),  # type: ignore[attr-defined]
    )  # fmt: skip
