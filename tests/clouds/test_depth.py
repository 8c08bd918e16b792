"""Depth images: a rendered plane comes back as that plane, in the world."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from clik.clouds.depth import Intrinsics, depth_points
from clik.errors import InputError


def test_a_wall_seen_head_on_comes_back_where_it_is():
    k = Intrinsics(fx=500.0, fy=520.0, cx=320.0, cy=240.0)
    depth = np.full((480, 640), 1500, dtype=np.uint16)  # a wall 1.5 m ahead, in millimetres
    depth[:10, :] = 0  # nothing seen
    depth[10, 0] = 20000  # beyond max_depth
    # the optical frame looks along the world's +x (z forward -> x, x right -> -y, y down -> -z)
    rotation = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    camera = pin.SE3(rotation, np.array([0.2, 0.0, 1.0]))
    points, left_out = depth_points(depth, k, camera, scale=0.001, max_depth=5.0)
    assert left_out == 10 * 640 + 1
    np.testing.assert_allclose(points[:, 0], 1.7, atol=1e-12)  # the wall at x = 0.2 + 1.5
    # the pixel at the principal point is straight ahead; the image's corners span the frustum
    centre = points[np.argmin(np.abs(points[:, 1]) + np.abs(points[:, 2] - 1.0))]
    np.testing.assert_allclose(centre, [1.7, 0.0, 1.0], atol=1e-12)
    assert points[:, 1].max() == pytest.approx(320.0 * 1.5 / 500.0)  # u = 0: left, +y
    assert points[:, 2].min() == pytest.approx(1.0 - (479 - 240.0) * 1.5 / 520.0)  # bottom row


def test_bad_images_and_settings_are_named():
    k = Intrinsics(500.0, 500.0, 1.0, 1.0)
    with pytest.raises(InputError, match="depth"):
        depth_points(np.zeros(5), k, pin.SE3.Identity())
    with pytest.raises(InputError, match="scale"):
        depth_points(np.ones((2, 2)), k, pin.SE3.Identity(), scale=0.0)
    with pytest.raises(InputError, match="intrinsics"):
        Intrinsics(0.0, 500.0, 1.0, 1.0)


def test_a_depth_image_is_a_cloud_obstacle_in_the_cameras_frame():
    from clik.clouds import CloudObstacle

    k = Intrinsics(fx=500.0, fy=520.0, cx=320.0, cy=240.0)
    depth = np.full((48, 64), 1.5)
    depth[0, :] = np.nan  # nothing seen
    # the optical frame looking along the world's +x: rpy of that rotation
    rotation = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    cloud = CloudObstacle.from_depth(
        "camera", depth, k, voxel=0.0, position=(0.2, 0.0, 1.0), rpy=pin.rpy.matrixToRpy(rotation)
    )
    assert cloud.dropped == 64 and len(cloud.local) == 47 * 64
    np.testing.assert_allclose(cloud.world[:, 0], 1.7, atol=1e-12)
    np.testing.assert_allclose(cloud.spheres(0.05).centres[:, 0], 1.7, atol=1e-12)
