"""Stick drawings: the arm drawn every few samples, projected on a plane, with the obstacles."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np
import pinocchio as pin
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon

from clik.errors import InputError
from clik.outputs.result import TrackingResult

if TYPE_CHECKING:
    from clik.model.robot import Robot

PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
"""Projection plane -> indices of its two world axes."""


def planar_stick(
    ax: Axes,
    result: TrackingResult,
    every: float = 0.25,
    *,
    plane: str = "xy",
    obstacles: bool = True,
    reference: bool = True,
) -> Axes:
    """The arm drawn every ``every`` seconds, projected on a plane, with the obstacles.

    The sticks join the joint origins (Pinocchio forward kinematics on
    ``result.robot``) and end at the task frame; their colour goes from light
    (t = 0) to dark (the end). Obstacles (``result.info["obstacles"]``) are drawn
    at their position at t = 0 with a dashed outline at their threshold ``d_o``
    (spheres, capsules, cylinders), a moving obstacle with an arrow to where it
    is at the end of the run.

    Args:
        ax: Axes to draw into (its aspect is set equal).
        result: A result that still has its robot (not one read back from a file).
        every: Time between two drawings [s] (the first and last samples are always drawn).
        plane: Projection plane, ``"xy"`` (the planar arm's), ``"xz"`` or ``"yz"``.
        obstacles: Draw the obstacles and their thresholds.
        reference: Draw the reference path of the task frame.

    Returns:
        ``ax``; one stick line (``gid == "stick"``) per drawn sample.

    Raises:
        InputError: The result has no robot, or a bad ``every`` or ``plane``.
    """
    if result.robot is None:
        raise InputError("result.robot", "a result with its robot (as returned by track)")
    if not (math.isfinite(every) and every > 0):
        raise InputError("every", "a positive time [s]", every)
    if plane not in PLANES:
        raise InputError("plane", "'xy', 'xz' or 'yz'", plane)
    a, b = PLANES[plane]
    _draw_sticks(ax, result, result.robot, every, a, b)
    (trail,) = ax.plot(
        result.position[:, a], result.position[:, b], color="k", linewidth=0.8, label="end effector"
    )
    trail.set_gid("path")
    if reference and result.reference_position is not None:
        (ref,) = ax.plot(
            result.reference_position[:, a],
            result.reference_position[:, b],
            ":",
            color="C3",
            linewidth=1.2,
            label="reference",
        )
        ref.set_gid("reference")
    if obstacles:
        for o in result.info.get("obstacles", []):
            _draw_obstacle(ax, o, a, b, float(result.t[-1]))
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def _draw_sticks(
    ax: Axes, result: TrackingResult, robot: Robot, every: float, a: int, b: int
) -> None:
    """The arm at t = 0, ``every``, ... and the last sample, light to dark, on plane (a, b)."""
    model = robot.model
    data = model.createData()
    t = result.t
    picks = sorted({0, len(t) - 1, *np.searchsorted(t, np.arange(t[0], t[-1], every)).tolist()})
    cmap = matplotlib.colormaps["viridis_r"]
    for n, k in enumerate(picks):
        pin.forwardKinematics(model, data, result.q[k])
        points = [data.oMi[j].translation for j in range(1, model.njoints)]
        points.append(result.position[k])
        pts = np.array(points)
        shade = 0.15 + 0.85 * n / max(1, len(picks) - 1)
        (stick,) = ax.plot(
            pts[:, a], pts[:, b], "-o", color=cmap(shade), markersize=2.5, linewidth=1.2, alpha=0.9
        )
        stick.set_gid("stick")


def _draw_obstacle(ax: Axes, o: dict[str, Any], a: int, b: int, t_end: float) -> None:
    """An obstacle's outline projected on the plane (a, b), its threshold outline, its path."""
    center = np.asarray(o["position"], dtype=float)
    c2 = (center[a], center[b])
    velocity = np.asarray(o.get("velocity", (0.0, 0.0, 0.0)), dtype=float)
    if np.any(velocity != 0.0):  # a moving obstacle: its path until the end of the run
        end = center + t_end * velocity
        ax.annotate(
            "",
            (end[a], end[b]),
            c2,
            arrowprops={"arrowstyle": "->", "color": "0.3", "linestyle": ":"},
        )
        (ghost,) = ax.plot(end[a], end[b], "o", color="0.3", alpha=0.4, markersize=4)
        ghost.set_gid("obstacle")
    d_o = float(o.get("threshold") or 0.0)
    shape = o.get("shape")
    radius = 0.0
    if shape == "box":
        R = pin.rpy.rpyToMatrix(*np.asarray(o.get("rpy", (0, 0, 0)), dtype=float))
        half = 0.5 * np.asarray(o["size"], dtype=float)
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        world = center + (corners * half) @ R.T
        outline = _hull2d(world[:, [a, b]])
        ax.add_patch(Polygon(outline, closed=True, color="0.3", alpha=0.6, gid="obstacle"))
    else:  # sphere, capsule, cylinder: a disk of the radius; mesh: a marker only
        radius = 0.0 if shape == "mesh" else float(o.get("radius", 0.0) or 0.0)
        ax.add_patch(Circle(c2, max(radius, 1e-3), color="0.3", alpha=0.6, gid="obstacle"))
    (mark,) = ax.plot(*c2, "x", color="0.1", markersize=6)
    mark.set_gid("obstacle")
    if d_o > 0 and shape in ("sphere", "capsule", "cylinder"):
        ax.add_patch(
            Circle(c2, radius + d_o, fill=False, linestyle="--", color="0.3", gid="threshold")
        )
    ax.annotate(
        str(o.get("name", "")), c2, textcoords="offset points", xytext=(6, 6), fontsize="small"
    )


def _hull2d(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points (monotone chain), counter-clockwise."""
    pts = sorted(map(tuple, np.round(points, 12)))
    if len(pts) <= 2:
        return np.array(pts)

    def half(seq: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while (
                len(out) >= 2
                and (
                    (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                    - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                )
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])
