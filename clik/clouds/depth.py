"""Points from a depth image: the pinhole camera model.

A pixel ``(u, v)`` (column, row) of depth ``z`` [m] along the optical axis is the point
``((u - c_x) z / f_x, (v - c_y) z / f_y, z)`` in the camera's optical frame (x right,
y down, z forward, as ROS's ``*_optical_frame`` and OpenCV); the camera's pose in the
world carries it there. Pixels of depth 0 (nothing seen), NaN or beyond ``max_depth``
are left out and counted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from clik.errors import InputError


@dataclass(frozen=True)
class Intrinsics:
    """A pinhole camera's intrinsics [pixels] (ROS ``CameraInfo``'s ``K``: fx, fy, cx, cy)."""

    fx: float
    fy: float
    cx: float
    cy: float

    def __post_init__(self) -> None:
        values = (self.fx, self.fy, self.cx, self.cy)
        if not all(np.isfinite(v) for v in values) or self.fx <= 0.0 or self.fy <= 0.0:
            raise InputError("intrinsics", "finite fx, fy > 0, cx, cy [pixels]", values)


def depth_points(
    depth: np.ndarray,
    intrinsics: Intrinsics,
    camera: pin.SE3,
    scale: float = 1.0,
    max_depth: float = 10.0,
) -> tuple[np.ndarray, int]:
    """The world points of a depth image, and how many pixels were left out.

    Args:
        depth: ``(H, W)`` depths along the optical axis, in units of ``scale`` metres
            (``scale = 0.001`` for a 16-bit image in millimetres).
        intrinsics: The camera's.
        camera: The optical frame's pose in the world.
        scale: Metres per depth unit, > 0.
        max_depth: Depths beyond this [m] are left out (a sensor's far noise).

    Raises:
        InputError: Not a 2-D image, or a bad ``scale`` or ``max_depth``.
    """
    image = np.asarray(depth)
    if image.ndim != 2 or not np.issubdtype(image.dtype, np.number):
        raise InputError("depth", "a 2-D numeric depth image (H, W)", image.shape)
    if not np.isfinite(scale) or scale <= 0.0:
        raise InputError("scale", "metres per depth unit, > 0", scale)
    if not np.isfinite(max_depth) or max_depth <= 0.0:
        raise InputError("max_depth", "a depth > 0 [m]", max_depth)
    z = image.astype(float) * scale
    seen = np.isfinite(z) & (z > 0.0) & (z <= max_depth)
    v, u = np.nonzero(seen)  # row and column of each pixel seen
    z = z[seen]
    optical = np.column_stack(
        [(u - intrinsics.cx) * z / intrinsics.fx, (v - intrinsics.cy) * z / intrinsics.fy, z]
    )
    world = optical @ camera.rotation.T + camera.translation
    return world, int(seen.size - int(seen.sum()))
