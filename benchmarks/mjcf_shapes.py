"""Shapes of :mod:`benchmarks.mjcf_agreement`: geoms matched, support functions, probes.

MuJoCo's collision geoms (clik's rule: ``contype`` or ``conaffinity`` not zero, or group
3) are paired with clik's collision objects (:func:`match_geoms`), compared as convex
sets through their support functions (a mesh: the convex hull MuJoCo collides,
``mesh_graph``), and probed with small spheres (:func:`probe`: ``mj_geomDistance``
against coal's distance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

PROBE_RADIUS = 0.01
"""Radius of a probe sphere [m]."""
PROBE_OFFSETS = (0.02, 0.035, 0.05)
"""Gaps between a probe sphere and a geom's supporting plane [m] (one probe per offset)."""
PROBE_DISTMAX = 10.0
"""``distmax`` of ``mj_geomDistance`` [m] (above every probe's distance)."""
SEED = 0
"""Seed of the probe directions (plus one)."""


def pruned_spec(path: Path) -> tuple[Any, int] | None:
    """The file's ``MjSpec`` without visual-only geoms of absent meshes, and their count.

    None when an absent mesh is used by a geom that can touch.
    """
    import mujoco

    spec = mujoco.MjSpec.from_file(str(path))
    folder = path.parent / (spec.meshdir or "")
    absent = {mesh.name for mesh in spec.meshes if not (folder / mesh.file).exists()}
    users = [g for g in spec.geoms if g.meshname in absent]
    if any(g.contype or g.conaffinity for g in users):
        return None
    for geom in users:
        spec.delete(geom)
    for mesh in [m for m in spec.meshes if m.name in absent]:
        spec.delete(mesh)
    return spec, len(users)


_MJ_KIND = {2: "Sphere", 3: "Capsule", 4: "Ellipsoid", 5: "Cylinder", 6: "Box", 7: "mesh"}


def collision_geoms(m: Any) -> list[int]:
    """MuJoCo's collision geoms of the robot (clik's rule), not a plane.

    ``contype`` or ``conaffinity`` not zero, or group 3 (the Menagerie's collision group,
    contacts off for explicit pairs).
    """
    return [
        g
        for g in range(m.ngeom)
        if (m.geom_contype[g] or m.geom_conaffinity[g] or m.geom_group[g] == 3)
        and int(m.geom_type[g]) not in (0, 1)
        and m.geom_bodyid[g] != 0
    ]


def _clik_kind(geometry_object: Any) -> str:
    """A clik (coal) shape's kind as :data:`_MJ_KIND` names it ("mesh" for meshes)."""
    name = type(geometry_object.geometry).__name__
    return "mesh" if name.startswith(("BVHModel", "Convex")) else name


def match_geoms(
    mujoco: Any, m: Any, model: Any, geometry: Any, notes: list[str]
) -> list[tuple[int, int]]:
    """``(MuJoCo geom id, clik geometry index)`` of MuJoCo's collision geoms.

    A named geom is clik's object of the same name (Pinocchio keeps a geom's name). The
    others, body by body, in order: Pinocchio names an unnamed geom ``<body>Geom_<k>``
    (``k`` counting its body's geoms), so clik's unmatched objects of a body (its
    parent frame) are paired in order with MuJoCo's unnamed collision geoms of that
    body, when their kinds (sphere, box, mesh...) agree. What stays unpaired is noted.
    """
    by_name = {go.name: k for k, go in enumerate(geometry.geometryObjects)}
    used: set[int] = set()
    pairs: list[tuple[int, int]] = []
    rest: dict[str, list[int]] = {}
    for g in collision_geoms(m):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
        if name and name in by_name:
            pairs.append((g, by_name[name]))
            used.add(by_name[name])
        else:
            body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[g])) or ""
            rest.setdefault(body, []).append(g)
    clik_rest: dict[str, list[int]] = {}
    for k, go in enumerate(geometry.geometryObjects):
        if k not in used:
            clik_rest.setdefault(str(model.frames[go.parentFrame].name), []).append(k)
    unpaired: list[str] = []
    kinds_differ = 0
    for body, geoms in rest.items():
        theirs = clik_rest.pop(body, [])
        for n, g in enumerate(geoms):
            if n >= len(theirs):
                unpaired.append(f"{body}#{g}")
                continue
            k = theirs[n]
            if _MJ_KIND.get(int(m.geom_type[g])) != _clik_kind(geometry.geometryObjects[k]):
                kinds_differ += 1
                continue
            pairs.append((g, k))
        clik_left = theirs[len(geoms) :]
        if clik_left:
            clik_rest[body] = clik_left
    if unpaired:
        notes.append(f"{len(unpaired)} MuJoCo collision geoms without clik's: {unpaired[:5]}")
    if kinds_differ:
        notes.append(f"{kinds_differ} geoms paired by order have different shapes (skipped)")
    extra = [geometry.geometryObjects[k].name for ks in clik_rest.values() for k in ks]
    if extra:
        notes.append(f"{len(extra)} clik collision objects not MuJoCo collision geoms: {extra[:5]}")
    return pairs


def fibonacci_sphere(n: int) -> np.ndarray:
    """``n`` unit directions spread over the sphere (rows)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


Support = Any  # a callable: directions (n, 3) -> support values (n,)


def _primitive_support(
    kind: str, sizes: np.ndarray, rotation: np.ndarray, centre: np.ndarray
) -> Support:
    """The support function of a placed primitive shape (MuJoCo's and coal's sizes alike).

    ``sizes``: sphere ``(r,)``, capsule and cylinder ``(r, half length)`` along the
    local z axis, box half sides, ellipsoid radii.
    """

    def support(directions: np.ndarray) -> np.ndarray:
        local = directions @ rotation  # the directions in the shape's frame
        value = directions @ centre
        if kind == "Sphere":
            return value + sizes[0]
        if kind == "Capsule":
            return value + sizes[1] * np.abs(local[:, 2]) + sizes[0]
        if kind == "Cylinder":
            radial = np.sqrt(np.maximum(0.0, 1.0 - local[:, 2] ** 2))
            return value + sizes[1] * np.abs(local[:, 2]) + sizes[0] * radial
        if kind == "Box":
            return value + np.abs(local) @ sizes[:3]
        if kind == "Ellipsoid":
            return value + np.sqrt(((local * sizes[:3]) ** 2).sum(axis=1))
        raise ValueError(kind)

    return support


def _points_support(points: np.ndarray) -> Support:
    """The support function of the convex hull of world points."""
    return lambda directions: np.max(directions @ points.T, axis=1)


def _mujoco_vertices(m: Any, d: Any, g: int) -> np.ndarray:
    """A mesh geom's vertices in the world (MuJoCo's re-centred vertices, placed).

    Those of the convex hull MuJoCo collides (``mesh_graph``, ``maxhullvert`` applied)
    when it computed one.
    """
    mesh = int(m.geom_dataid[g])
    start, count = int(m.mesh_vertadr[mesh]), int(m.mesh_vertnum[mesh])
    vertices = np.asarray(m.mesh_vert[start : start + count], dtype=float)
    graph = int(m.mesh_graphadr[mesh])
    if graph >= 0:  # numvert, numface, vert_edgeadr[numvert], vert_globalid[numvert], ...
        n_vert = int(m.mesh_graph[graph])
        ids = np.asarray(m.mesh_graph[graph + 2 + n_vert : graph + 2 + 2 * n_vert], dtype=int)
        vertices = vertices[ids]
    return vertices @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]


def mujoco_support(mujoco: Any, m: Any, d: Any, g: int, directions: np.ndarray) -> Support:
    """The support function of MuJoCo's geom ``g`` in the world, or None (unknown type)."""
    kind = _MJ_KIND.get(int(m.geom_type[g]))
    if kind is None:
        return None
    if kind == "mesh":
        return _points_support(_mujoco_vertices(m, d, g))
    rotation = d.geom_xmat[g].reshape(3, 3)
    return _primitive_support(kind, np.asarray(m.geom_size[g]), rotation, d.geom_xpos[g])


def _coal_sizes(shape: Any, kind: str) -> np.ndarray:
    """A coal primitive's sizes in MuJoCo's convention (:func:`_primitive_support`)."""
    if kind == "Sphere":
        return np.array([shape.radius])
    if kind in ("Capsule", "Cylinder"):
        return np.array([shape.radius, shape.halfLength])
    if kind == "Box":
        return np.asarray(shape.halfSide, dtype=float)
    return np.asarray(shape.radii, dtype=float)


def _clik_vertices(geometry_object: Any) -> np.ndarray:
    """A clik mesh's vertices in its own frame (as coal holds them, scaled)."""
    shape = geometry_object.geometry
    if hasattr(shape, "vertices"):
        return np.asarray(shape.vertices(), dtype=float)
    return np.asarray(shape.points(), dtype=float)


def clik_support(geometry_object: Any, placement: Any) -> Support:
    """The support function of clik's geometry object at ``placement``, or None."""
    kind = _clik_kind(geometry_object)
    rotation, centre = placement.rotation, placement.translation
    if kind == "mesh":
        return _points_support(_clik_vertices(geometry_object) @ rotation.T + centre)
    if kind not in _MJ_KIND.values():
        return None
    sizes = _coal_sizes(geometry_object.geometry, kind)
    return _primitive_support(kind, sizes, rotation, centre)


def _coal_shape(geometry_object: Any) -> Any:
    """The shape clik's collision scene uses: a mesh's convex hull, else the shape."""
    shape = geometry_object.geometry
    if _clik_kind(geometry_object) != "mesh" or not hasattr(shape, "buildConvexHull"):
        return shape
    if shape.convex is None:
        shape.buildConvexHull(True, "Qt")
    return shape.convex


def probe(
    mujoco: Any,
    path: Path,
    m: Any,
    robot: Any,
    mapping: Any,
    configurations: Sequence[tuple[str, np.ndarray]],
    pairs: Sequence[tuple[int, int]],
    result: dict[str, Any],
) -> None:
    """Probe spheres off each paired geom: MuJoCo's and coal's distances compared."""
    import coal
    import pinocchio as pin

    pruned = pruned_spec(path)
    if pruned is None:
        result["notes"].append("an absent mesh can touch: no probes")
        return
    spec = pruned[0]
    body = spec.worldbody.add_body(name="clik_agreement_probe", mocap=True)
    body.add_geom(
        name="clik_agreement_probe",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[PROBE_RADIUS, 0.0, 0.0],
        contype=0,
        conaffinity=0,
    )
    mp = spec.compile()
    probe = mujoco.mj_name2id(mp, mujoco.mjtObj.mjOBJ_GEOM, "clik_agreement_probe")
    same = mp.ngeom == m.ngeom + 1 and all(
        mp.geom_type[g] == m.geom_type[g] and mp.geom_bodyid[g] == m.geom_bodyid[g]
        for g, _ in pairs
    )
    if not same:
        result["notes"].append("probe model's geoms differ from the file's: no probes")
        return
    dp = mujoco.MjData(mp)
    model, geometry = robot.model, robot.collision_model
    data, geometry_data = model.createData(), geometry.createData()
    rng = np.random.default_rng(SEED + 1)
    sphere = coal.Sphere(PROBE_RADIUS)
    request = coal.DistanceRequest()
    worst, count, skipped = 0.0, 0, 0
    for _, qpos in configurations[:2]:  # the reference and one random configuration
        dp.qpos[:] = qpos
        mujoco.mj_kinematics(mp, dp)
        pin.framesForwardKinematics(model, data, mapping.q(qpos))
        pin.updateGeometryPlacements(model, data, geometry, geometry_data)
        for g, k in pairs:
            geometry_object = geometry.geometryObjects[k]
            if _clik_kind(geometry_object) == "Ellipsoid":
                skipped += 1  # clik's collision scene skips ellipsoids
                continue
            shape = _coal_shape(geometry_object)
            support = mujoco_support(mujoco, mp, dp, g, np.zeros((1, 3)))
            placement = geometry_data.oMg[k]
            tf = coal.Transform3s(placement.rotation, placement.translation)
            for offset in PROBE_OFFSETS:
                direction = rng.normal(size=3)
                direction /= np.linalg.norm(direction)
                height = float(support(direction[None, :])[0])
                centre = direction * (height + PROBE_RADIUS + offset)
                dp.mocap_pos[mp.body_mocapid[mp.geom_bodyid[probe]]] = centre
                mujoco.mj_kinematics(mp, dp)
                theirs = mujoco.mj_geomDistance(mp, dp, g, probe, PROBE_DISTMAX, None)
                res = coal.DistanceResult()
                tf_probe = coal.Transform3s(np.eye(3), centre)
                ours = coal.distance(shape, tf, sphere, tf_probe, request, res)
                worst = max(worst, abs(float(theirs) - float(ours)))
                count += 1
    result["probes"] = count
    if count:
        result["probe_distance_m"] = worst
    if skipped:
        result["notes"].append(f"ellipsoids not probed (clik's scene skips them): {skipped}")
