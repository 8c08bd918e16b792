r"""The gaze task: an axis of a frame points at a point.

docs/method.md, "Several tasks", gaze: an axis that points at a point. Frame A (a
camera, a tool) has an axis ``a`` (in A's axes, default ``z``); the task keeps it
pointing at a point ``g(t)`` of the world, the roll about it free. With ``R``, ``o`` A's
orientation and origin, ``v = R^T (g - o)`` the point in A's axes, ``d = v / |v|``, and
``S`` a fixed rotation with ``S a = e_z``, ``w = S d``: the two rows are the rotation
vector that turns the axis onto the point's direction, in the gaze axes,

.. math::

    e = \frac{\theta}{s} (-w_y, w_x), \qquad \theta = \operatorname{atan2}(s, w_z),
    \quad s = \sqrt{w_x^2 + w_y^2}

[rad] (``|e|`` is the angle to the point), and with ``E = de/dw``, ``P = I - d d^T``,

.. math::

    J = -E S P ([v]_\times R^T J_\omega - R^T J_v) / |v|, \qquad
    \dot x_d = E S P R^T \dot g / |v|.

The reference is the point (3,) [m] and its velocity (3,) [m/s] (the feed-forward rows
depend on the configuration: :attr:`GazeTask.ff_size` is 3).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.schema import MAX_LENGTH
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import FrameTarget
from clik.trajectory.hold import Hold
from clik.trajectory.line import Line

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory

LWA = pin.LOCAL_WORLD_ALIGNED
SMALL_SINE = 1e-8
"""Below this ``s`` the error and its derivative take their limits (the axis on the point)."""
AHEAD = 1.0
"""A table's default point: this far [m] along the axis from the frame, at the start."""


def gaze_error(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The error ``e`` (2,) [rad] of a direction ``w`` in the gaze axes, and ``E = de/dw``.

    At the axis pointing away (``s = 0``, ``w_z < 0``) the direction of turning is not
    defined: the one about the gaze x axis is taken.
    """
    wx, wy, wz = float(w[0]), float(w[1]), float(w[2])
    s = math.hypot(wx, wy)
    if s < SMALL_SINE and wz < 0.0:  # pointing away: turn about one axis
        wx, s = SMALL_SINE, SMALL_SINE
    r2 = wx * wx + wy * wy + wz * wz
    if s < SMALL_SINE:  # the limits of theta / s and of its derivative's factor
        f, g = 1.0 / wz, -2.0 / (3.0 * wz**3)
    else:
        f = math.atan2(s, wz) / s
        g = (wz / r2 - f) / (s * s)
    e = np.array([-f * wy, f * wx])
    E = np.array([
        [-wy * wx * g, -(wy * wy * g + f), wy / r2],
        [wx * wx * g + f, wx * wy * g, -wx / r2],
    ])  # fmt: skip
    return e, E


def gaze_axes(axis: np.ndarray) -> np.ndarray:
    """``S``: a rotation taking the unit ``axis`` to ``e_z`` (3, 3)."""
    return np.asarray(pin.Quaternion.FromTwoVectors(axis, np.array([0.0, 0.0, 1.0])).matrix())


class GazeTask(BaseTask):
    """The axis ``axis`` of ``frame`` (in that frame) points at a point of the world, 2 rows.

    Args:
        robot: The robot.
        frame: The frame (a camera's, a tool's).
        axis: Its axis, in its own axes (normalised); default ``z``.

    Raises:
        InputError: A zero or non-finite axis (``task.axis``).
        FrameNotFound: No such frame.
    """

    names = ("gaze",)
    table_keys = (
        "`frame`, `axis` (in the frame, default `[0, 0, 1]`): the axis points at a point, "
        "two rows, the roll free"
    )
    table_trajectory = (
        'the point, in the world: `kind = "hold"` with `position` [m] (default: 1 m along '
        'the axis at the start) and `duration`, or `kind = "line"` with `start` (default: '
        "the same), `goal` [m] and `duration` [s]"
    )
    example = "panda_look_at"
    kind = "gaze"
    m = 2
    reference_size = 3

    def __init__(
        self, robot: Robot, frame: str, axis: Sequence[float] | np.ndarray = (0.0, 0.0, 1.0)
    ) -> None:
        robot.check_model()
        try:
            a = np.array(axis, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError("task.axis", "a non-zero 3-vector", axis) from None
        if a.shape != (3,) or not np.isfinite(a).all() or np.linalg.norm(a) < 1e-9:
            raise InputError("task.axis", "a non-zero 3-vector", axis)
        self.robot, self.frame = robot, frame
        self.frame_id = robot.frame_id(frame)
        self.axis = a / np.linalg.norm(a)
        self.S = gaze_axes(self.axis)

    @property
    def ff_size(self) -> int:
        """The point's velocity (3,) [m/s]: the rows' feed-forward depends on ``q``."""
        return 3

    @property
    def axes(self) -> list[str]:
        """The two rows' names: the gaze error about the gaze axes x and y."""
        return ["gaze_x", "gaze_y"]

    def __repr__(self) -> str:
        return f"GazeTask(frame={self.frame!r}, axis={self.axis.tolist()})"

    def describe(self) -> str:
        """``"gaze of frame 'camera' along [0, 0, 1]"``."""
        return f"gaze of frame {self.frame!r} along {np.round(self.axis, 6).tolist()}"

    def ahead(self, q: np.ndarray, distance: float = AHEAD) -> np.ndarray:
        """The point ``distance`` [m] along the axis from the frame's origin at ``q``."""
        robot = self.robot
        data = robot.thread_data()
        pin.framesForwardKinematics(robot.model, data, q)
        oMf = data.oMf[self.frame_id]
        return np.asarray(oMf.translation + distance * oMf.rotation @ self.axis, dtype=float)

    # -- the scenario: [[tasks]] kind = "gaze" ------------------------------------------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """``frame``, ``axis`` (default ``[0, 0, 1]``) and the point's ``[tasks.trajectory]``.

        ``kind = "hold"`` with ``position`` [m] (default: 1 m along the axis at the
        start) and ``duration`` [s] (default 0), or ``kind = "line"`` with ``start``
        (default: the same point), ``goal`` [m] and ``duration`` [s]; all in the world.
        """
        axis = t.vector("axis", 3, [0.0, 0.0, 1.0], bound=MAX_LENGTH)
        if not any(axis):
            raise t.error("axis", "a non-zero 3-vector", axis)
        tr = t.table("trajectory")
        kind = tr.string("kind", "hold", ("hold", "line")) if tr.data else "hold"
        trajectory: dict[str, Any] = {"kind": kind}
        if kind == "hold":
            trajectory["position"] = tr.vector("position", 3, None, "[m]", MAX_LENGTH)
            trajectory["duration"] = tr.number("duration", 0.0, 0.0, unit="[s]")
        else:
            trajectory["start"] = tr.vector("start", 3, None, "[m]", MAX_LENGTH)
            trajectory["goal"] = tr.vector("goal", 3, unit="[m]", bound=MAX_LENGTH)
            trajectory["duration"] = tr.number("duration", minimum=0.0, strict=True, unit="[s]")
        tr.done()
        return {"frame": t.string("frame"), "axis": axis, "trajectory": trajectory}

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The gaze of the table's frame and axis."""
        return cls(robot, spec["frame"], spec["axis"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The point: held (``position``, else 1 m ahead at ``q0``), or along a line."""
        ahead = self.ahead(q0)
        if spec["kind"] == "hold":
            p = ahead if spec["position"] is None else np.asarray(spec["position"], dtype=float)
            return Hold(position=p, duration=float(spec["duration"]))
        start = ahead if spec["start"] is None else np.asarray(spec["start"], dtype=float)
        return Line(start, spec["goal"], duration=float(spec["duration"]))

    # -- the rows ----------------------------------------------------------------------

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """The angle between the axis and the direction to the point [rad]."""
        return Norm("gaze angle", "rad"), None

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """The point (n, 3) [m] and its velocity (n, 3) [m/s], from a position trajectory.

        Raises:
            InputError: The trajectory has no position.
        """
        if getattr(ref, "position", None) is None:
            raise InputError("trajectory", "a position trajectory of the point the axis points at")
        P = np.ascontiguousarray(ref.position, dtype=float)
        return P, np.ascontiguousarray(ref.linear_velocity, dtype=float)

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """The module's ``e``, ``J`` and ``xdot_d`` at ``q``."""
        oMf = pin.updateFramePlacement(model, data, self.frame_id)
        Rt = oMf.rotation.T
        v = Rt @ (ref[:3] - oMf.translation)
        n = max(float(np.linalg.norm(v)), 1e-12)  # the point at the origin: no direction
        d = v / n
        err, E = gaze_error(self.S @ d)
        A = E @ self.S @ (np.eye(3) - np.outer(d, d)) / n
        J6 = pin.getFrameJacobian(model, data, self.frame_id, LWA)
        J[:] = -A @ (pin.skew(v) @ Rt @ J6[3:] - Rt @ J6[:3])
        e[:] = err
        xdot[:] = A @ (Rt @ ff[:3])

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """The angle to the point [rad], and 0."""
        return float(np.linalg.norm(e)), 0.0

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.GazeGoal``."""
        return engine.GazeGoal(frame=int(self.frame_id), axis=np.array(self.axis, dtype=float))

    def tick_target(self) -> FrameTarget:
        """The point (3,) [m] (or a pose's position) and its velocity (3,) [m/s]."""
        return FrameTarget(True, False, (0, 1, 2), rotation_ref=False)

    # -- the view ----------------------------------------------------------------------

    def trail(
        self, model: pin.Model, data: pin.Data, ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Where the axis points, as far as the point is, and the point [m]."""
        oMf = data.oMf[self.frame_id]
        reach = float(np.linalg.norm(ref[:3] - oMf.translation))
        return oMf.translation + reach * (oMf.rotation @ self.axis), ref[:3].copy()
