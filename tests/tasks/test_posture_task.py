"""The posture task: its case for the generic tests of every kind."""

from __future__ import annotations

from clik.tasks.posture_task import PostureTask
from clik.trajectory import JointPath
from tests.tasks.kind_case import Q0, Case, panda


def case() -> Case:
    """Joints 1 and 7 turning by 0.05 rad."""
    robot = panda()
    task = PostureTask(robot, ["panda_joint1", "panda_joint7"])
    start_q = task.angles(Q0)  # type: ignore[attr-defined]
    traj = JointPath([start_q, start_q + 0.05], duration=0.3)
    table = 'kind = "posture"\njoints = ["panda_joint1", "panda_joint7"]'
    return Case(
        task, traj, table, {"joints": "panda_joint1"}, lambda r: [r.copy(), r.tolist()],
        lambda s, k: s.qdot[k], task.angles,  # type: ignore[attr-defined]
    )  # fmt: skip
