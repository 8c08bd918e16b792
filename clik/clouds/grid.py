"""The voxel spheres in a uniform grid: docs/method.md, "Obstacles from point clouds".

A grid of cubic cells of edge ``cell`` [m] over the spheres' centres, stored as one
list of sphere indices sorted by cell (x, then y, then z) and each cell's start in it
(compressed rows), so the spheres of a column of cells are one slice. Both engines
read the same arrays (the compiled one checks them), so a query meets the same
spheres in the same order in both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from clik.errors import InputError

MAX_GRID_SPAN = 128
"""Most cells along a cloud's longest side (the cell grows for a wider cloud)."""

MIN_CELL = 1e-3
"""Smallest grid cell [m]."""


@dataclass(frozen=True)
class SphereGrid:
    """Voxel spheres hashed in a uniform grid.

    Attributes:
        centres: ``(K, 3)`` sphere centres [m] (world).
        radii: ``(K,)`` sphere radii [m].
        cell: The grid's cell edge [m].
        low: The grid's lowest corner [m] (the centres' smallest coordinates).
        dims: Cells along x, y, z.
        order: ``(K,)`` sphere indices sorted by cell.
        start: ``(cells + 1,)`` each cell's first position in ``order``.
        largest: The largest radius [m].
    """

    centres: np.ndarray
    radii: np.ndarray
    cell: float
    low: np.ndarray
    dims: np.ndarray
    order: np.ndarray
    start: np.ndarray
    largest: float


def grid_cell(centres: np.ndarray, radii: np.ndarray, threshold: float) -> float:
    """The cell [m]: the threshold plus a sphere's diameter, or wider for a wide cloud."""
    extent = float(np.ptp(centres, axis=0).max()) if len(centres) else 0.0
    largest = float(radii.max()) if len(radii) else 0.0
    return max(2.0 * largest, extent / MAX_GRID_SPAN, MIN_CELL)


def sphere_grid(centres: np.ndarray, radii: np.ndarray, cell: float) -> SphereGrid:
    """The grid of the spheres (their arrays kept read-only).

    Raises:
        InputError: ``cell`` not a positive number, centres not ``(K, 3)`` finite, radii
            not ``(K,)`` finite and >= 0.
    """
    if not np.isfinite(cell) or cell <= 0.0:
        raise InputError("cell", "a positive grid cell [m]", cell)
    centres = np.ascontiguousarray(centres, dtype=float).reshape(-1, 3)
    radii = np.ascontiguousarray(radii, dtype=float).reshape(-1)
    if len(radii) != len(centres) or not np.all(np.isfinite(centres)):
        raise InputError("centres", "(K, 3) finite sphere centres [m] with K radii", centres.shape)
    if not np.all(np.isfinite(radii)) or np.any(radii < 0.0):
        raise InputError("radii", "finite sphere radii >= 0 [m]", radii.min(initial=0.0))
    low = centres.min(axis=0) if len(centres) else np.zeros(3)
    high = centres.max(axis=0) if len(centres) else np.zeros(3)
    dims = np.floor((high - low) / cell).astype(np.int64) + 1
    cells = np.minimum(np.floor((centres - low) / cell).astype(np.int64), dims - 1)
    flat = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]
    order = np.argsort(flat, kind="stable").astype(np.int32)
    start = np.searchsorted(flat[order], np.arange(int(np.prod(dims)) + 1)).astype(np.int32)
    for array in (centres, radii, low, dims, order, start):
        array.flags.writeable = False
    largest = float(radii.max()) if len(radii) else 0.0
    return SphereGrid(centres, radii, float(cell), low, dims, order, start, largest)


def cells_of_box(grid: SphereGrid, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The spheres of the cells a world box ``[low, high]`` [m] meets, cell by cell."""
    a = np.floor((low - grid.low) / grid.cell).astype(np.int64)
    b = np.floor((high - grid.low) / grid.cell).astype(np.int64)
    if np.any(b < 0) or np.any(a >= grid.dims) or len(grid.order) == 0:
        return np.zeros(0, dtype=np.int32)
    a, b = np.maximum(a, 0), np.minimum(b, grid.dims - 1)
    ny, nz = int(grid.dims[1]), int(grid.dims[2])
    slices = [
        grid.order[grid.start[(x * ny + y) * nz + a[2]] : grid.start[(x * ny + y) * nz + b[2] + 1]]
        for x in range(a[0], b[0] + 1)
        for y in range(a[1], b[1] + 1)
    ]
    return np.concatenate(slices) if slices else np.zeros(0, dtype=np.int32)
