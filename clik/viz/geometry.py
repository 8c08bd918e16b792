"""Shapes for the viewer: Pinocchio/coal geometry and clik obstacles as three.js JSON.

three.js primitives are built around the y axis (cylinders) while coal's
cylinders and capsules lie along z, so those get an intrinsic rotation
``R_x(pi/2)``. Meshes (coal ``BVHModel`` as loaded by Pinocchio, scale already
applied; convex hulls) are sent once as indexed ``BufferGeometry`` with
``Float32`` vertices and ``Uint16`` indices where they fit, which is far smaller
than the original Collada files and lets every part be recoloured (a
joint-limit highlight is a change of ``material.color``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from clik.viz.commands import buffer_attribute, new_uuid

MIN_DISPLAY_RADIUS = 0.004
"""Radius [m] drawn for zero-radius spheres, capsules and cylinders (a point, a segment)."""

_ROTATE_Y_TO_Z = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)
"""``R_x(pi/2)``: maps three.js's y axis (cylinder axis) onto coal's z axis."""


@dataclass
class Shape:
    """A three.js geometry and the transform placing it in its node.

    Attributes:
        geometry: three.js geometry JSON (with ``uuid``).
        matrix: 4x4 transform of the geometry in the node's frame.
        is_mesh: True for triangle meshes (drawn with flat shading).
    """

    geometry: dict[str, Any]
    matrix: np.ndarray
    is_mesh: bool = False


def sphere(radius: float) -> Shape:
    """A sphere of ``radius`` [m] (at least :data:`MIN_DISPLAY_RADIUS`)."""
    geometry = {
        "uuid": new_uuid(),
        "type": "SphereGeometry",
        "radius": max(float(radius), MIN_DISPLAY_RADIUS),
        "widthSegments": 32,
        "heightSegments": 16,
    }
    return Shape(geometry, np.eye(4))


def box(size: np.ndarray) -> Shape:
    """A box with side lengths ``size`` (3,) [m]."""
    x, y, z = (float(v) for v in size)
    geometry = {"uuid": new_uuid(), "type": "BoxGeometry", "width": x, "height": y, "depth": z}
    return Shape(geometry, np.eye(4))


def cylinder(radius: float, length: float) -> Shape:
    """A closed cylinder along z, centred at the origin."""
    r = max(float(radius), MIN_DISPLAY_RADIUS)
    geometry = {
        "uuid": new_uuid(),
        "type": "CylinderGeometry",
        "radiusTop": r,
        "radiusBottom": r,
        "height": float(length),
        "radialSegments": 32,
    }
    return Shape(geometry, _ROTATE_Y_TO_Z.copy())


def capsule(radius: float, length: float, segments: int = 24, rings: int = 6) -> Shape:
    """A capsule along z (a cylinder of ``length`` [m] capped by two half spheres).

    three.js r129 (meshcat 0.3.2) has no capsule geometry: the surface is built
    here as a triangle mesh, a lathe of the capsule's profile.
    """
    r = max(float(radius), MIN_DISPLAY_RADIUS)
    half = 0.5 * float(length)
    # Profile (rho, z) from the bottom pole to the top pole.
    angles = np.linspace(-0.5 * math.pi, 0.0, rings + 1)
    bottom = [(r * math.cos(a), -half + r * math.sin(a)) for a in angles]
    top = [(rho, -z) for rho, z in reversed(bottom)]
    profile = np.array(bottom + top)
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    rho, z = profile[:, 0], profile[:, 1]
    vertices = np.stack(
        [
            np.outer(rho, np.cos(phi)),
            np.outer(rho, np.sin(phi)),
            np.repeat(z[:, None], segments, 1),
        ],
        axis=-1,
    ).reshape(-1, 3)
    faces = []
    n_rows = len(profile)
    for i in range(n_rows - 1):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, b, d), (a, d, c)]
    return mesh(vertices, np.array(faces), flat=False)


def mesh(vertices: np.ndarray, faces: np.ndarray, flat: bool = True) -> Shape:
    """An indexed triangle mesh (vertices (V, 3) [m], faces (F, 3) vertex indices)."""
    vertices = np.asarray(vertices, dtype=np.float32).reshape(-1, 3)
    faces = np.asarray(faces).reshape(-1, 3)
    index_type = np.uint16 if len(vertices) < 65536 else np.uint32
    geometry = {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {
            "attributes": {"position": buffer_attribute(vertices)},
            "index": buffer_attribute(faces.reshape(-1), index_type),
        },
    }
    return Shape(geometry, np.eye(4), is_mesh=flat)


def bvh_arrays(model: coal.BVHModelBase) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (F, 3) of a coal mesh."""
    vertices = np.asarray(model.vertices(), dtype=float).reshape(-1, 3)
    faces = np.empty((model.num_tris, 3), dtype=np.int64)
    for k in range(model.num_tris):
        tri = model.tri_indices(k)
        faces[k] = (tri[0], tri[1], tri[2])
    return vertices, faces


def convex_arrays(convex: coal.ConvexBase) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a coal convex polytope (polygons fanned into triangles)."""
    vertices = np.asarray(convex.points(), dtype=float).reshape(-1, 3)
    if not hasattr(convex, "polygons"):  # a bare ConvexBase: rebuild its hull with faces
        cloud = coal.BVHModelOBBRSS()
        cloud.beginModel(0, len(vertices))
        cloud.addVertices(vertices)
        cloud.endModel()
        cloud.buildConvexHull(True, "Qt")
        convex = cloud.convex
        vertices = np.asarray(convex.points(), dtype=float).reshape(-1, 3)
    faces = []
    for k in range(convex.num_polygons):
        poly = convex.polygons(k)
        idx = [poly[i] for i in range(poly.size())]
        faces += [(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)]
    return vertices, np.array(faces, dtype=np.int64).reshape(-1, 3)


def from_coal(
    geometry: coal.CollisionGeometry, mesh_cache: dict[int, Shape] | None = None
) -> Shape | None:
    """The display shape of a coal geometry, or None for a type that cannot be drawn.

    Args:
        geometry: A coal shape: sphere, box, cylinder, capsule, convex polytope or mesh
            (cones, planes and height fields are not drawn).
        mesh_cache: Shapes already built, by ``id`` of the coal object: a mesh
            shared by several geometry objects is converted once.
    """
    if isinstance(geometry, coal.Sphere):
        return sphere(geometry.radius)
    if isinstance(geometry, coal.Box):
        return box(2.0 * np.asarray(geometry.halfSide))
    if isinstance(geometry, coal.Cylinder):
        return cylinder(geometry.radius, 2.0 * geometry.halfLength)
    if isinstance(geometry, coal.Capsule):
        return capsule(geometry.radius, 2.0 * geometry.halfLength)
    key = id(geometry)
    if mesh_cache is not None and key in mesh_cache:
        return mesh_cache[key]
    if isinstance(geometry, coal.BVHModelBase):
        shape = mesh(*bvh_arrays(geometry))
    elif isinstance(geometry, coal.ConvexBase):
        shape = mesh(*convex_arrays(geometry))
    else:
        return None
    if mesh_cache is not None:
        mesh_cache[key] = shape
    return shape


def geometry_object_shape(go: pin.GeometryObject, mesh_cache: dict[Any, Shape]) -> Shape | None:
    """The display shape of a Pinocchio geometry object (in its own frame)."""
    path = go.meshPath
    if path and path in mesh_cache:  # same mesh file, e.g. left and right fingers
        return mesh_cache[path]
    shape = from_coal(go.geometry, mesh_cache)
    if shape is not None and path and isinstance(go.geometry, coal.BVHModelBase):
        mesh_cache[path] = shape
    return shape


def obstacle_shape(spec: dict[str, Any], inflate: float = 0.0) -> Shape:
    """The shape of an obstacle from ``result.info["obstacles"]``, grown by ``inflate`` [m].

    With ``inflate`` equal to the threshold distance, this is the threshold
    shell (exact for spheres and capsules; a box or a cylinder is grown along
    each axis, a mesh scaled about its centre: close enough to see).
    """
    kind = spec["shape"]
    if kind == "sphere":
        radius = float(spec.get("radius", 0.0))
        if inflate > 0.0:
            return sphere(radius + inflate)
        return sphere(radius)
    if kind == "box":
        return box(np.asarray(spec["size"], dtype=float) + 2.0 * inflate)
    if kind == "capsule":
        return capsule(float(spec["radius"]) + inflate, float(spec["length"]))
    if kind == "cylinder":
        return cylinder(float(spec["radius"]) + inflate, float(spec["length"]) + 2.0 * inflate)
    if kind == "mesh":
        from clik.constraints.obstacle import Obstacle

        hull = Obstacle(
            spec["name"],
            "mesh",
            spec["position"],
            file=spec["file"],
            scale=spec.get("scale", (1.0, 1.0, 1.0)),
        ).geometry
        vertices, faces = convex_arrays(hull)
        if inflate > 0.0:
            center = vertices.mean(axis=0)
            offset = vertices - center
            norm = np.linalg.norm(offset, axis=1, keepdims=True)
            vertices = center + offset * (1.0 + inflate / np.maximum(norm, 1e-9))
        return mesh(vertices, faces)
    raise ValueError(f"unknown obstacle shape {kind!r}")
