"""The robot's own points out of a cloud: docs/method.md, "Obstacles from point clouds".

A camera that sees the arm would make the arm an obstacle to itself. A point within
``padding`` [m] of a link's collision shape (its convex hull for a mesh, as the
collision rows use it), at the configuration given, is removed: the link's points are
first found in its own bounding box grown by ``padding`` (one matrix product per
link), then coal measures those few (a point as a sphere of radius 0).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from clik.errors import InputError
from clik.model.robot import Robot


def without_robot(
    points: np.ndarray, robot: Robot, q: np.ndarray, padding: float = 0.01
) -> tuple[np.ndarray, int]:
    """The points farther than ``padding`` from every link, and how many were removed.

    Args:
        points: ``(N, 3)`` points [m] in the robot's world frame.
        robot: The robot.
        q: Its configuration when the cloud was taken.
        padding: Margin [m] >= 0 around the links (a depth camera's noise).

    Raises:
        InputError: ``padding`` negative, ``q`` not a configuration of the robot.
    """
    if not np.isfinite(padding) or padding < 0.0:
        raise InputError("padding", "a finite margin >= 0 [m]", padding)
    q = robot.check_configuration(q, "q")
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    model, geometry = robot.model, robot.collision_model
    data, placed = model.createData(), geometry.createData()
    pin.updateGeometryPlacements(model, data, geometry, placed, q)
    mine = np.zeros(len(points), dtype=bool)
    for go, pose in zip(geometry.geometryObjects, placed.oMg, strict=True):
        shape = _convex(go.geometry)
        candidates = np.flatnonzero(~mine & _in_box(shape, pose, points, padding))
        for i in candidates:
            mine[i] = _distance(shape, pose, points[i]) < padding
    return points[~mine], int(mine.sum())


def _convex(shape: coal.CollisionGeometry) -> coal.CollisionGeometry:
    """A mesh's convex hull (points inside a closed mesh are then inside), else the shape."""
    if isinstance(shape, coal.BVHModelBase):
        if shape.convex is None:
            shape.buildConvexHull(True, "Qt")
        return shape.convex
    return shape


def _in_box(
    shape: coal.CollisionGeometry, pose: pin.SE3, points: np.ndarray, padding: float
) -> np.ndarray:
    """Points inside the shape's own bounding box grown by ``padding``."""
    shape.computeLocalAABB()
    low = np.asarray(shape.aabb_local.min_) - padding
    high = np.asarray(shape.aabb_local.max_) + padding
    local = (points - pose.translation) @ pose.rotation
    return np.all((local >= low) & (local <= high), axis=1)


def _distance(shape: coal.CollisionGeometry, pose: pin.SE3, point: np.ndarray) -> float:
    """Signed distance [m] from a point to the placed shape (negative inside)."""
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    request.enable_signed_distance = True
    coal.distance(
        shape,
        coal.Transform3s(pose.rotation, pose.translation),
        coal.Sphere(1e-12),
        coal.Transform3s(np.eye(3), point),
        request,
        result,
    )
    return float(result.min_distance) + 1e-12
