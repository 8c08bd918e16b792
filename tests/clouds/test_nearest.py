"""The nearest voxel sphere to a link: the grid's query against every sphere by coal."""

from __future__ import annotations

import coal
import numpy as np
import pytest

from clik.clouds import voxel_spheres
from clik.clouds.grid import grid_cell, sphere_grid
from clik.clouds.nearest import local_box, nearest_sphere, sphere_distance


def brute_force(shape, placement, centres, radii):
    return min(
        (sphere_distance(shape, placement, c, r).distance, k)
        for k, (c, r) in enumerate(zip(centres, radii, strict=True))
    )


@pytest.mark.parametrize("voxel", [0.0, 0.02])
def test_the_grid_finds_what_every_sphere_by_coal_finds(voxel):
    rng = np.random.default_rng(7)
    table = np.column_stack([rng.uniform(-0.5, 0.5, 3000), rng.uniform(-0.5, 0.5, 3000),
                             rng.normal(0.0, 0.002, 3000)])  # fmt: skip
    centres, radii = voxel_spheres(table, voxel)
    reach = 0.05
    grid = sphere_grid(centres, radii, grid_cell(centres, radii, reach))
    box = coal.Box(0.1, 0.06, 0.2)
    bounds = local_box(box)
    checked = near = 0
    for height in np.linspace(0.08, 0.35, 12):
        for _ in range(3):
            rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            if np.linalg.det(rotation) < 0:
                rotation[:, 0] *= -1.0
            centre = np.array([*rng.uniform(-0.3, 0.3, 2), height])
            placement = coal.Transform3s(rotation, centre)
            found = nearest_sphere(grid, box, bounds, placement, reach)
            truth, _ = brute_force(box, placement, centres, radii)
            checked += 1
            if truth >= reach:
                assert found is None  # nothing within reach: no row, no coal call
                continue
            near += 1
            assert found is not None and found.distance == pytest.approx(truth, abs=1e-9)
            gap = float(np.linalg.norm(found.on_link - found.on_cloud))
            assert gap == pytest.approx(abs(truth), abs=2e-9)  # inside: the depth
    assert checked == 36 and 0 < near < checked  # both cases met


def test_an_empty_neighbourhood_asks_nothing():
    grid = sphere_grid(np.array([[5.0, 5.0, 5.0]]), np.array([0.01]), 0.1)
    ball = coal.Sphere(0.1)
    assert nearest_sphere(grid, ball, local_box(ball), coal.Transform3s(), 0.05) is None


def test_the_grid_keeps_every_sphere_once_in_cell_order():
    rng = np.random.default_rng(3)
    centres = rng.uniform(-1.0, 1.0, (500, 3))
    grid = sphere_grid(centres, np.full(500, 0.01), 0.2)
    assert sorted(grid.order.tolist()) == list(range(500))
    assert grid.start[0] == 0 and grid.start[-1] == 500 and np.all(np.diff(grid.start) >= 0)
    with pytest.raises(Exception, match="cell"):
        sphere_grid(centres, np.full(500, 0.01), 0.0)


def test_the_engine_builds_the_same_spheres_and_grid():
    from clik.clouds import CloudObstacle
    from clik.engine import load

    rng = np.random.default_rng(5)
    points = np.vstack([rng.uniform(-0.4, 0.4, (4000, 3)) * [1.0, 1.0, 0.05],
                        [[np.nan, 0.0, 0.0]]])  # fmt: skip
    for voxel in (0.0, 0.01):
        cloud = CloudObstacle("scan", points, voxel, position=(0.1, -0.2, 0.3), rpy=(0.3, 0.2, 0.1))
        grid = cloud.spheres(0.05)
        built, dropped = load().CloudConfig.build(
            "scan", points, voxel, cloud.rotation, cloud.position, 0.05
        )
        assert dropped == cloud.dropped == 1
        np.testing.assert_allclose(built.centres, grid.centres, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(built.radii, grid.radii, rtol=0.0, atol=1e-12)
        assert built.cell == pytest.approx(grid.cell, abs=1e-15)
        assert list(built.dims) == list(grid.dims)
        assert list(built.order) == list(grid.order) and list(built.start) == list(grid.start)
