"""Collision and visual geometry of an MJCF robot, from MuJoCo's compiled model.

Each geom of a body becomes a Pinocchio geometry object on the body's frame
(:mod:`clik.model.mjcf_compiled`) at MuJoCo's compiled pose (``geom_pos``,
``geom_quat``: default classes, ``fromto`` and orientations already applied), with
MuJoCo's sizes (``geom_size``). A mesh is MuJoCo's compiled mesh (``mesh_vert``,
``mesh_face``: the file scaled, moved to its centre and principal axes, the geom's pose
holding that offset); a collision mesh is MuJoCo's convex hull of it (``mesh_graph``,
with ``maxhullvert`` applied: the shape MuJoCo collides). So every shape sits where
MuJoCo puts it, and is the one MuJoCo uses.

- **Collision** geoms: those that can touch (not both ``contype="0"`` and
  ``conaffinity="0"``), and those of ``group`` 3 (the Menagerie's collision group,
  where some models keep collision shapes with contacts off). **Visual** geoms: those
  of ``group`` 0 to 2 (MuJoCo's viewer shows those by default), so a group 3 geom is
  collision only.
- Names: the geom's, else ``<body>Geom_<k>`` (its rank among its body's geoms, as
  Pinocchio's reader names them).
- Planes (a floor) are dropped: the environment is given as obstacles. Geoms of the
  world body are not part of the robot and are dropped too.
"""

from __future__ import annotations

from typing import Any

import coal
import numpy as np
import pinocchio as pin

from clik.model.mjcf_compiled import body_name, element_name, se3

PLANE, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH = 0, 2, 3, 4, 5, 6, 7
"""MuJoCo's geom types (``mjtGeom``) clik reads (height fields are refused before)."""

VISUAL_GROUPS = 3
"""Geoms of a ``group`` below this are drawn (MuJoCo's viewer default)."""

COLLISION_GROUP = 3
"""A geom of this group is collision geometry even with contacts off."""


def is_collision(mj: Any, geom: int) -> bool:
    """A geom that can touch (``contype`` or ``conaffinity`` not zero), or of group 3.

    Group 3 is the Menagerie's collision group: some models keep their collision shapes
    there with contacts off (``contype="0" conaffinity="0"``), for explicit pairs.
    """
    return (
        bool(mj.geom_contype[geom] or mj.geom_conaffinity[geom])
        or int(mj.geom_group[geom]) == COLLISION_GROUP
    )


def build_geometry(mj: Any, model: pin.Model, kind: pin.GeometryType) -> pin.GeometryModel:
    """The collision or visual geometry of the robot, on ``model``'s body frames.

    Args:
        mj: The compiled model.
        model: The Pinocchio model built from it (its body frames are placed there).
        kind: ``pin.COLLISION`` or ``pin.VISUAL``.
    """
    geometry = pin.GeometryModel()
    meshes: dict[int, coal.CollisionGeometry] = {}
    paths = _mesh_paths(mj)
    for geom in range(mj.ngeom):
        body = int(mj.geom_bodyid[geom])
        wanted = is_collision(mj, geom) if kind == pin.COLLISION else _is_visual(mj, geom)
        if body == 0 or int(mj.geom_type[geom]) == PLANE or not wanted:
            continue
        frame_id = model.getFrameId(body_name(mj, body), pin.BODY)
        frame = model.frames[frame_id]
        placement = frame.placement * se3(mj.geom_pos[geom], mj.geom_quat[geom])
        shape = _shape(mj, geom, meshes, hull=kind == pin.COLLISION)
        go = pin.GeometryObject(
            element_name(mj, "geom", geom), frame.parentJoint, frame_id, placement, shape
        )
        go.meshPath = paths[int(mj.geom_dataid[geom])] if mj.geom_type[geom] == MESH else ""
        geometry.addGeometryObject(go)
    return geometry


def _is_visual(mj: Any, geom: int) -> bool:
    return int(mj.geom_group[geom]) < VISUAL_GROUPS


def _shape(
    mj: Any, geom: int, meshes: dict[int, coal.CollisionGeometry], hull: bool
) -> coal.CollisionGeometry:
    """The coal shape of a geom (sizes [m] as MuJoCo compiled them).

    With ``hull``, a mesh is MuJoCo's collision hull (``mesh_graph``: the convex hull
    MuJoCo collides, ``maxhullvert`` applied) when MuJoCo computed one.
    """
    kind = int(mj.geom_type[geom])
    size = np.array(mj.geom_size[geom], dtype=float)
    if kind == SPHERE:
        return coal.Sphere(size[0])
    if kind == CAPSULE:
        return coal.Capsule(size[0], 2.0 * size[1])
    if kind == CYLINDER:
        return coal.Cylinder(size[0], 2.0 * size[1])
    if kind == BOX:
        return coal.Box(*(2.0 * size))
    if kind == ELLIPSOID:
        return coal.Ellipsoid(*size)
    mesh = int(mj.geom_dataid[geom])
    if mesh not in meshes:
        meshes[mesh] = _mesh(mj, mesh, hull)
    return meshes[mesh]


def _mesh(mj: Any, mesh: int, hull: bool) -> coal.BVHModelOBBRSS:
    """MuJoCo's compiled mesh (scaled, in its centred frame) as a coal triangle mesh.

    With ``hull`` and a ``mesh_graph`` (MuJoCo's convex hull of a collision mesh:
    ``numvert, numface, vert_edgeadr[numvert], vert_globalid[numvert],
    edge_localid[numvert + 3 numface], face_globalid[3 numface]``), the hull's vertices
    and faces only.
    """
    start, count = int(mj.mesh_vertadr[mesh]), int(mj.mesh_vertnum[mesh])
    first, faces = int(mj.mesh_faceadr[mesh]), int(mj.mesh_facenum[mesh])
    vertices = np.array(mj.mesh_vert[start : start + count], dtype=float)
    triangles = np.array(mj.mesh_face[first : first + faces], dtype=np.int64)
    graph = int(mj.mesh_graphadr[mesh])
    if hull and graph >= 0:
        n_vert, n_face = int(mj.mesh_graph[graph]), int(mj.mesh_graph[graph + 1])
        ids = np.array(mj.mesh_graph[graph + 2 + n_vert : graph + 2 + 2 * n_vert], dtype=np.int64)
        at = graph + 2 + 3 * n_vert + 3 * n_face
        face_ids = np.array(mj.mesh_graph[at : at + 3 * n_face], dtype=np.int64)
        local = np.full(count, -1, dtype=np.int64)
        local[ids] = np.arange(n_vert)
        vertices, triangles = vertices[ids], local[face_ids].reshape(-1, 3)
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(triangles), len(vertices))
    bvh.addVertices(vertices)
    bvh.addTriangles(triangles)
    bvh.endModel()
    return bvh


def _mesh_paths(mj: Any) -> list[str]:
    """Each mesh's file; with ``#<asset name>`` when several mesh assets read that file.

    Viewers cache a shape by this path: one file scaled two ways is two shapes.
    """
    files = []
    for mesh in range(mj.nmesh):
        address = int(mj.mesh_pathadr[mesh])
        files.append("" if address < 0 else mj.paths[address:].split(b"\0", 1)[0].decode())
    return [
        f"{file}#{mj.mesh(m).name}" if files.count(file) > 1 or not file else file
        for m, file in enumerate(files)
    ]
