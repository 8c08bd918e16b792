"""What the 3-D view draws of a kind's region: translucent surfaces and lines.

A kind that keeps a frame in a region (a box, a cone) describes it in
``result.info["shapes"]`` (its :meth:`~clik.constraints.kind.ConstraintKind.finish`,
one dict per region, its ``name`` a key of the kind: ``workspace:cell``) and says how
it is drawn (:meth:`~clik.constraints.kind.ConstraintKind.region`) with two primitives:
a :class:`Surface` of triangles and :class:`Lines`, in the region's frame, which is the
world or follows a frame of the robot (its origin, along the animation). The view
(:mod:`clik.viz.shape_layer`) draws any region from these alone: a new shape (a plane: a
large thin square and its normal) is the kind's, not the view's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

import numpy as np


def _points(value: np.ndarray, what: str) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim != 2 or array.shape[1] != 3 or not np.all(np.isfinite(array)):
        raise ValueError(f"{what}: expected finite points (n, 3) [m], got shape {array.shape}")
    return array


@dataclass(frozen=True)
class Surface:
    """A translucent surface: triangles in the region's frame.

    Attributes:
        name: Its node under the region's (``walls``, ``cone``).
        vertices: Points (V, 3) [m].
        triangles: Vertex indices (F, 3), any winding (both sides are drawn).
        smooth: Shaded as one curved surface (a cone) rather than flat faces (walls).
    """

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    smooth: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "vertices", _points(self.vertices, f"Surface {self.name!r}"))
        tri = np.asarray(self.triangles, dtype=np.int64)
        if tri.ndim != 2 or tri.shape[1] != 3 or not tri.size:
            raise ValueError(f"Surface {self.name!r}: expected triangles (F, 3), got {tri.shape}")
        if tri.min() < 0 or tri.max() >= len(self.vertices):
            raise ValueError(f"Surface {self.name!r}: a triangle's index is not a vertex")
        object.__setattr__(self, "triangles", tri)


@dataclass(frozen=True)
class Lines:
    """Line segments in the region's frame: ``points[2 k]`` to ``points[2 k + 1]``.

    Attributes:
        name: Its node under the region's (``edges``, ``normal``).
        points: Segment ends (2 S, 3) [m].
    """

    name: str
    points: np.ndarray

    def __post_init__(self) -> None:
        points = _points(self.points, f"Lines {self.name!r}")
        if not len(points) or len(points) % 2:
            raise ValueError(f"Lines {self.name!r}: expected pairs of points, got {len(points)}")
        object.__setattr__(self, "points", points)


Part = Surface | Lines
"""One drawn part of a region."""


@dataclass(frozen=True)
class Region:
    """A region as drawn: its parts, and the frame it follows.

    Attributes:
        parts: Its surfaces and lines (distinct names).
        follows: A frame of the robot whose origin carries the region's origin along the
            animation (a cone's apex), or None: the parts are in the world frame.
    """

    parts: tuple[Part, ...]
    follows: str | None = None
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names = tuple(p.name for p in self.parts)
        if not names or len(set(names)) != len(names):
            raise ValueError(f"Region: expected parts with distinct names, got {list(names)}")
        object.__setattr__(self, "names", names)


_CORNER_BITS = list(product((0, 1), repeat=3))
"""A box's corners as (x, y, z) bits: 0 the lower coordinate, 1 the upper."""


def box_surface(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box's six faces: vertices (8, 3) [m] and triangles (12, 3)."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    vertices = np.array([np.where(np.array(bits), hi, lo) for bits in _CORNER_BITS])
    triangles = []
    for axis in range(3):
        for side in (0, 1):
            a, b, c, d = [i for i, bits in enumerate(_CORNER_BITS) if bits[axis] == side]
            triangles += [(a, b, d), (a, d, c)]  # the face's corners in bit order: a square
    return vertices, np.array(triangles)


def box_edges(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """An axis-aligned box's 12 edges as segment ends (24, 3) [m]."""
    vertices, _ = box_surface(lower, upper)
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    return np.array([vertices[i] for pair in pairs for i in pair])
