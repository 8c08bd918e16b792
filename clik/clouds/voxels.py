"""Voxel spheres of a point cloud: eq. (C1) of docs/method.md.

The points of each occupied voxel (edge ``voxel`` [m], voxels aligned on the cloud
frame's origin) become one sphere: centre the points' centroid, radius the largest
distance of a point to it. Every point lies in its voxel's sphere, so the clearance to
the spheres is a lower bound of the clearance to the points (C2).
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
    _, owner, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    owner = owner.reshape(-1)
    centres = np.zeros((len(counts), 3))
    np.add.at(centres, owner, points)
    centres /= counts[:, None]
    radii = np.zeros(len(counts))
    np.maximum.at(radii, owner, np.linalg.norm(points - centres[owner], axis=1))
    return centres, radii
