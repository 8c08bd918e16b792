r"""The distance task: the distance between the origins of two frames.

docs/method.md, "Several tasks", the distance between two frames. One row: with ``p_a``,
``p_b`` the world positions of frames A and B's origins, ``rho = |p_a - p_b|`` and ``u =
(p_a - p_b) / rho``, the error is ``e = rho_d - rho`` [m] and the Jacobian ``J = u^T
(J_{v,a} - J_{v,b})`` (the origins' world-aligned linear Jacobians), the feed-forward
``rho_dot_d``. Two hands that hold a box keep its width while both move; the reference
is one value per sample (a :class:`~clik.trajectory.JointPath` of one value, or a held
value).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.schema import MAX_LENGTH, MIN_DURATION
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import ValuesTarget
from clik.trajectory.joint_path import JointPath

if TYPE_CHECKING:
    from pathlib import Path

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory

LWA = pin.LOCAL_WORLD_ALIGNED
MIN_DISTANCE = 1e-9
"""Shortest distance [m] between the two origins the row is defined at (``u`` needs one)."""


class DistanceTask(BaseTask):
    """The distance between the origins of ``frame`` and ``relative_to`` [m], one row.

    Args:
        robot: The robot.
        frame: Frame A.
        relative_to: Frame B.

    Raises:
        InputError: The same frame twice (``task.relative_to``).
        FrameNotFound: No such frame.
    """

    names = ("distance",)
    table_keys = "`frame`, `relative_to`: the distance between their origins [m], one row"
    table_trajectory = (
        'optional: `kind = "hold"` with `value` [m] (default: the start\'s distance) and '
        '`duration` [s], or `kind = "line"` with `goal` [m] and `duration` [s]'
    )
    example = "baxter_box_width"
    kind = "distance"
    m = 1
    reference_size = 1

    def __init__(self, robot: Robot, frame: str, relative_to: str) -> None:
        robot.check_model()
        self.robot, self.frame, self.relative_to = robot, frame, relative_to
        self.frame_id = robot.frame_id(frame)
        self.relative_id = robot.frame_id(relative_to)
        if self.relative_id == self.frame_id:
            raise InputError("task.relative_to", f"a frame other than {frame!r}", relative_to)

    @property
    def axes(self) -> list[str]:
        """The one row's name."""
        return ["distance"]

    def __repr__(self) -> str:
        return f"DistanceTask(frame={self.frame!r}, relative_to={self.relative_to!r})"

    def describe(self) -> str:
        """``"distance between frames 'left_hand' and 'right_hand'"``."""
        return f"distance between frames {self.frame!r} and {self.relative_to!r}"

    def distance(self, q: np.ndarray) -> float:
        """The distance between the two origins at ``q`` [m]."""
        robot = self.robot
        data = robot.thread_data()
        pin.framesForwardKinematics(robot.model, data, q)
        return float(np.linalg.norm(_offset(data, self.frame_id, self.relative_id)))

    # -- the scenario: [[tasks]] kind = "distance" --------------------------------------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """``frame``, ``relative_to`` and a ``[tasks.trajectory]`` of the distance (optional).

        ``kind = "hold"`` with ``value`` [m] (default: the distance at the start) and
        ``duration`` [s] (default 0), or ``kind = "line"`` with ``goal`` [m] and
        ``duration`` [s]: from the start's distance to ``goal``. No trajectory: hold the
        start's distance.
        """
        out: dict[str, Any] = {"frame": t.string("frame"), "relative_to": t.string("relative_to")}
        tr = t.table("trajectory")
        kind = tr.string("kind", "hold", ("hold", "line")) if tr.data else "hold"
        trajectory: dict[str, Any] = {"kind": kind}
        if kind == "hold":
            trajectory["value"] = tr.number("value", None, 0.0, True, "[m]", bound=MAX_LENGTH)
            trajectory["duration"] = tr.number("duration", 0.0, 0.0, unit="[s]")
        else:
            trajectory["goal"] = tr.number(
                "goal", minimum=0.0, strict=True, unit="[m]", bound=MAX_LENGTH
            )
            trajectory["duration"] = tr.number("duration", minimum=MIN_DURATION, unit="[s]")
        tr.done()
        out["trajectory"] = trajectory
        return out

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The distance between the table's two frames."""
        return cls(robot, spec["frame"], spec["relative_to"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """A held distance (the start's, or ``value``), or a line from the start's to ``goal``.

        Raises:
            InputError: The two origins at one point at ``q0`` (``frame``).
        """
        start = self.distance(q0)
        if start < MIN_DISTANCE:
            raise InputError("frame", "two frames apart at the start (their distance > 0)", start)
        duration = float(spec["duration"])
        if spec["kind"] == "hold":
            value = start if spec["value"] is None else float(spec["value"])
            return (
                JointPath([[value], [value]], duration=duration) if duration else JointPath([value])
            )
        return JointPath([[start], [float(spec["goal"])]], duration=duration)

    # -- the rows ----------------------------------------------------------------------

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """The distance's error [m]."""
        return Norm("distance error", "m"), None

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """Distances (n, 1) [m] and their rates (n, 1) [m/s], from a one-value path's samples.

        Raises:
            InputError: Not a reference of one value per sample.
        """
        values = getattr(ref, "q", None)
        if values is None or values.shape[1] != 1:
            raise InputError(
                "trajectory", "one value per sample, the distance [m] (a clik.trajectory.JointPath "
                "of one value)", None if values is None else f"{values.shape[1]} values",
            )  # fmt: skip
        return np.ascontiguousarray(values), np.ascontiguousarray(ref.qdot)

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """``e = rho_d - rho``, ``J = u^T (J_v,a - J_v,b)`` and ``rho_dot_d``."""
        pin.updateFramePlacement(model, data, self.frame_id)
        pin.updateFramePlacement(model, data, self.relative_id)
        d = _offset(data, self.frame_id, self.relative_id)
        rho = float(np.linalg.norm(d))
        e[0] = ref[0] - rho
        Ja = pin.getFrameJacobian(model, data, self.frame_id, LWA)[:3]
        Jb = pin.getFrameJacobian(model, data, self.relative_id, LWA)[:3]
        u = d / max(rho, MIN_DISTANCE)
        J[0] = u @ (Ja - Jb)
        xdot[0] = ff[0]

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """``|rho_d - rho|`` [m], and 0."""
        return abs(float(e[0])), 0.0

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.DistanceGoal``."""
        return engine.DistanceGoal(frame=int(self.frame_id), relative_to=int(self.relative_id))

    def tick_target(self) -> ValuesTarget:
        """A distance [m] (a number, or (1,)) and its rate [m/s]."""
        return ValuesTarget(1, "distance", "m", "rate", "m/s")


def _offset(data: pin.Data, a: int, b: int) -> np.ndarray:
    """``p_a - p_b``, the world offset of frame ``a``'s origin from frame ``b``'s [m]."""
    return np.asarray(data.oMf[a].translation - data.oMf[b].translation, dtype=float)
