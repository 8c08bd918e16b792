r"""The centre-of-mass task: the robot's CoM follows a position reference.

docs/method.md, "Several tasks". The error is ``c_d - c`` [m] on the kept axes, the
Jacobian Pinocchio's centre-of-mass Jacobian ``J_com = dc/dq`` (world axes), the
feed-forward the reference's velocity. A humanoid on a fixed base keeps its CoM over
its feet (axes ``x, y``) while its arms move.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.tasks.kind import BaseTask, Norm
from clik.tasks.targets import FrameTarget
from clik.trajectory.tables import build_trajectory, strings, trajectory_table

if TYPE_CHECKING:
    from pathlib import Path

    from clik.model.robot import Robot
    from clik.schema import Table
    from clik.trajectory.base import Trajectory

COM_AXES = ("x", "y", "z")


class ComTask(BaseTask):
    """The centre of mass on axes ``axes`` (default ``x, y, z``), in the world.

    Args:
        robot: The robot.
        axes: A subset of ``"x", "y", "z"``.

    Raises:
        InputError: Bad axes, or a robot without mass.
    """

    names = ("com",)
    table_keys = '`axes` (default `["x", "y", "z"]`)'
    table_trajectory = "the keys of `[trajectory]` (optional: hold the start's centre of mass)"
    kind = "com"
    has_position = True
    has_orientation = False
    reference_size = 3

    def __init__(self, robot: Robot, axes: Sequence[str] | None = None) -> None:
        robot.check_model()
        if axes is None:
            axes = COM_AXES
        if isinstance(axes, str) or not axes or len(set(axes)) != len(axes):
            raise InputError("task.axes", "distinct names among ['x', 'y', 'z']", axes)
        bad = [a for a in axes if a not in COM_AXES]
        if bad:
            raise InputError("task.axes", "distinct names among ['x', 'y', 'z']", list(axes))
        if not pin.computeTotalMass(robot.model) > 0.0:
            raise InputError("task.kind", "a robot whose links have mass for a com task", "com")
        self.robot = robot
        self.rows = np.asarray(sorted(COM_AXES.index(a) for a in axes), dtype=np.intp)
        self.m = len(self.rows)

    @property
    def axes(self) -> list[str]:
        """The kept axes."""
        return [COM_AXES[i] for i in self.rows]

    # -- the scenario: [[tasks]] kind = "com" --------------------------------------------

    @classmethod
    def read_table(cls, t: Table, folder: Path) -> dict[str, Any]:
        """``axes`` (default every one) and a position ``[tasks.trajectory]`` (optional).

        The trajectory takes :func:`clik.trajectory.tables.trajectory_table`'s keys;
        without one the centre of mass of the start is held.
        """
        axes = strings(t, "axes") or None
        if t.has("axes") and (
            axes is None or not set(axes) <= set(COM_AXES) or len(set(axes)) != len(axes)
        ):
            raise t.error("axes", f"distinct names among {list(COM_AXES)}", axes)
        tr = t.table("trajectory")
        held = {"kind": "hold", "start": None, "goal": None, "duration": 0.0, "goal_rpy": None}
        return {
            "axes": axes,
            "trajectory": trajectory_table(tr, folder, False) if tr.data else held,
        }

    @classmethod
    def from_spec(cls, robot: Robot, spec: dict[str, Any]) -> BaseTask:
        """The centre of mass on the table's axes."""
        return cls(robot, spec["axes"])

    def trajectory_from(self, spec: dict[str, Any], q0: np.ndarray) -> Trajectory:
        """The table's position trajectory from the centre of mass at ``q0``."""
        return build_trajectory(spec, pin.SE3(np.eye(3), self.position(q0)), True, False)

    @property
    def norms(self) -> tuple[Norm, Norm | None]:
        """The centre of mass's error [m]."""
        return Norm("centre of mass error", "m"), None

    def trail(
        self, model: pin.Model, data: pin.Data, ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The centre of mass and its reference [m]."""
        return np.array(data.com[0], dtype=float), ref[:3].copy()

    def tick_target(self) -> FrameTarget:
        """A position (3,) [m] (or a pose's), and its velocity (:mod:`clik.tasks.targets`)."""
        return FrameTarget(True, False, tuple(int(r) for r in self.rows), rotation_ref=False)

    def __repr__(self) -> str:
        return f"ComTask(axes={self.axes})"

    def describe(self) -> str:
        """``"centre of mass (x, y)"``."""
        return f"centre of mass ({', '.join(self.axes)})"

    def position(self, q: np.ndarray) -> np.ndarray:
        """The CoM at ``q`` (3,) [m]."""
        return np.array(pin.centerOfMass(self.robot.model, self.robot.thread_data(), q))

    def reference_arrays(self, ref: Any) -> tuple[np.ndarray, np.ndarray]:
        """CoM positions (n, 3) and the kept axes' velocities (n, m) from a trajectory.

        Raises:
            InputError: The trajectory has no position.
        """
        if getattr(ref, "position", None) is None:
            raise InputError("trajectory", "a position reference for the com task")
        P = np.ascontiguousarray(ref.position, dtype=float)
        return P, np.ascontiguousarray(ref.linear_velocity[:, self.rows])

    def fill(
        self, model: pin.Model, data: pin.Data, q: np.ndarray, ref: np.ndarray,
        ff: np.ndarray, J: np.ndarray, e: np.ndarray, xdot: np.ndarray,
    ) -> None:  # fmt: skip
        """``e = c_d - c``, ``J_com`` rows and the feed-forward."""
        xdot[:] = ff
        Jc = pin.jacobianCenterOfMass(model, data, q, False)
        np.take(ref - data.com[0], self.rows, out=e)
        np.take(Jc, self.rows, axis=0, out=J)

    def error_norms(self, e: np.ndarray) -> tuple[float, float]:
        """The CoM error norm [m], and 0."""
        return float(np.linalg.norm(e)), 0.0

    def engine_goal(self, engine: Any) -> Any:
        """``_engine.ComGoal``."""
        return engine.ComGoal(rows=[int(r) for r in self.rows])
