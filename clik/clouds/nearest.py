"""A link's nearest voxel sphere within a reach, fast when none is: docs/method.md (C1)-(C2).

The link is a convex coal shape in its own axis-aligned box ``[lo, hi]`` (its frame).
Only spheres in the grid cells met by the link's world box grown by ``reach`` (or the
distance of a hinted sphere, the pair's last nearest, asked first) and the largest
radius can be nearer; when those cells are empty coal is not asked.
Otherwise each candidate's distance has the lower bound ``|c_k - b(c_k)| - r_k``
(``b(c)`` the nearest point of the link's box to ``c``; none for a centre inside the
box), and coal is asked (the link against one sphere) in the order of that bound until
it reaches the best distance found or ``reach``. Each answer with the centre outside
the link gives a separating plane (through the link's nearest point, normal to it): a
sphere that a plane met so far keeps as far as the best is not asked (on a flat table
under a flat link the box bound ties for every sphere below; the planes do not). The
compiled engine's
``src/engine/constraints/cloud_query.cpp`` does the same, step for step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np

from clik.clouds.grid import SphereGrid, cells_of_box

CLOUD_GJK_TOLERANCE = 1e-9
"""coal's GJK/EPA tolerance of a link-sphere distance [m] (as the collision scene's)."""

MAX_PLANES = 4
"""Separating planes a query keeps (the latest) to skip spheres they keep far."""

POINT_RADIUS = 1e-9
"""The radius [m] coal is given for a sphere of radius 0 (a point); its distance is
corrected by it."""


@dataclass(frozen=True)
class Nearest:
    """A link's nearest voxel sphere (C1).

    Attributes:
        distance: ``d_k`` [m], negative when the link is inside the sphere.
        on_link: The link's witness point (world) [m].
        on_cloud: The sphere's witness point (world) [m].
        normal: coal's unit normal from the link toward the sphere.
        sphere: The sphere's index.
    """

    distance: float
    on_link: np.ndarray
    on_cloud: np.ndarray
    normal: np.ndarray
    sphere: int


def local_box(shape: coal.CollisionGeometry) -> tuple[np.ndarray, np.ndarray]:
    """The shape's axis-aligned box in its own frame: ``(lo, hi)`` [m]."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    return np.array(box.min_, dtype=float), np.array(box.max_, dtype=float)


def nearest_sphere(
    grid: SphereGrid,
    shape: coal.CollisionGeometry,
    box: tuple[np.ndarray, np.ndarray],
    placement: coal.Transform3s,
    reach: float,
    hint: int = -1,
) -> Nearest | None:
    """The link's nearest sphere if nearer than ``reach`` [m], else None.

    Args:
        grid: The cloud's spheres.
        shape: The link's convex shape.
        box: Its local box (:func:`local_box`).
        placement: Its pose in the world.
        reach: How far to look [m] (the threshold plus a search margin).
        hint: A sphere likely to be the nearest (the last one found), asked first: its
            distance narrows the cells searched; -1: none.
    """
    best: Nearest | None = None
    planes = np.zeros((0, 4))  # separating planes met so far: the link in n . x <= offset
    if 0 <= hint < len(grid.radii):
        best = sphere_distance(shape, placement, grid.centres[hint], float(grid.radii[hint]), hint)
        planes = _with_plane(planes, grid.centres[hint], best)
    bar = reach if best is None else min(best.distance, reach)
    rotation = np.asarray(placement.getRotation())
    translation = np.asarray(placement.getTranslation())
    lo, hi = box
    centre = rotation @ (0.5 * (lo + hi)) + translation
    half = np.abs(rotation) @ (0.5 * (hi - lo)) + (bar + grid.largest)
    candidates = cells_of_box(grid, centre - half, centre + half)
    candidates = candidates[candidates != hint]
    local = (grid.centres[candidates] - translation) @ rotation
    outside = np.maximum(np.maximum(lo - local, local - hi), 0.0)
    gaps = np.sqrt(np.einsum("ij,ij->i", outside, outside))
    # a centre inside the box may be deep inside the link: no bound on its signed distance
    radii = grid.radii[candidates]
    lower = np.where(gaps > 0.0, gaps - radii, -np.inf)
    if len(planes):  # the hint's plane bounds every sphere too (a sphere inside it as well)
        lower = np.maximum(lower, planes_bound(planes, grid.centres[candidates]) - radii)
    keep = lower < bar
    candidates, lower = candidates[keep], lower[keep]
    for i in np.argsort(lower, kind="stable"):
        bar = reach if best is None else min(best.distance, reach)
        if lower[i] >= bar:
            break  # no sphere left can be nearer, nor within reach
        k = int(candidates[i])
        centre, radius = grid.centres[k], float(grid.radii[k])
        if len(planes) and plane_bound(planes, centre) - radius >= bar:
            continue  # a plane met before keeps it at least that far
        found = sphere_distance(shape, placement, centre, radius, k)
        if best is None or found.distance < best.distance:
            best = found
        planes = _with_plane(planes, centre, found)
    return best if best is not None and best.distance < reach else None


def _with_plane(planes: np.ndarray, centre: np.ndarray, found: Nearest) -> np.ndarray:
    """The latest :data:`MAX_PLANES` planes, with the one ``found`` gives if any."""
    plane = separating_plane(centre, found)
    return planes if plane is None else np.vstack([planes[-(MAX_PLANES - 1) :], plane])


def separating_plane(centre: np.ndarray, found: Nearest) -> np.ndarray | None:
    """``(n, offset)``: the plane through the link's nearest point to ``centre``, normal to it.

    The link (convex) lies in ``n . x <= offset`` when the centre is outside it; None
    when it is not (a sphere whose centre is inside the link gives no plane).
    """
    gap = centre - found.on_link
    norm = math.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])
    if not found.distance > 0.0 or norm <= 0.0:
        return None
    n = gap / norm
    offset = n[0] * found.on_link[0] + n[1] * found.on_link[1] + n[2] * found.on_link[2]
    return np.array([n[0], n[1], n[2], offset])


def planes_bound(planes: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """:func:`plane_bound` of each of ``centres`` (K, 3) [m]."""
    gaps = [
        n[0] * centres[:, 0] + n[1] * centres[:, 1] + n[2] * centres[:, 2] - n[3] for n in planes
    ]
    return np.max(gaps, axis=0)


def plane_bound(planes: np.ndarray, centre: np.ndarray) -> float:
    """A lower bound of the distance from ``centre`` to the link: its largest plane gap [m]."""
    gaps = planes[:, 0] * centre[0] + planes[:, 1] * centre[1] + planes[:, 2] * centre[2]
    return float((gaps - planes[:, 3]).max())


def sphere_distance(
    shape: coal.CollisionGeometry,
    placement: coal.Transform3s,
    centre: np.ndarray,
    radius: float,
    sphere: int = -1,
) -> Nearest:
    """Coal's signed distance from a convex shape to a sphere, and the witness points."""
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    request.enable_signed_distance = True
    request.gjk_tolerance = request.epa_tolerance = CLOUD_GJK_TOLERANCE
    ball = max(radius, POINT_RADIUS)
    coal.distance(
        shape, placement, coal.Sphere(ball), coal.Transform3s(np.eye(3), centre), request, result
    )
    return Nearest(
        float(result.min_distance) + (ball - radius),
        np.array(result.getNearestPoint1()),
        np.array(result.getNearestPoint2()),
        np.array(result.normal),
        sphere,
    )
