"""The Panda lines' three spheres as a Pinocchio geometry model, built apart from clik's scene.

pink's collision barrier (:mod:`benchmarks.pink_barrier`) and the tick lines'
clearance check (:mod:`benchmarks.tick_quality`) both need the spheres beside the
robot's link geometry. This builds that geometry model from the robot's URDF
collision model and coal alone, not from clik's constraint code: every link
geometry as a convex shape (a mesh replaced by its convex hull, as clik and MuJoCo
collide meshes), each sphere a ``coal.Sphere`` on the world joint (index 0), and one
collision pair per (sphere, link geometry).
"""

from __future__ import annotations

from collections.abc import Sequence

import coal
import numpy as np
import pinocchio as pin

import clik

WORLD_JOINT = 0
"""Pinocchio's index of the universe joint, where the spheres are fixed."""


def _convex_shape(geometry: coal.CollisionGeometry) -> coal.CollisionGeometry:
    """A mesh's convex hull (of a copy: the robot's own mesh is left alone), else the shape."""
    if isinstance(geometry, coal.BVHModelBase):
        mesh = geometry.clone()
        mesh.buildConvexHull(True, "Qt")
        return mesh.convex
    return geometry


def sphere_geometry(
    robot: clik.Robot, centres: Sequence[Sequence[float]], radius: float
) -> pin.GeometryModel:
    """The robot's link geometries, convex, the spheres, and every (sphere, link) pair.

    Args:
        robot: The robot (its collision model gives the links).
        centres: Sphere centres in the world frame [m].
        radius: Radius of every sphere [m].

    Returns:
        A new geometry model: the link geometries first (``robot.collision_model``'s
        order), then the spheres; ``len(centres) * n_links`` collision pairs, sphere by
        sphere, link geometry first in each pair.
    """
    gmodel = pin.GeometryModel()
    links = []
    for go in robot.collision_model.geometryObjects:
        links.append(
            gmodel.addGeometryObject(
                pin.GeometryObject(
                    go.name, go.parentJoint, go.parentFrame, go.placement,
                    _convex_shape(go.geometry),
                )
            )
        )  # fmt: skip
    for i, centre in enumerate(centres):
        placement = pin.SE3(np.eye(3), np.asarray(centre, dtype=float))
        sphere = gmodel.addGeometryObject(
            pin.GeometryObject(f"sphere{i}", WORLD_JOINT, 0, placement, coal.Sphere(radius))
        )
        for link in links:
            gmodel.addCollisionPair(pin.CollisionPair(link, sphere))
    return gmodel
