"""Colours of clik's scenes (RGB in [0, 1]), chosen to stay apart from each other.

Every element that has a legend entry (:data:`LEGEND`) has a colour of its own:
no two entries share a colour, and none is close to another or to the
background (``tests/viz/test_viz.py`` checks a CIELAB distance of at least 25
between any two of them).
"""

from __future__ import annotations

BACKGROUND_TOP = (0.98, 0.98, 0.98)
"""Top of the background gradient."""
BACKGROUND_BOTTOM = (0.77, 0.8, 0.84)
"""Bottom of the background gradient."""

OBSTACLE = (0.45, 0.2, 0.65)
"""Obstacle body (purple)."""
OBSTACLE_SHELL = (0.0, 0.75, 0.8)
"""Threshold shell drawn around each obstacle (cyan, translucent)."""
OBSTACLE_SHELL_OPACITY = 0.22
"""Opacity of the threshold shell."""

REFERENCE = (0.1, 0.35, 0.95)
"""Reference path of the task frame (blue line)."""
TRAIL = (0.12, 0.12, 0.12)
"""Path the task frame followed, growing along the animation (dark line)."""

ROW_ACTIVE = (0.9, 0.05, 0.05)
"""Witness segment of an active obstacle (or self-collision) row (red)."""
MONITOR_NEAR = (1.0, 0.5, 0.0)
"""Closest link-obstacle segment inside the threshold but with no active row (orange)."""
MONITOR_CLEAR = (0.15, 0.65, 0.3)
"""Closest link-obstacle segment outside the threshold (green)."""

JOINT_LIMIT_ACTIVE = (0.85, 0.1, 0.8)
"""Links of a joint whose range row is active (magenta)."""
JOINT_LIMIT_NEAR = (0.95, 0.85, 0.1)
"""Links of a joint inside its range threshold, row not active (yellow)."""

REGION = (0.55, 0.35, 0.1)
"""A region a constraint keeps a frame in: a workspace box, a tool cone (brown)."""
REGION_OPACITY = 0.12
"""Opacity of a region's walls."""

LEGEND = (
    (REFERENCE, "reference"),
    (TRAIL, "path"),
    (OBSTACLE, "obstacle"),
    (OBSTACLE_SHELL, "obstacle threshold"),
    (ROW_ACTIVE, "active obstacle row"),
    (MONITOR_NEAR, "closest link inside threshold"),
    (MONITOR_CLEAR, "closest link outside threshold"),
    (JOINT_LIMIT_ACTIVE, "joint range row active"),
    (JOINT_LIMIT_NEAR, "joint inside range threshold"),
    (REGION, "workspace box, tool cone"),
)
"""``(colour, label)`` of each element of the tracking scene's legend (the HTML caption)."""

ROBOT_NEUTRAL = (0.6, 0.6, 0.6)
"""Grey a robot link is drawn in when its own colour is close to a legend colour."""


def _lab(rgb: tuple[float, float, float]) -> tuple[float, float, float]:
    """CIELAB (D65) of an sRGB colour in [0, 1]."""

    def linear(c: float) -> float:
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    r, g, b = (linear(c) for c in rgb)
    xyz = (
        (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047,
        0.2126 * r + 0.7152 * g + 0.0722 * b,
        (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883,
    )
    fx, fy, fz = (t ** (1 / 3) if t > 0.008856 else 7.787 * t + 16 / 116 for t in xyz)
    return 116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)


def distance(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """CIELAB distance (CIE76) between two sRGB colours in [0, 1]."""
    la, lb = _lab(a), _lab(b)
    return sum((x - y) ** 2 for x, y in zip(la, lb, strict=True)) ** 0.5


LEGEND_DISTANCE = 25.0
"""Smallest CIELAB distance between a robot link's drawn colour and any legend colour."""


def link_color(rgb: tuple[float, float, float]) -> tuple[float, float, float]:
    """The colour a robot link is drawn in: its own, unless a legend colour is near it.

    The legend's colours mean states (reference, closest link inside threshold,
    active row, ...): a link coloured like one would read as that state, so it is
    drawn in :data:`ROBOT_NEUTRAL` instead.
    """
    if all(distance(rgb, c) >= LEGEND_DISTANCE for c, _ in LEGEND):
        return rgb
    return ROBOT_NEUTRAL


TASKS = (
    (0.85, 0.2, 0.45),
    (0.6, 0.9, 0.2),
    (0.0, 0.45, 0.45),
    (0.45, 0.75, 1.0),
    (0.45, 0.5, 0.0),
    (0.5, 0.0, 0.15),
    (0.3, 0.4, 0.55),
    (0.4, 0.9, 0.7),
)
"""Colours of a several-task run's other tasks (rose, lime, teal, sky, olive, maroon,
slate, mint), in the order of the run's rows (:mod:`clik.viz.task_layer`): each task's
path and reference in one colour, its legend entry the task's name. They keep the same
CIELAB distance from each other, from :data:`LEGEND` and from the background; a run
with more tasks reuses them in turn."""
TASK_REFERENCE_OPACITY = 0.45
"""Opacity of a task's reference line (its path is drawn opaque over it)."""
