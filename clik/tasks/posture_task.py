r"""The posture task: chosen joints follow a joint-space reference ``q_d(t)``.

docs/method.md, "Several tasks". Each row is one joint: its error is
``e_i = q_{d,i} - q_i`` [rad or m] (a continuous joint's angle difference wrapped
into ``[-pi, pi)``), its Jacobian row the unit row of the joint's velocity, and its
feed-forward ``qdot_{d,i}``. At a lower priority than the hands it chooses the
redundant arm's free motion (the elbow); at the same priority it is a soft pull,
weighted by its gain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.errors import InputError
from clik.model.joints import CONTINUOUS, PRISMATIC, REVOLUTE, unit_scale
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import ValuesTarget
from clik.trajectory.tables import joint_path, joint_trajectory_table, strings

if TYPE_CHECKING:
    from pathlib import Path

    import pinocchio as pin

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory


class PostureTask(BaseTask):
    """Joints ``joints`` (default: every one-DoF joint) follow a joint-space reference.

    Args:
        robot: The robot.
        joints: Names of the joints (one-DoF: revolute, prismatic or continuous);
            None: all of them.

    Raises:
        InputError: No joint, a repeated joint, or a joint of several DoF.
        JointNotFound: No such joint.

    Attributes:
        joints: The joints' names, in row order.
        idx_q, idx_v: Their configuration and velocity indices.
        continuous: Whether each is continuous (``(cos, sin)`` in ``q``).
    """

    names = ("posture",)
    table_keys = "`joints` (default: every one-DoF joint)"
    table_trajectory = "a joint path (optional: hold the start), below"
    kind = "posture"

    def __init__(self, robot: Robot, joints: Sequence[str] | None = None) -> None:
        robot.check_model()
        kinds = robot.joint_kinds
        if joints is None:
            joints = [n for n, k in kinds.items() if k in (REVOLUTE, PRISMATIC, CONTINUOUS)]
        if isinstance(joints, str) or len(joints) == 0:
            raise InputError("task.joints", "a non-empty list of joint names", joints)
        if len(set(joints)) != len(joints):
            raise InputError("task.joints", "distinct joint names", list(joints))
        idx_q, idx_v, continuous = [], [], []
        for name in joints:
            joint = robot.model.joints[robot.joint_id(name)]
            if kinds[name] not in (REVOLUTE, PRISMATIC, CONTINUOUS):
                raise InputError(
                    "task.joints", "one-DoF joints (revolute, prismatic, continuous)", name
                )
            idx_q.append(joint.idx_q)
            idx_v.append(joint.idx_v)
            continuous.append(kinds[name] == CONTINUOUS)
        self.robot = robot
        self.joints = list(joints)
        self.idx_q = np.asarray(idx_q, dtype=np.intp)
        self.idx_v = np.asarray(idx_v, dtype=np.intp)
        self.continuous = np.asarray(continuous, dtype=bool)
        self.m = len(joints)
        self.reference_size = self.m

    @property
    def axes(self) -> list[str]:
        """The joints' names."""
        return list(self.joints)

    def tick_target(self) -> ValuesTarget:
        """The joints' values (m,) and velocities (:mod:`clik.tasks.targets`)."""
        return ValuesTarget(self.m)

    def __repr__(self) -> str:
        return f"PostureTask(joints={self.joints})"

    def describe(self) -> str:
        """``"posture of 7 joints"``."""
        return f"posture of {self.m} joint{'s' if self.m > 1 else ''}"

    def angles(self, q: np.ndarray) -> np.ndarray:
        """The joints' values at ``q`` (m,) [rad or m] (a continuous joint's angle)."""
        q = np.asarray(q, dtype=float)
        out = q[self.idx_q].copy()
        c = self.continuous
        if c.any():
            out[c] = np.arctan2(q[self.idx_q[c] + 1], q[self.idx_q[c]])
        return out

    # -- the scenario: [[tasks]] kind = "posture" ----------------------------------------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """``joints`` (default every one-DoF joint) and a joint-space ``[tasks.trajectory]``.

        The trajectory (optional: default, hold the start) takes
        :func:`clik.trajectory.tables.joint_trajectory_table`'s keys: a hold of ``values``,
        or ``waypoints`` with ``duration`` or ``times``, ``unit`` as for ``[initial]``.
        """
        joints = strings(t, "joints") or None
        if t.has("joints") and joints is None:
            raise t.error("joints", "a non-empty list of names (omit it for every joint)", [])
        return {"joints": joints, "trajectory": joint_trajectory_table(t.table("trajectory"))}

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The posture of the table's joints."""
        return cls(robot, spec["joints"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The table's joint path from the joints' values at ``q0``.

        Values written in degrees are converted per joint: revolute and continuous joints
        by ``unit``, prismatic ones kept in metres.
        """
        kinds, angle = self.robot.joint_kinds, unit_scale(spec["unit"], "unit")
        scale = np.array([1.0 if kinds[j] == PRISMATIC else angle for j in self.joints])
        return joint_path(spec, self.angles(q0), scale, self.joints)

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """The joints' error: [rad], [m] for prismatic joints only, else ``"rad, m"``."""
        prismatic = {self.robot.joint_kinds[j] == PRISMATIC for j in self.joints}
        unit = "rad, m" if len(prismatic) > 1 else ("m" if True in prismatic else "rad")
        return Norm("joints' error", unit), None

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """Joint values (n, m) and velocities (n, m) from a joint-space trajectory's samples.

        Raises:
            InputError: Not a joint-space reference of this task's joints.
        """
        values = getattr(ref, "q", None)
        if values is None:
            raise InputError(
                "trajectory",
                "a joint-space trajectory (clik.trajectory.JointPath) for the posture task",
            )
        if values.shape[1] != self.m:
            raise InputError(
                "trajectory", f"{self.m} joint values per sample (the posture task's joints)",
                f"{values.shape[1]}",
            )  # fmt: skip
        return np.ascontiguousarray(values), np.ascontiguousarray(ref.qdot)

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """``e = q_d - q`` (wrapped for continuous joints), unit rows, the feed-forward."""
        xdot[:] = ff
        np.subtract(ref, self.angles(q), out=e)
        c = self.continuous
        if c.any():
            e[c] = np.remainder(e[c] + math.pi, 2.0 * math.pi) - math.pi
        J[:] = 0.0
        J[np.arange(self.m), self.idx_v] = 1.0

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """The joints' error norm [rad or m], and 0."""
        return float(np.linalg.norm(e)), 0.0

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.PostureGoal``."""
        return engine.PostureGoal(
            idx_q=[int(i) for i in self.idx_q], idx_v=[int(i) for i in self.idx_v],
            continuous=[bool(c) for c in self.continuous],
        )  # fmt: skip
