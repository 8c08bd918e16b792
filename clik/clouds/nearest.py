"""The nearest voxel sphere to a link, and "nothing near" fast: docs/method.md (C1)-(C2).

:class:`CloudIndex` hashes the voxel spheres in a uniform grid of cell ``h``. A link
(a convex coal shape with a bounding sphere of centre ``o`` and radius ``R``) can be
within the threshold ``d_o`` of sphere ``k`` only if ``|c_k - o| < R + d_o + r_k``;
those spheres lie in the cells met by the ball of radius ``R + d_o + max r``. When
those cells are empty the link has no row and coal is not asked. Otherwise the
candidates are taken in the order of the lower bound ``|c_k - b| - r_k`` of their
distance (``b`` the nearest point of the link's own bounding box: the box holds the
link) and coal is asked (one sphere against the convex link) until that bound
exceeds the best distance found or the threshold.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import coal
import numpy as np

from clik.errors import InputError


@dataclass(frozen=True)
class Nearest:
    """A link's nearest voxel sphere (C1).

    Attributes:
        distance: ``d_k`` [m], negative when the link is inside the sphere.
        on_link: The link's witness point (world) [m].
        on_cloud: The sphere's witness point (world) [m].
        sphere: The sphere's index.
    """

    distance: float
    on_link: np.ndarray
    on_cloud: np.ndarray
    sphere: int


class CloudIndex:
    """Voxel spheres hashed in a uniform grid.

    Args:
        centres: ``(K, 3)`` sphere centres [m] (world).
        radii: ``(K,)`` sphere radii [m].
        cell: Grid cell [m], > 0 (e.g. the threshold plus twice the largest radius).
    """

    def __init__(self, centres: np.ndarray, radii: np.ndarray, cell: float) -> None:
        if not np.isfinite(cell) or cell <= 0.0:
            raise InputError("cell", "a positive grid cell [m]", cell)
        self.centres = np.asarray(centres, dtype=float).reshape(-1, 3)
        self.radii = np.asarray(radii, dtype=float).reshape(-1)
        self.cell = float(cell)
        self.largest = float(self.radii.max()) if len(self.radii) else 0.0
        keys = np.floor(self.centres / self.cell).astype(np.int64)
        self.cells: dict[tuple[int, int, int], np.ndarray] = {}
        order = np.lexsort(keys.T[::-1])
        for key, group in _groups(keys[order], order):
            self.cells[key] = group

    def near(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """Indices of the spheres with ``|c_k - centre| < reach + r_k`` (any order)."""
        span = reach + self.largest
        low = np.floor((centre - span) / self.cell).astype(np.int64)
        high = np.floor((centre + span) / self.cell).astype(np.int64)
        found = [
            self.cells[(x, y, z)]
            for x in range(low[0], high[0] + 1)
            for y in range(low[1], high[1] + 1)
            for z in range(low[2], high[2] + 1)
            if (x, y, z) in self.cells
        ]
        if not found:
            return np.zeros(0, dtype=np.int64)
        candidates = np.concatenate(found)
        gaps = np.linalg.norm(self.centres[candidates] - centre, axis=1)
        return candidates[gaps < reach + self.radii[candidates]]

    def nearest(
        self,
        shape: coal.CollisionGeometry,
        placement: coal.Transform3s,
        bound: tuple[np.ndarray, float],
        threshold: float,
    ) -> Nearest | None:
        """The link's nearest sphere within ``threshold``, or None (no row).

        Args:
            shape: The link's convex shape.
            placement: Its pose in the world.
            bound: Its bounding sphere in the world: centre [m], radius [m].
            threshold: The obstacle threshold ``d_o`` [m].
        """
        centre, radius = bound
        candidates = self.near(centre, radius + threshold)
        if len(candidates) == 0:
            return None
        gaps = _box_gaps(shape, placement, self.centres[candidates])
        # a centre inside the box may be deep inside the link: no bound on its signed distance
        lower = np.where(gaps > 0.0, gaps - self.radii[candidates], -np.inf)
        best: Nearest | None = None
        for i in np.argsort(lower, kind="stable"):
            if lower[i] >= (threshold if best is None else min(best.distance, threshold)):
                break  # no sphere left can be nearer, nor within the threshold
            found = _distance(
                shape, placement, self.centres[candidates[i]], self.radii[candidates[i]]
            )
            if best is None or found[0] < best.distance:
                best = Nearest(found[0], found[1], found[2], int(candidates[i]))
        return best if best is not None and best.distance < threshold else None


def _box_gaps(
    shape: coal.CollisionGeometry, placement: coal.Transform3s, points: np.ndarray
) -> np.ndarray:
    """Distances [m] from points (world) to the shape's box in its own frame: lower bounds.

    The shape lies in its local axis-aligned box, so a point's distance to the box is at
    most its distance to the shape.
    """
    shape.computeLocalAABB()
    box = shape.aabb_local
    low, high = np.asarray(box.min_), np.asarray(box.max_)
    local = (points - np.asarray(placement.getTranslation())) @ np.asarray(placement.getRotation())
    outside = np.maximum(np.maximum(low - local, local - high), 0.0)
    return np.linalg.norm(outside, axis=1)


def _distance(
    shape: coal.CollisionGeometry, placement: coal.Transform3s, centre: np.ndarray, radius: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """Coal's distance from a convex shape to a sphere, and the witness points."""
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    request.enable_signed_distance = True
    ball = coal.Sphere(radius) if radius > 0.0 else coal.Sphere(1e-12)
    coal.distance(shape, placement, ball, coal.Transform3s(np.eye(3), centre), request, result)
    return (
        float(result.min_distance) - (1e-12 if radius == 0.0 else 0.0),
        np.array(result.getNearestPoint1()),
        np.array(result.getNearestPoint2()),
    )


def _groups(keys: np.ndarray, order: np.ndarray) -> list[tuple[tuple[int, int, int], np.ndarray]]:
    """Runs of equal sorted keys: (key, the original indices holding it)."""
    if len(keys) == 0:
        return []
    starts = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
    bounds = np.concatenate([[0], starts, [len(keys)]])
    return [
        ((int(keys[a, 0]), int(keys[a, 1]), int(keys[a, 2])), order[a:b])
        for a, b in itertools.pairwise(bounds)
    ]
