"""The task: where a frame of the robot must be, as rows of the task vector.

The full task of a frame is six components, ``(x, y, z, rx, ry, rz)``: the
frame origin's position in the world frame and its orientation. A task keeps
a subset of them (its *mask*), so a planar arm tracks ``(x, y)`` and a tool
may track its position plus one axis of orientation.

Convention (one for the whole package, ``LOCAL_WORLD_ALIGNED``): velocities
and Jacobian rows are expressed in the world frame at the frame's origin.

- Position error (docs/method.md, ``e = x_d - x``): ``e_p = p_d - p`` [m].
- Orientation error: ``e_r = log3(R_d R^T)`` [rad], the rotation vector, in
  the world frame, that turns the current orientation ``R`` into ``R_d``.
  Its time derivative is ``omega_d - omega`` to first order in ``|e_r|``, so
  the task Jacobian of eq. (3) is the frame's geometric Jacobian
  ``J = (J_v; J_omega)``, masked to the task's rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import FrameTarget
from clik.trajectory.tables import build_trajectory, strings, trajectory_table

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory

TaskKind = Literal["position", "orientation", "pose"]

POSITION_ERROR = Norm("position error", "m")
ORIENTATION_ERROR = Norm("orientation error", "rad")

AXES: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
"""Names of the six components of a frame task, in row order."""

_KIND_AXES: dict[str, tuple[int, ...]] = {
    "position": (0, 1, 2),
    "orientation": (3, 4, 5),
    "pose": (0, 1, 2, 3, 4, 5),
}


def frame_rows(kind: str, axes: Sequence[str] | None) -> tuple[int, ...]:
    """The rows among ``(x, y, z, rx, ry, rz)`` a frame task of ``kind`` keeps.

    Raises:
        InputError: A bad kind, or axes not among the kind's (named).
    """
    if kind not in _KIND_AXES:
        raise InputError("task.kind", "one of 'position', 'orientation', 'pose'", kind)
    allowed = _KIND_AXES[kind]
    if axes is None:
        return allowed
    if isinstance(axes, str) or len(axes) == 0:
        raise InputError("task.axes", "a non-empty list of axis names", axes)
    valid = [AXES[i] for i in allowed]
    bad = [a for a in axes if a not in valid]
    if bad or len(set(axes)) != len(axes):
        raise InputError("task.axes", f"distinct names among {valid} for a {kind} task", list(axes))
    return tuple(sorted(AXES.index(a) for a in axes))


def frame_table(t: Table) -> dict[str, Any]:
    """A frame task's keys (``frame``, ``kind``, ``axes``) of a ``[task]`` or ``[[tasks]]`` table.

    The axes are checked against the kind.

    Raises:
        ScenarioError: A bad key (named).
    """
    out = {
        "frame": t.string("frame"),
        "kind": t.string("kind", "pose", tuple(_KIND_AXES)),
        "axes": strings(t, "axes") or None,
    }
    if t.has("axes") and out["axes"] is None:
        raise t.error("axes", "a non-empty list of axis names (omit it for every axis)", [])
    try:
        frame_rows(out["kind"], out["axes"])
    except InputError as exc:
        raise t.error("axes", exc.expected, exc.got) from None
    return out


def has_orientation_rows(kind: str, axes: Sequence[str] | None) -> bool:
    """Whether a frame task of ``kind`` on ``axes`` has orientation rows."""
    return any(row >= 3 for row in frame_rows(kind, axes))


def frame_norms(has_position: bool, has_orientation: bool) -> tuple[Norm, Norm | None]:
    """A frame task's norms: position [m] and orientation [rad], or the one it has."""
    if not has_position:
        return ORIENTATION_ERROR, None
    return POSITION_ERROR, ORIENTATION_ERROR if has_orientation else None


class Task(BaseTask):
    """A position, orientation or pose task on one frame, with a component mask.

    Args:
        robot: The robot whose frame is tracked.
        frame: Name of the frame (see ``robot.frame_names``).
        kind: ``"position"`` (3 rows), ``"orientation"`` (3 rows) or ``"pose"`` (6 rows).
        axes: Optional subset of the kind's components, among
            ``"x", "y", "z", "rx", "ry", "rz"`` (e.g. ``["x", "y"]`` for a planar arm).

    Raises:
        InputError: A bad kind or axes; or the robot's model changed after loading.
        FrameNotFound: No such frame.

    A task is only read by runs and solves: it may serve several threads at once.

    Attributes:
        frame: Frame name.
        frame_id: Pinocchio frame index.
        kind: Task kind.
        rows: Indices of the kept components in the six-vector ``(x, y, z, rx, ry, rz)``.
        m: Task dimension, ``len(rows)``.
    """

    names = ("position", "orientation", "pose")
    leads = True
    table_keys = '`frame`, `axes`; `relative_to = "other_frame"`: the frame\'s pose in that frame'
    table_trajectory = "the keys of `[trajectory]` (required), in `relative_to`'s axes"
    reference_size = 12
    """A pose per sample: the position (3) [m], then the rotation, row-major (9)."""

    def __init__(
        self,
        robot: Robot,
        frame: str,
        kind: TaskKind = "pose",
        axes: Sequence[str] | None = None,
    ) -> None:
        rows = frame_rows(kind, axes)
        robot.check_model()
        self.robot = robot
        self.frame = frame
        self.frame_id = robot.frame_id(frame)
        self.kind: TaskKind = kind
        self.rows = np.asarray(rows, dtype=np.intp)
        self.m = len(rows)
        self.has_position = bool(np.any(self.rows < 3))
        self.has_orientation = bool(np.any(self.rows >= 3))
        # Contiguous masks are slices (views, no copy in the hot loop).
        self._slice = (
            slice(rows[0], rows[-1] + 1) if rows == tuple(range(rows[0], rows[-1] + 1)) else None
        )

    @property
    def axes(self) -> list[str]:
        """Names of the kept components, in row order."""
        return [AXES[i] for i in self.rows]

    def tick_target(self) -> FrameTarget:
        """A pose, a position or a rotation, and its velocity (:mod:`clik.tasks.targets`)."""
        return FrameTarget(
            self.has_position, self.has_orientation, tuple(int(r) for r in self.rows)
        )

    # -- the scenario: [[tasks]] kind = "position" | "orientation" | "pose" --------------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """``frame``, ``axes``, ``relative_to`` and a ``[tasks.trajectory]`` (required).

        ``relative_to`` makes it the frame's pose in that frame (a
        :class:`~clik.tasks.relative_task.RelativeTask`); the trajectory takes the keys of
        :func:`clik.trajectory.tables.trajectory_table`.
        """
        out = frame_table(t)
        out["relative_to"] = t.string("relative_to", None)
        has_orientation = has_orientation_rows(out["kind"], out["axes"])
        out["trajectory"] = trajectory_table(t.table("trajectory", True), folder, has_orientation)
        return out

    @classmethod
    def leads_spec(cls, spec: dict[str, Any]) -> bool:
        """A frame task in the world (no ``relative_to``)."""
        return spec.get("relative_to") is None

    @classmethod
    def builds(cls, spec: dict[str, Any]) -> bool:
        """A frame table without ``relative_to`` (with it: a relative task's)."""
        return spec["kind"] in cls.names and spec.get("relative_to") is None

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """A :class:`Task` of the frame in the world."""
        return cls(robot, spec["frame"], spec["kind"], spec["axes"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The table's trajectory from the frame's pose at ``q0``."""
        return build_trajectory(spec, self.placement(q0), self.has_position, self.has_orientation)

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """Position [m] and orientation [rad] errors (the one it has)."""
        return frame_norms(self.has_position, self.has_orientation)

    def __repr__(self) -> str:
        return f"Task(frame={self.frame!r}, kind={self.kind!r}, axes={self.axes})"

    # -- evaluation (used by the tracking loop and by tests) ---------------------------

    def placement(self, q: np.ndarray) -> pin.SE3:
        """Frame placement in the world at ``q`` (runs forward kinematics).

        This and :meth:`jacobian` compute in the calling thread's own data
        (:meth:`~clik.model.robot.Robot.thread_data`): a task may be shared by threads.
        """
        robot = self.robot
        robot.check_model(full=False)
        data = robot.thread_data()
        pin.framesForwardKinematics(robot.model, data, q)
        return data.oMf[self.frame_id].copy()

    def full_error(
        self, placement: pin.SE3, position_d: np.ndarray | None, rotation_d: np.ndarray | None
    ) -> np.ndarray:
        """Six-vector error ``(p_d - p, log3(R_d R^T))``; missing references give zero rows."""
        return frame_error(placement, position_d, rotation_d)

    def error(
        self, q: np.ndarray, position_d: np.ndarray | None, rotation_d: np.ndarray | None
    ) -> np.ndarray:
        """Masked task error ``e`` (m,) at ``q``: [m] for position rows, [rad] for orientation."""
        return self.full_error(self.placement(q), position_d, rotation_d)[self.rows]

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Masked task Jacobian ``J`` (m, nv) at ``q``, eq. (3), ``LOCAL_WORLD_ALIGNED``."""
        robot = self.robot
        robot.check_model(full=False)
        J6 = pin.computeFrameJacobian(
            robot.model, robot.thread_data(), q, self.frame_id, pin.LOCAL_WORLD_ALIGNED
        )
        return J6[self.rows]

    # -- as one of several tasks (clik.tasks.kind) ---------------------------------------

    def describe(self) -> str:
        """``"pose of frame 'tool'"``."""
        return f"{self.kind} of frame {self.frame!r}"

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """Poses (n, 12) and the rows' velocities (n, m) from a trajectory's samples."""
        return pose_reference_arrays(self, ref)

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """Error (6) ``(p_d - p, log3(R_d R^T))``, Jacobian (3) rows and feed-forward at ``q``."""
        xdot[:] = ff
        fid = self.frame_id
        placement = pin.updateFramePlacement(model, data, fid)
        e6 = frame_error(
            placement,
            ref[:3] if self.has_position else None,
            ref[3:].reshape(3, 3) if self.has_orientation else None,
        )
        np.take(e6, self.rows, out=e)
        J6 = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        np.take(J6, self.rows, axis=0, out=J)

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """Norms of the position rows [m] and orientation rows [rad] (see ``BaseTask``)."""
        return split_norms(self.rows, e)

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.FrameGoal`` in the world."""
        return engine.FrameGoal(frame=int(self.frame_id), rows=[int(r) for r in self.rows])

    def trail(
        self, model: pin.Model, data: pin.Data, ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The frame's origin and its reference position (none for an orientation task)."""
        reference = ref[:3].copy() if self.has_position else None
        return data.oMf[self.frame_id].translation.copy(), reference


def frame_error(
    placement: pin.SE3, position_d: np.ndarray | None, rotation_d: np.ndarray | None
) -> np.ndarray:
    """Six-vector error (6) ``(p_d - p, log3(R_d R^T))``; missing references give zero rows."""
    e6 = np.zeros(6)
    if position_d is not None:
        e6[:3] = position_d - placement.translation
    if rotation_d is not None:
        e6[3:] = pin.log3(rotation_d @ placement.rotation.T)
    return e6


def split_norms(rows: np.ndarray, e: np.ndarray) -> tuple[float, float]:
    """Norms of the position rows (``rows < 3``) and orientation rows of ``e``.

    The first is the orientation's when there is no position row.
    """
    pos = rows < 3
    rot = float(np.linalg.norm(e[~pos]))
    return (float(np.linalg.norm(e[pos])) if pos.any() else rot), rot


def pose_reference_arrays(task: Any, ref: Any) -> tuple[np.ndarray, np.ndarray]:
    """A frame task's poses (n, 12) and feed-forward (n, m) from a Reference.

    Raises:
        InputError: The trajectory lacks the position or orientation the task tracks.
    """
    P_d, R_d = getattr(ref, "position", None), getattr(ref, "rotation", None)
    if task.has_position and P_d is None:
        raise InputError("trajectory", f"a position reference for the {task.kind} task")
    if task.has_orientation and R_d is None:
        raise InputError("trajectory", f"an orientation reference for the {task.kind} task")
    n = ref.t.shape[0]
    out = np.zeros((n, 12))
    out[:, 3:] = np.eye(3).ravel()
    V6 = np.zeros((n, 6))
    if task.has_position:
        out[:, :3] = P_d
        V6[:, :3] = ref.linear_velocity
    if task.has_orientation:
        out[:, 3:] = np.reshape(np.asarray(R_d), (n, 9))
        V6[:, 3:] = ref.angular_velocity
    return out, np.ascontiguousarray(V6[:, task.rows])
