"""clik's obstacles in a MuJoCo model: geoms on mocap bodies, measured, not collided.

The replay (:mod:`clik.sim.replay`) measures each robot geom's distance to each obstacle
with ``mujoco.mj_geomDistance``; contacts with obstacles are off, so that the distances
are those of the motion the servos reach, not of a robot pushed back by a contact.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from clik.sim.mujoco_model import POINT_RADIUS


def add_obstacles(mujoco: Any, spec: Any, obstacles: list[Any]) -> list[str]:
    """Each clik obstacle as a geom on a mocap body (moved each step), without contacts.

    MuJoCo sizes are halves where clik's are whole (box sides, capsule and cylinder
    lengths); a point (a sphere of radius 0) is a sphere of 1 um whose radius is added
    back to the distances (:func:`clik.sim.replay.clearance`). A mesh is its convex hull's
    points, as clik collides it.

    Args:
        mujoco: The imported ``mujoco`` module.
        spec: The robot's ``mujoco.MjSpec`` (changed in place).
        obstacles: clik's obstacles (:class:`~clik.constraints.obstacle.Obstacle`).

    Returns:
        The mocap bodies' names, in the obstacles' order.
    """
    geom = mujoco.mjtGeom
    names = []
    for o in obstacles:
        body = spec.worldbody.add_body(name=f"clik_obstacle_{o.name}", mocap=True)
        body.pos = o.position.tolist()
        body.quat = _quaternion(o.rotation)
        kind: Any
        if o.shape == "sphere":
            kind, size = geom.mjGEOM_SPHERE, [max(o.params["radius"], POINT_RADIUS), 0.0, 0.0]
        elif o.shape == "box":
            kind, size = geom.mjGEOM_BOX, [0.5 * s for s in o.params["size"]]
        elif o.shape in ("capsule", "cylinder"):
            kind = geom.mjGEOM_CAPSULE if o.shape == "capsule" else geom.mjGEOM_CYLINDER
            size = [o.params["radius"], 0.5 * o.params["length"], 0.0]
        else:
            mesh = spec.add_mesh(name=f"clik_obstacle_{o.name}")
            mesh.uservert = np.asarray(o.geometry.points(), dtype=float).ravel().tolist()
            kind, size = geom.mjGEOM_MESH, [0.0, 0.0, 0.0]
        g = body.add_geom(name=f"clik_obstacle_{o.name}", type=kind, size=size)
        g.contype, g.conaffinity = 0, 0
        g.rgba = [0.9, 0.3, 0.2, 0.5]
        if kind == geom.mjGEOM_MESH:
            g.meshname = f"clik_obstacle_{o.name}"
        names.append(body.name)
    return names


def _quaternion(rotation: np.ndarray) -> list[float]:
    """MuJoCo's (w, x, y, z) quaternion of a rotation matrix."""
    q = pin.Quaternion(np.asarray(rotation, dtype=float))
    return [q.w, q.x, q.y, q.z]
