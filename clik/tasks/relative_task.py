r"""The relative frame task: frame A's pose in frame B (docs/method.md, "Several tasks").

Two hands holding a box keep the box's width (the left hand's position in the right
hand's frame); a tool keeps its pose relative to a part held by the other arm.

With ``oMa``, ``oMb`` the world placements of A and B, the task's pose is
``bMa = oMb^-1 oMa``: ``p = R_b^T (p_a - p_b)``, ``R = R_b^T R_a``. The error (6) is
``(p_d - p, log3(R_d R^T))`` in B's axes, and the Jacobian (3) of those rows, from the
``LOCAL_WORLD_ALIGNED`` Jacobians of A and B (linear rows at their origins), is

.. math::

    J_v = R_b^T \big(J_{v,a} - J_{v,b} + [p_a - p_b]_\times J_{\omega,b}\big), \qquad
    J_\omega = R_b^T (J_{\omega,a} - J_{\omega,b}),

the derivative of ``p`` and the angular velocity of A relative to B, both in B's axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import FrameTarget
from clik.tasks.task import (
    AXES,
    Task,
    TaskKind,
    frame_error,
    frame_norms,
    pose_reference_arrays,
    split_norms,
)
from clik.trajectory.tables import build_trajectory

if TYPE_CHECKING:
    from pathlib import Path

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory

LWA = pin.LOCAL_WORLD_ALIGNED


class RelativeTask(BaseTask):
    """A position, orientation or pose task on frame ``frame`` expressed in ``relative_to``.

    Args:
        robot: The robot.
        frame: Frame A, whose pose is tracked.
        relative_to: Frame B, in which A's pose (and the trajectory) is expressed.
        kind: ``"position"``, ``"orientation"`` or ``"pose"``.
        axes: Optional subset of the kind's components (in B's axes).

    Raises:
        InputError: A bad kind or axes, or the same frame twice.
        FrameNotFound: No such frame.

    Attributes:
        relative_to: Frame B's name.
        relative_id: Its Pinocchio index.
    """

    def __init__(
        self,
        robot: Robot,
        frame: str,
        relative_to: str,
        kind: TaskKind = "pose",
        axes: Sequence[str] | None = None,
    ) -> None:
        world = Task(robot, frame, kind, axes)  # the same frame in the world: checks all
        self.robot, self.frame, self.frame_id = robot, frame, world.frame_id
        self.relative_id = robot.frame_id(relative_to)
        if self.relative_id == self.frame_id:
            raise InputError("task.relative_to", f"a frame other than {frame!r}", relative_to)
        self.relative_to = relative_to
        self.kind: TaskKind = world.kind
        self.rows, self.m = world.rows, world.m
        self.has_position, self.has_orientation = world.has_position, world.has_orientation

    reference_size = 12
    """A pose of A in B per sample: the position (3) [m], then the rotation, row-major (9)."""

    # -- the scenario: a frame task's table with relative_to (Task.read_table) ----------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """A frame task's table (:meth:`Task.read_table`), its ``relative_to`` required."""
        out = Task.read_table(t, folder)
        if out["relative_to"] is None:
            raise t.error("relative_to", "the frame the pose is expressed in")
        return out

    @classmethod
    def builds(cls, spec: dict[str, Any]) -> bool:
        """A frame task's table naming ``relative_to``."""
        return spec["kind"] in Task.names and spec.get("relative_to") is not None

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The relative task of a frame task's table with ``relative_to``."""
        return cls(robot, spec["frame"], spec["relative_to"], spec["kind"], spec["axes"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The table's trajectory from A's pose in B at ``q0`` (in B's axes)."""
        return build_trajectory(spec, self.placement(q0), self.has_position, self.has_orientation)

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """Position [m] and orientation [rad] errors of A in B (the one it has)."""
        return frame_norms(self.has_position, self.has_orientation)

    def trail(
        self, model: pin.Model, data: pin.Data, ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """A's origin and its reference position, placed by B's pose (world) [m]."""
        reference = data.oMf[self.relative_id].act(ref[:3]) if self.has_position else None
        return data.oMf[self.frame_id].translation.copy(), reference

    @property
    def axes(self) -> list[str]:
        """Names of the kept components (in B's axes), in row order."""
        return [AXES[i] for i in self.rows]

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """Poses of A in B (n, 12) and the rows' velocities (n, m), from a trajectory."""
        return pose_reference_arrays(self, ref)

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """Norms of the position rows [m] and orientation rows [rad]."""
        return split_norms(self.rows, e)

    def tick_target(self) -> FrameTarget:
        """A's pose (position, rotation) in B, and its velocity (:mod:`clik.tasks.targets`)."""
        return FrameTarget(
            self.has_position, self.has_orientation, tuple(int(r) for r in self.rows)
        )

    def __repr__(self) -> str:
        return (
            f"RelativeTask(frame={self.frame!r}, relative_to={self.relative_to!r}, "
            f"kind={self.kind!r}, axes={self.axes})"
        )

    def describe(self) -> str:
        """``"pose of frame 'left_hand' in frame 'right_hand'"``."""
        return f"{self.kind} of frame {self.frame!r} in frame {self.relative_to!r}"

    def placement(self, q: np.ndarray) -> pin.SE3:
        """A's placement in B at ``q``, ``oMb^-1 oMa`` (runs forward kinematics)."""
        robot = self.robot
        robot.check_model(full=False)
        data = robot.thread_data()
        pin.framesForwardKinematics(robot.model, data, q)
        return data.oMf[self.relative_id].actInv(data.oMf[self.frame_id])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Masked Jacobian (m, nv) of A's pose in B at ``q`` (the module's equations)."""
        robot = self.robot
        data = robot.thread_data()
        pin.computeJointJacobians(robot.model, data, q)
        pin.updateFramePlacements(robot.model, data)
        return relative_jacobian(robot.model, data, self.frame_id, self.relative_id)[self.rows]

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """Error ``(p_d - p, log3(R_d R^T))`` of A's pose in B, its Jacobian rows, feed-forward."""
        xdot[:] = ff
        oMa = pin.updateFramePlacement(model, data, self.frame_id)
        oMb = pin.updateFramePlacement(model, data, self.relative_id)
        e6 = frame_error(
            oMb.actInv(oMa),
            ref[:3] if self.has_position else None,
            ref[3:].reshape(3, 3) if self.has_orientation else None,
        )
        np.take(e6, self.rows, out=e)
        J6 = relative_jacobian(model, data, self.frame_id, self.relative_id)
        np.take(J6, self.rows, axis=0, out=J)

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.FrameGoal`` relative to B."""
        return engine.FrameGoal(
            frame=int(self.frame_id), rows=[int(r) for r in self.rows],
            relative_to=int(self.relative_id),
        )  # fmt: skip


def relative_jacobian(model: pin.Model, data: pin.Data, a: int, b: int) -> np.ndarray:
    """The (6, nv) Jacobian of frame ``a``'s pose in frame ``b`` (the module's equations).

    ``data`` holds every joint's Jacobian and both frames' placements.
    """
    Ja = pin.getFrameJacobian(model, data, a, LWA)
    Jb = pin.getFrameJacobian(model, data, b, LWA)
    oMa, oMb = data.oMf[a], data.oMf[b]
    Rt = oMb.rotation.T
    out = np.empty_like(Ja)
    lin = Ja[:3] - Jb[:3] + pin.skew(oMa.translation - oMb.translation).dot(Jb[3:])
    out[:3] = Rt.dot(lin)
    out[3:] = Rt.dot(Ja[3:] - Jb[3:])
    return out
