"""The nearest voxel sphere to a link: the hashed query against every sphere by coal."""

from __future__ import annotations

import coal
import numpy as np
import pytest

from clik.clouds import voxel_spheres
from clik.clouds.nearest import CloudIndex


def brute_force(shape, placement, centres, radii):
    best = (np.inf, -1)
    for k, (c, r) in enumerate(zip(centres, radii, strict=True)):
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        request.enable_signed_distance = True
        coal.distance(shape, placement, coal.Sphere(max(r, 1e-12)),
                      coal.Transform3s(np.eye(3), c), request, result)  # fmt: skip
        d = result.min_distance - (1e-12 if r == 0.0 else 0.0)
        best = min(best, (d, k))
    return best


@pytest.mark.parametrize("voxel", [0.0, 0.02])
def test_the_index_finds_what_every_sphere_by_coal_finds(voxel):
    rng = np.random.default_rng(7)
    table = np.column_stack([rng.uniform(-0.5, 0.5, 3000), rng.uniform(-0.5, 0.5, 3000),
                             rng.normal(0.0, 0.002, 3000)])  # fmt: skip
    centres, radii = voxel_spheres(table, voxel)
    threshold = 0.05
    index = CloudIndex(centres, radii, cell=threshold + 2.0 * radii.max() + 0.01)
    box = coal.Box(0.1, 0.06, 0.2)
    bound_radius = float(np.linalg.norm([0.05, 0.03, 0.1]))
    checked = near = 0
    for height in np.linspace(0.08, 0.35, 12):
        for _ in range(3):
            rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            if np.linalg.det(rotation) < 0:
                rotation[:, 0] *= -1.0
            centre = np.array([*rng.uniform(-0.3, 0.3, 2), height])
            placement = coal.Transform3s(rotation, centre)
            found = index.nearest(box, placement, (centre, bound_radius), threshold)
            truth, _ = brute_force(box, placement, centres, radii)
            checked += 1
            if truth >= threshold:
                assert found is None  # nothing within the threshold: no row
                continue
            near += 1
            assert found is not None and found.distance == pytest.approx(truth, abs=1e-9)
            gap = float(np.linalg.norm(found.on_link - found.on_cloud))
            assert gap == pytest.approx(abs(truth), abs=1e-9)  # inside: the depth
    assert checked == 36 and 0 < near < checked  # both cases met


def test_an_empty_neighbourhood_asks_nothing():
    index = CloudIndex(np.array([[5.0, 5.0, 5.0]]), np.array([0.01]), cell=0.1)
    assert len(index.near(np.zeros(3), 0.5)) == 0
    assert index.nearest(coal.Sphere(0.1), coal.Transform3s(), (np.zeros(3), 0.1), 0.05) is None
