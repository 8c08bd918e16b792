"""A reachability map as one self-contained HTML file (meshcat, no server, no network).

Built like :func:`clik.viz.export_html`: viewer commands recorded by
:class:`clik.viz.html.Recorder` and inlined with meshcat's viewer bundle. The
scene: the robot at its reference configuration, the box's outline, the
solved points coloured by manipulability (viridis: dark = near a singularity,
yellow = the highest of the map), the points blocked by the scenario's constraints in
orange, the unreachable points in red, and the scenario's obstacles with their
threshold shells.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.outputs.io import atomic_write
from clik.viz import palette
from clik.viz.camera import default_view, is_planar
from clik.viz.commands import (
    Command,
    buffer_attribute,
    delete,
    line_material,
    new_uuid,
    scene_object,
    set_object,
    set_property,
    set_transform,
)
from clik.viz.html import Recorder, page
from clik.viz.obstacle_layer import obstacle_commands
from clik.viz.robot_layer import drawn_geometry, joint_path, robot_commands
from clik.viz.timeline import frame_origins, joint_placements

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.sweep.reach_data import ReachMap

ROOT = "/meshcat/reach"
"""Scene path of the map's points and box."""

UNREACHABLE = (0.9, 0.1, 0.1)
"""Colour of the points not solved (red)."""

BLOCKED = (1.0, 0.55, 0.0)
"""Colour of the points blocked by the constraints (orange): solved without them."""

BOX = (0.3, 0.3, 0.3)
"""Colour of the box outline."""


def manipulability_colors(values: np.ndarray) -> np.ndarray:
    """RGB (N, 3) of manipulability values: viridis over ``[0, max]``."""
    from matplotlib import colormaps

    values = np.asarray(values, dtype=float)
    top = float(np.nanmax(values)) if values.size and np.any(np.isfinite(values)) else 1.0
    scaled = np.clip(values / (top if top > 0 else 1.0), 0.0, 1.0)
    return np.asarray(colormaps["viridis"](np.nan_to_num(scaled)))[:, :3]


def _points(points: np.ndarray, colors: np.ndarray, size: float, name: str) -> dict[str, Any]:
    geometry = {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {
            "attributes": {
                "position": buffer_attribute(points),
                "color": buffer_attribute(colors),
            }
        },
    }
    material = {
        "uuid": new_uuid(),
        "type": "PointsMaterial",
        "color": 0xFFFFFF,
        "size": float(size),
        "vertexColors": True,
    }
    return scene_object("Points", geometry, material, name=name)


def _box_outline(box: np.ndarray) -> dict[str, Any]:
    low, high = box[:3], box[3:]
    corners = np.array(
        [[(high if (k >> i) & 1 else low)[i] for i in range(3)] for k in range(8)], dtype=float
    )
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    segments = np.array([corners[i] for edge in edges for i in edge])
    geometry = {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {"attributes": {"position": buffer_attribute(segments)}},
    }
    return scene_object("LineSegments", geometry, line_material(BOX), name="box")


def reach_commands(
    reach: ReachMap, robot: Robot, obstacles: list[dict[str, Any]] | None = None
) -> list[Command]:
    """Viewer commands drawing the map, the robot at its reference configuration, obstacles.

    Args:
        reach: The map.
        robot: The robot.
        obstacles: The obstacles as :meth:`clik.constraints.ConstraintSet.obstacle_info`
            lists them, or None.
    """
    gmodel = drawn_geometry(robot)
    commands: list[Command] = [
        delete("/meshcat"),
        set_property("/Background", "top_color", list(palette.BACKGROUND_TOP)),
        set_property("/Background", "bottom_color", list(palette.BACKGROUND_BOTTOM)),
    ]
    robot_cmds, _ = robot_commands(robot, gmodel)
    commands += robot_cmds
    q = robot.q_reference[None, :]
    placements = joint_placements(robot.model, q)[0]
    for j in range(1, robot.model.njoints):
        commands.append(set_transform(joint_path(robot.model, j), placements[j]))
    commands += obstacle_commands(obstacles or [])
    commands += _point_commands(reach)
    box = np.asarray(reach.spec.box, dtype=float)
    commands.append(set_object(f"{ROOT}/box", _box_outline(box)))
    origins = frame_origins(robot.model, q).reshape(-1, 3)
    shown = np.vstack([origins, reach.points, box.reshape(2, 3)])
    view = default_view(shown, planar=is_planar(shown))
    commands += view.commands()
    return commands


def _point_commands(reach: ReachMap) -> list[Command]:
    """The reachable points (by manipulability), the blocked and the unreachable ones."""
    commands: list[Command] = []
    size = 0.5 * reach.spec.step
    ok = reach.success
    blocked = np.zeros_like(ok) if reach.blocked is None else reach.blocked
    if blocked.any():
        orange = np.tile(BLOCKED, (int(blocked.sum()), 1))
        commands.append(
            set_object(
                f"{ROOT}/blocked", _points(reach.points[blocked], orange, 0.8 * size, "blocked")
            )
        )
    missed = ~ok & ~blocked
    if ok.any():
        colors = manipulability_colors(reach.manipulability[ok])
        commands.append(
            set_object(f"{ROOT}/reachable", _points(reach.points[ok], colors, size, "reachable"))
        )
    if missed.any():
        red = np.tile(UNREACHABLE, (int(missed.sum()), 1))
        commands.append(
            set_object(
                f"{ROOT}/unreachable", _points(reach.points[missed], red, 0.6 * size, "unreachable")
            )
        )
    return commands


def export_reach_html(
    reach: ReachMap, path: str | os.PathLike[str], robot: Robot | None = None
) -> Path:
    """Write the map's 3-D view as one self-contained HTML file (atomically).

    Args:
        reach: The map.
        path: The ``.html`` file.
        robot: The robot to draw (default: loaded from ``reach.spec``, with its scenario).
    """
    from clik.sweep.reach import reach_objects

    spec = reach.spec
    obstacles = None
    if robot is None or spec.scenario is not None:
        loaded, _, constraints = reach_objects(spec)
        robot = loaded if robot is None else robot
        obstacles = None if constraints is None else constraints.obstacle_info()
    commands = reach_commands(reach, robot, obstacles)
    counts = reach.counts()
    solved = counts["reachable"]
    w = reach.manipulability[reach.success]
    top = f", max manipulability {np.nanmax(w):.3g}" if w.size else ""
    caption = (
        f"{robot.name} {spec.frame}: {solved}/{len(reach.points)} points reachable "
        f"({spec.kind} task, step {spec.step:g} m{top})"
    )
    if spec.scenario is not None:
        caption += (
            f"; {counts['blocked']} blocked by the constraints, {counts['unreachable']} unreachable"
        )
    legend = [
        (manipulability_colors(np.array([0.0]))[0], "low manipulability"),
        (manipulability_colors(np.array([1.0]))[0], "highest"),
        (UNREACHABLE, "unreachable"),
    ]
    if spec.scenario is not None:
        legend.insert(2, (BLOCKED, "blocked by the constraints"))
    path = Path(path)
    text = page(Recorder().extend(commands).messages, f"clik reach: {robot.name}", caption, legend)
    atomic_write(path, lambda f: f.write(text), mode="w")
    path.chmod(0o644)
    return path
