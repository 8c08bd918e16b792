r"""Is a configuration clear of its constraints? Checked directly, with coal and the joint values.

A configuration ``q`` *satisfies* a :class:`~clik.constraints.ConstraintSet` when

- every monitored link is at a distance ``d >= d_o`` from every obstacle, ``d_o`` that
  obstacle's threshold: the error (13) (normalised form ``e_o = d_o - d``) is not positive;
- with self-collision rows, every checked link pair is at least its threshold apart;
- every joint is inside the robot's limits and, with joint-range rows (16)-(19), at
  least ``d_q`` from each limit of the constraint (the tighter of the robot's and the
  override): the error (17) ``e_q = d_q - d`` is not positive;
- with a dexterity row, the task's manipulability is at least ``w_min`` (D1)-(D2);
- and so for every kind of the set: each kind checks its own rows' errors.

Distances are computed by coal (``pinocchio.computeDistances``) on the constraint set's
own link geometry, the convex hulls of the links' collision meshes: a hull contains its
mesh, so a hull at ``d >= d_o`` puts the mesh at least as far. Nothing here trusts a
run's status or its recorded distances: :func:`clik.solve` calls :meth:`PoseCheck.violations`
on the pose it returns.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.collision_scene import GJK_TOLERANCE
from clik.constraints.kind import CHECK_TOLERANCE, Violation
from clik.model.joints import PRISMATIC, REVOLUTE, joint_kind

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.tasks.task import Task


def constraint_label(key: str) -> str:
    """A constraint row's key (``obstacle:table:panda_link7``, ``joint:j4:lower``) in words."""
    kind, _, rest = key.partition(":")
    name, _, part = rest.rpartition(":")
    if kind == "obstacle" and name:
        return f"obstacle {name!r} (link {part})"
    if kind == "joint" and name:
        return f"joint range of {name} ({part} limit)"
    return key


LWA = pin.LOCAL_WORLD_ALIGNED


class PoseCheck:
    """Checks configurations against one constraint set (its own Pinocchio and coal data).

    One checker serves one solve at a time (a solve takes its prepared checker out of
    the cache while it runs); the set, robot and task are only read.

    The robot's own joint limits are checked here; every kind of the set checks its own
    constraints (:meth:`~clik.constraints.kind.ConstraintKind.check`), reading the
    distances and the task Jacobian this checker computes once per configuration.

    Args:
        cset: The constraints. Its obstacles must be at rest (solve mode has no time).
        task: The task (kinds that check the task's rows need it: dexterity), or None.
    """

    def __init__(self, cset: ConstraintSet, task: Task | None = None) -> None:
        self.cset, self.task = cset, task
        robot = cset.robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.scene = cset.scene
        self.gdata = None if self.scene is None else pin.GeometryData(self.scene.gmodel)
        if self.gdata is not None:
            for request in self.gdata.distanceRequests:
                request.gjk_tolerance = GJK_TOLERANCE
                request.epa_tolerance = GJK_TOLERANCE
        self.limited = [
            (name, joint.idx_q)
            for name, joint in zip(robot.joint_names, robot.model.joints[1:], strict=True)
            if joint_kind(joint) in (REVOLUTE, PRISMATIC)
            and math.isfinite(robot.lower[joint.idx_q])
            and math.isfinite(robot.upper[joint.idx_q])
        ]
        self.lower, self.upper = robot.lower, robot.upper
        self._measured: bytes | None = None

    def violations(self, q: np.ndarray) -> list[Violation]:
        """Every constraint ``q`` does not satisfy, the largest shortfall first."""
        self._measured = None
        found = self._robot_limits(q)
        for kind in self.cset.kinds:
            found += kind.check(self, q)
        return sorted(found, key=lambda v: -v.shortfall)

    def worst(self, q: np.ndarray) -> Violation | None:
        """The constraint ``q`` misses by most, or None when ``q`` satisfies them all."""
        found = self.violations(q)
        return found[0] if found else None

    def distances(self, q: np.ndarray) -> Any:
        """Coal's distance results of every pair of the scene at ``q`` (computed once per q)."""
        assert self.scene is not None and self.gdata is not None
        key = np.asarray(q, dtype=float).tobytes()
        if self._measured != key:
            pin.computeDistances(self.model, self.data, self.scene.gmodel, self.gdata, q)
            self._measured = key
        return self.gdata.distanceResults

    def frame_placement(self, q: np.ndarray, frame_id: int) -> pin.SE3:
        """A frame's placement in the world at ``q`` (this checker's own data)."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return self.data.oMf[frame_id]

    def task_jacobian(self, q: np.ndarray) -> np.ndarray | None:
        """The task's Jacobian (m, nv) at ``q`` (3), or None without a task (own data)."""
        task = self.task
        if task is None:
            return None
        J6 = pin.computeFrameJacobian(self.model, self.data, q, task.frame_id, LWA)
        return J6[task.rows]

    def _robot_limits(self, q: np.ndarray) -> list[Violation]:
        """Joints outside the robot's own limits."""
        out: list[Violation] = []
        for name, i in self.limited:
            below, above = self.lower[i] - q[i], q[i] - self.upper[i]
            if max(below, above) > CHECK_TOLERANCE:
                side, limit = ("lower", self.lower[i]) if below > 0 else ("upper", self.upper[i])
                detail = f"{name} = {q[i]:.6g} beyond its {side} limit {limit:.6g}"
                out.append(Violation(f"joint range of {name}", detail, float(max(below, above))))
        return out
