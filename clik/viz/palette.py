"""Colours of clik's scenes (RGB in [0, 1]), chosen to stay apart from each other."""

from __future__ import annotations

BACKGROUND_TOP = (0.98, 0.98, 0.98)
"""Top of the background gradient."""
BACKGROUND_BOTTOM = (0.77, 0.8, 0.84)
"""Bottom of the background gradient."""

OBSTACLE = (0.45, 0.2, 0.65)
"""Obstacle body (purple)."""
OBSTACLE_SHELL_OPACITY = 0.22
"""Opacity of the threshold shell drawn around each obstacle (same colour as the body)."""

REFERENCE = (0.05, 0.6, 0.2)
"""Reference path of the task frame (green line)."""
TRAIL = (0.12, 0.12, 0.12)
"""Path the task frame followed, growing along the animation (dark line)."""

ROW_ACTIVE = (0.9, 0.05, 0.05)
"""Witness segment of an active obstacle (or self-collision) row (red)."""
MONITOR_NEAR = (1.0, 0.6, 0.0)
"""Closest link-obstacle segment inside the threshold but with no active row (amber)."""
MONITOR_CLEAR = (0.15, 0.65, 0.3)
"""Closest link-obstacle segment outside the threshold (green)."""

JOINT_LIMIT_ACTIVE = (0.85, 0.1, 0.8)
"""Links of a joint whose range row is active (magenta)."""
JOINT_LIMIT_NEAR = (0.95, 0.85, 0.1)
"""Links of a joint inside its range threshold, row not active (yellow)."""
