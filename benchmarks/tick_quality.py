"""How well a tick line tracked, from its recorded joints alone (no tool's own figures).

Every tool's joints go through the same check: Pinocchio's forward kinematics of
the Panda for the pose errors against the tick's own desired pose ``x_d(t_k)``,
the robot's collision geometry placed by Pinocchio and coal's distances to the
spheres for the clearance (:func:`~benchmarks.sphere_scene.sphere_geometry`: the
link geometries' convex hulls, as clik and MuJoCo collide them), and the joints'
differences for the speed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

import clik
from benchmarks.config import DT
from benchmarks.pose_error import pose_errors
from benchmarks.sphere_scene import sphere_geometry
from benchmarks.tick_variant import TickReference

CLEARANCE_EVERY = 10
"""The clearance is computed on every 10th recorded tick (and on the last)."""


class QualityCheck:
    """The tracking-quality check of the Panda's tick lines, its geometry built once.

    Args:
        robot: The Panda (its model, URDF velocity limits and collision geometry).
        frame_id: Frame of the pose task.
        reference: The reference at every tick.
        centres: Sphere centres [m].
        radius: Sphere radius [m].
    """

    def __init__(
        self,
        robot: clik.Robot,
        frame_id: int,
        reference: TickReference,
        centres: Sequence[Sequence[float]],
        radius: float,
    ) -> None:
        self.model = robot.model
        self.data = robot.model.createData()
        self.frame_id = frame_id
        self.reference = reference
        self.vmax = np.asarray(robot.model.velocityLimit, dtype=float)
        self.gmodel = sphere_geometry(robot, centres, radius)
        self.gdata = pin.GeometryData(self.gmodel)

    def clearance(self, q: np.ndarray) -> float:
        """Smallest distance between a sphere and a link geometry at ``q`` [m] (< 0: inside).

        Args:
            q: Configuration.
        """
        pin.computeDistances(self.model, self.data, self.gmodel, self.gdata, q)
        return min(r.min_distance for r in self.gdata.distanceResults)

    def __call__(self, joints: np.ndarray) -> dict[str, Any]:
        """The quality figures of a line's recorded joints.

        Args:
            joints: ``q_k`` at the tick times ``t_0, t_1, ...`` (m, nq) [rad]; rows
                past the reference's last sample count for the speed only.

        Returns:
            ``max_position_error_m`` and ``max_orientation_error_rad`` (of ``q_k``
            against ``x_d(t_k)``, every recorded tick within the reference),
            ``min_clearance_m`` (every :data:`CLEARANCE_EVERY`-th tick and the last),
            ``velocity_ratio`` (``max_k,i |q_k+1,i - q_k,i| / (dt vmax_i)``, the URDF
            velocity limits) and ``ticks_checked``.
        """
        poses = self.reference.poses
        n = min(len(joints), len(poses))
        errors = np.array(
            [
                pose_errors(self.model, self.data, self.frame_id, joints[k], poses[k])
                for k in range(n)
            ]
        )
        sampled = sorted({*range(0, len(joints), CLEARANCE_EVERY), len(joints) - 1})
        speed = np.abs(np.diff(joints, axis=0)) / DT
        return {
            "max_position_error_m": float(errors[:, 0].max()),
            "max_orientation_error_rad": float(errors[:, 1].max()),
            "min_clearance_m": float(min(self.clearance(joints[k]) for k in sampled)),
            "velocity_ratio": float((speed / self.vmax).max()) if len(speed) else 0.0,
            "ticks_checked": n,
        }
