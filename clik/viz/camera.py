"""Default view: the scene centred on the motion, seen from above or at three quarters.

meshcat 0.3.2's orbit controls always turn about the world origin, and
Pinocchio's ``setCameraTarget`` fails with it. So the scene is moved instead:
the content (``/meshcat``), the grid and the axes are translated by ``-c``, with
``c`` the centre of everything the run shows, and the camera is placed at a
distance that fits it. A planar arm (all frames in one ``z = const`` plane) is
seen from above, ``x`` to the right and ``y`` up; a spatial arm from the front
right, above.

The camera object lives in meshcat's y-up frame ``/Cameras/default/rotated``
(``R_x(pi/2)`` of the world): a world offset ``(x, y, z)`` is ``(x, z, -y)`` there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from clik.viz.commands import Command, set_property, set_transform

FIELD_OF_VIEW = math.radians(75.0)
"""Vertical field of view of meshcat's default camera [rad]."""

ASPECT = 4.0 / 3.0
"""Width over height assumed for the viewer's window (fits a landscape window)."""

SPATIAL_DIRECTION = np.array([1.0, -1.1, 0.75])
"""Direction from the scene centre to the camera for a spatial arm (world frame)."""

CAMERA_PATH = "/Cameras/default/rotated/<object>"
"""Scene path of the default camera."""


@dataclass(frozen=True)
class View:
    """Where the scene is centred and where the camera sits.

    Attributes:
        center: Centre of the shown content in the world frame [m]; the scene is
            translated by ``-center``.
        offset: Camera position relative to the centre, world frame [m].
        planar: True when the run lies in a horizontal plane (top view).
    """

    center: np.ndarray
    offset: np.ndarray
    planar: bool

    def commands(self) -> list[Command]:
        """Commands moving the content, grid and axes, and placing the camera."""
        shift = np.eye(4)
        shift[:3, 3] = -self.center
        x, y, z = (float(v) for v in self.offset)
        return [
            set_transform("/meshcat", shift),
            set_transform("/Grid", shift),
            set_transform("/Axes", shift),
            set_property(CAMERA_PATH, "position", [x, z, -y]),
        ]


def is_planar(points: np.ndarray) -> bool:
    """True when ``points`` (M, 3) lie in one horizontal plane (a planar arm in x-y)."""
    points = _finite(points)
    if len(points) == 0:
        return False
    low, high = points.min(axis=0), points.max(axis=0)
    return bool(high[2] - low[2] <= 1e-6 + 1e-3 * float(np.max(high[:2] - low[:2])))


def _finite(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    return points[np.all(np.isfinite(points), axis=1)]


def default_view(points: np.ndarray, planar: bool, margin: float = 1.25) -> View:
    """The view that fits ``points`` (M, 3) [m]: every point the run shows.

    Args:
        points: Frame origins over the animation, paths, obstacle extents.
        planar: Look down the z axis (see :func:`is_planar`); else a three-quarter view.
        margin: Extra room around the content (1 = touching the edges).
    """
    points = _finite(points)
    if len(points) == 0:
        return View(np.zeros(3), np.array([0.0, -1e-3, 2.0]), planar=True)
    low, high = points.min(axis=0), points.max(axis=0)
    center = 0.5 * (low + high)
    half = np.maximum(0.5 * (high - low), 0.05)
    tan = math.tan(0.5 * FIELD_OF_VIEW)
    if planar:
        distance = margin * max(half[1], half[0] / ASPECT) / tan
        # A hair towards -y so that the orbit controls keep +y up on the screen.
        return View(center, np.array([0.0, -1e-3 * distance, distance]), planar=True)
    radius = float(np.max(np.linalg.norm(points - center, axis=1)))
    distance = margin * max(radius, 0.05) / math.sin(0.5 * FIELD_OF_VIEW)
    direction = SPATIAL_DIRECTION / np.linalg.norm(SPATIAL_DIRECTION)
    return View(center, distance * direction, planar=False)
