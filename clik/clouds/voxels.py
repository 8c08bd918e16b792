"""Voxel spheres of a point cloud: eq. (C1) of docs/method.md.

The points of each occupied voxel (edge ``voxel`` [m], voxels aligned on the cloud
frame's origin) become one sphere: centre the points' centroid, radius the largest
distance of a point to it. Every point lies in its voxel's sphere, so the clearance to
the spheres is a lower bound of the clearance to the points (C2). The spheres come in
the order of their voxels (x, then y, then z).
"""

from __future__ import annotations

import numpy as np

from clik.errors import InputError


def voxel_spheres(points: np.ndarray, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres ``(K, 3)`` [m] and radii ``(K,)`` [m] of the voxel spheres (C1).

    Args:
        points: ``(N, 3)`` finite points [m].
        voxel: Voxel edge [m], >= 0; 0 keeps every point as a sphere of radius 0.

    Raises:
        InputError: ``voxel`` negative or not finite.
    """
    if not np.isfinite(voxel) or voxel < 0.0:
        raise InputError("voxel", "a finite voxel size >= 0 [m]", voxel)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if voxel == 0.0 or len(points) == 0:
        return points.copy(), np.zeros(len(points))
    keys = np.floor(points / voxel).astype(np.int64)
    low, high = keys.min(axis=0), keys.max(axis=0)
    span = high - low + 1
    flat = ((keys[:, 0] - low[0]) * span[1] + (keys[:, 1] - low[1])) * span[2] + (
        keys[:, 2] - low[2]
    )
    order = np.argsort(flat, kind="stable")
    flat, inside = flat[order], points[order]
    starts = np.concatenate([[0], np.flatnonzero(flat[1:] != flat[:-1]) + 1])
    counts = np.diff(np.append(starts, len(flat)))
    centres: np.ndarray = np.add.reduceat(inside, starts, axis=0) / counts[:, None]
    gaps = inside - np.repeat(centres, counts, axis=0)
    radii = np.maximum.reduceat(np.sqrt(np.einsum("ij,ij->i", gaps, gaps)), starts)
    return centres, radii
