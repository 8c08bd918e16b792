"""A point cloud as an obstacle: its points, their voxel spheres and its pose.

docs/method.md, "Obstacles from point clouds": the points (in the cloud's own frame,
placed in the world by ``position`` and ``rpy``) become voxel spheres (C1), voxels
aligned on the cloud frame's origin; the rows keep every link at least the threshold
from the spheres, so at least that far from the points (C2). NaN or infinite points
are dropped and counted (:attr:`CloudObstacle.dropped`); an empty cloud gives no rows
and an :class:`EmptyCloudWarning`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from clik.bounds import in_range
from clik.clouds.grid import SphereGrid, grid_cell, sphere_grid
from clik.clouds.read import finite_points, read_cloud
from clik.clouds.voxels import voxel_spheres
from clik.errors import ClikWarning, InputError

DEFAULT_VOXEL = 0.01
"""Voxel edge [m] of a cloud unless given (a depth camera's noise at about 1 m)."""


class EmptyCloudWarning(ClikWarning):
    """A cloud obstacle has no points (all dropped, or none given): it adds no rows."""


class CloudObstacle:
    """A point cloud obstacle.

    Args:
        name: Its name (``cloud:<name>:<link>`` rows, summaries, ``ctl.step(obstacles=)``).
        points: ``(N, 3)`` points [m] in the cloud's frame; NaN or infinite rows dropped.
        voxel: Voxel edge [m] >= 0 (0: every point its own sphere of radius 0).
        position: The cloud frame's origin in the world [m].
        rpy: The cloud frame's orientation, roll, pitch, yaw [rad].
        threshold: Its own ``d_o`` [m]; None: the set's obstacle threshold.
        source: Where the points came from (a file), for messages.

    Attributes:
        local: ``(N, 3)`` finite points in the cloud's frame [m] (read-only).
        dropped: Points dropped for a NaN or infinite coordinate.
        removed: Points removed as the robot's own (:meth:`without_robot`).
    """

    def __init__(
        self,
        name: str,
        points: np.ndarray | Sequence[Sequence[float]],
        voxel: float = DEFAULT_VOXEL,
        position: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
        rpy: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
        threshold: float | None = None,
        source: str = "",
    ) -> None:
        if not isinstance(name, str) or not name or ":" in name:
            raise InputError("obstacles.name", "a non-empty name without ':'", name)
        if not in_range(voxel, 0.0):
            raise InputError(f"obstacles.{name}.voxel", "a finite voxel size >= 0 [m]", voxel)
        if threshold is not None and not in_range(threshold, 0.0, strict=True):
            raise InputError(f"obstacles.{name}.threshold", "a positive distance [m]", threshold)
        array = np.asarray(points, dtype=float) if _numeric(points) else None
        if array is None or array.ndim != 2 or array.shape[1] != 3:
            shape = getattr(array, "shape", type(points).__name__)
            raise InputError(f"obstacles.{name}.points", "an (N, 3) array of points [m]", shape)
        self.name, self.voxel, self.threshold = name, float(voxel), threshold
        self.source = source or f"obstacles.{name}.points"
        self.position = _vector3(position, f"obstacles.{name}.position")
        self.rpy = _vector3(rpy, f"obstacles.{name}.rpy")
        self.rotation = pin.rpy.rpyToMatrix(*self.rpy)
        read = finite_points(array, self.source)
        self.dropped, self.removed = read.dropped, 0
        self.local = read.points
        if len(self.local) == 0:
            warnings.warn(
                f"cloud obstacle {name!r} has no points ({self.dropped} dropped as NaN or "
                "infinite): it adds no rows",
                EmptyCloudWarning,
                stacklevel=2,
            )
        self._grids: dict[float, SphereGrid] = {}

    @property
    def world(self) -> np.ndarray:
        """``(N, 3)`` finite points in the world [m] (a new read-only array)."""
        return _placed(self.local, self.rotation, self.position)

    @classmethod
    def from_file(cls, name: str, path: str, **settings: Any) -> CloudObstacle:
        """A cloud read from a ``.npy``, ``.ply`` or ``.pcd`` file (:func:`read_cloud`)."""
        read = read_cloud(path)
        cloud = cls(name, read.points, source=str(path), **settings)
        cloud.dropped = read.dropped
        return cloud

    @classmethod
    def from_depth(
        cls, name: str, depth: np.ndarray, intrinsics: Any, scale: float = 1.0,
        max_depth: float = 10.0, **settings: Any,
    ) -> CloudObstacle:  # fmt: skip
        """A cloud seen by a depth camera (:func:`~clik.clouds.depth.depth_points`).

        The cloud's frame is the camera's optical frame (x right, y down, z forward):
        its pose is ``position`` and ``rpy`` in ``settings``. Pixels of depth 0, NaN or
        beyond ``max_depth`` [m] are left out and counted in :attr:`dropped`.
        """
        from clik.clouds.depth import depth_points

        points, left_out = depth_points(depth, intrinsics, pin.SE3.Identity(), scale, max_depth)
        cloud = cls(name, points, source="depth image", **settings)
        cloud.dropped = left_out
        return cloud

    @classmethod
    def from_bag(
        cls, name: str, folder: str, topic: str | None = None, index: int = -1, **settings: Any
    ) -> CloudObstacle:
        """A rosbag2 folder's ``sensor_msgs/PointCloud2`` (:func:`~clik.clouds.bag.read_bag_cloud`).

        The cloud's frame is the message's ``frame_id``: its pose is ``position`` and
        ``rpy`` in ``settings``.
        """
        from clik.clouds.bag import read_bag_cloud

        points, frame = read_bag_cloud(folder, topic, index)
        return cls(name, points, source=f"{folder} ({frame})", **settings)

    def with_points(self, points: np.ndarray) -> CloudObstacle:
        """The same cloud (frame, voxel, threshold) with new points in its frame [m]."""
        return CloudObstacle(
            self.name, points, self.voxel, self.position, self.rpy, self.threshold, self.source
        )

    def without_robot(self, robot: Any, q: np.ndarray, padding: float = 0.01) -> CloudObstacle:
        """This cloud without the points within ``padding`` [m] of the robot at ``q``."""
        from clik.clouds.self_filter import without_robot

        kept, removed = without_robot(self.world, robot, q, padding)
        local = (kept - self.position) @ self.rotation
        out = CloudObstacle(
            self.name, local, self.voxel, self.position, self.rpy, self.threshold, self.source
        )
        out.dropped, out.removed = self.dropped, removed
        return out

    def spheres(self, threshold: float) -> SphereGrid:
        """The voxel spheres (C1) in the world, in a grid for ``threshold`` [m] (kept)."""
        grid = self._grids.get(threshold)
        if grid is None:
            centres, radii = voxel_spheres(self.local, self.voxel)
            centres = _placed(centres, self.rotation, self.position)
            grid = sphere_grid(centres, radii, grid_cell(centres, radii, threshold))
            self._grids[threshold] = grid
        return grid

    def info(self) -> dict[str, Any]:
        """The cloud as a run's ``info["clouds"]`` lists it."""
        return {
            "name": self.name,
            "shape": "cloud",
            "points": len(self.local),
            "dropped": self.dropped,
            "removed": self.removed,
            "voxel": self.voxel,
            "position": self.position.tolist(),
            "rpy": self.rpy.tolist(),
            "source": self.source,
        }


def _vector3(value: object, field: str) -> np.ndarray:
    """Three finite numbers as a new read-only array (a position [m], an rpy [rad])."""
    array = np.array(value, dtype=float) if _numeric(value) else np.zeros(0)
    if array.shape != (3,) or not np.all(np.isfinite(array)):
        raise InputError(field, "three finite numbers", value)
    array.flags.writeable = False
    return array


def _numeric(points: object) -> bool:
    try:
        return np.asarray(points).dtype.kind in "fiub"
    except (ValueError, TypeError):
        return False


def _placed(points: np.ndarray, rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    world = np.ascontiguousarray(points @ rotation.T + position)
    world.flags.writeable = False
    return world
