"""What a view draws of the clouds: a few of each cloud's world points, kept with the run.

A run's ``info`` goes to JSON and holds no points; the points drawn are kept in
``result.extra`` (saved with the run, so ``clik show`` of an output folder draws them):
``cloud_points`` ``(M, 3)`` float32 world points [m], every cloud's in turn, and
``cloud_points_index`` ``(M,)`` the index in ``info["clouds"]`` of each point's cloud.
A cloud of more than :data:`MAX_DRAWN_POINTS` points is thinned by a uniform stride
(every ``k``-th point, in file order).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from clik.clouds.cloud_obstacle import CloudObstacle

MAX_DRAWN_POINTS = 20_000
"""Most points drawn of one cloud (a browser draws that many without effort)."""


def drawn_points(points: np.ndarray, limit: int = MAX_DRAWN_POINTS) -> np.ndarray:
    """At most ``limit`` of ``points`` (N, 3), every ``ceil(N / limit)``-th, as float32."""
    stride = max(1, math.ceil(len(points) / limit))
    return np.ascontiguousarray(np.asarray(points)[::stride], dtype=np.float32).reshape(-1, 3)


def drawn_clouds(clouds: Sequence[CloudObstacle]) -> tuple[np.ndarray, np.ndarray]:
    """``cloud_points`` (M, 3) float32 [m] and ``cloud_points_index`` (M,) int32 of clouds."""
    points = [drawn_points(c.world) for c in clouds]
    index = [np.full(len(p), i, dtype=np.int32) for i, p in enumerate(points)]
    return (
        np.concatenate([np.empty((0, 3), np.float32), *points]),
        np.concatenate([np.empty(0, np.int32), *index]),
    )
