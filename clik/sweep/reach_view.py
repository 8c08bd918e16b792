"""A reachability map as one self-contained HTML file (meshcat, no server, no network).

Built like :func:`clik.viz.export_html`: viewer commands recorded by
:class:`clik.viz.html.Recorder` and inlined with meshcat's viewer bundle. The
scene: the robot at its reference configuration, the box's outline, the
solved points coloured by manipulability (viridis: dark = near a singularity,
yellow = the highest of the map) and the unreachable points in red.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from clik.io import atomic_write
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
from clik.viz.robot_layer import joint_path, robot_commands
from clik.viz.timeline import frame_origins, joint_placements

if TYPE_CHECKING:
    from clik.robot import Robot
    from clik.sweep.reach_data import ReachMap

ROOT = "/meshcat/reach"
"""Scene path of the map's points and box."""

UNREACHABLE = (0.9, 0.1, 0.1)
"""Colour of the points not solved (red)."""

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


def reach_commands(reach: ReachMap, robot: Robot) -> list[Command]:
    """Viewer commands drawing the map and the robot at its reference configuration."""
    gmodel = robot.visual_model if robot.visual_model.ngeoms else robot.collision_model
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
    size = 0.5 * reach.spec.step
    ok = reach.success
    if ok.any():
        colors = manipulability_colors(reach.manipulability[ok])
        commands.append(
            set_object(f"{ROOT}/reachable", _points(reach.points[ok], colors, size, "reachable"))
        )
    if (~ok).any():
        red = np.tile(UNREACHABLE, (int((~ok).sum()), 1))
        commands.append(
            set_object(
                f"{ROOT}/unreachable", _points(reach.points[~ok], red, 0.6 * size, "unreachable")
            )
        )
    box = np.asarray(reach.spec.box, dtype=float)
    commands.append(set_object(f"{ROOT}/box", _box_outline(box)))
    origins = frame_origins(robot.model, q).reshape(-1, 3)
    shown = np.vstack([origins, reach.points, box.reshape(2, 3)])
    view = default_view(shown, planar=is_planar(shown))
    commands += view.commands()
    return commands


def export_reach_html(
    reach: ReachMap, path: str | os.PathLike[str], robot: Robot | None = None
) -> Path:
    """Write the map's 3-D view as one self-contained HTML file (atomically).

    Args:
        reach: The map.
        path: The ``.html`` file.
        robot: The robot to draw (default: loaded from ``reach.spec``).
    """
    from clik.robot import Robot

    spec = reach.spec
    if robot is None:
        robot = Robot.load(spec.robot, lock=spec.lock or None)
    commands = reach_commands(reach, robot)
    solved = int(reach.success.sum())
    w = reach.manipulability[reach.success]
    top = f", max manipulability {np.nanmax(w):.3g}" if w.size else ""
    caption = (
        f"{robot.name} {spec.frame}: {solved}/{len(reach.points)} points reachable "
        f"({spec.kind} task, step {spec.step:g} m{top})"
    )
    legend = [
        (manipulability_colors(np.array([0.0]))[0], "low manipulability"),
        (manipulability_colors(np.array([1.0]))[0], "highest"),
        (UNREACHABLE, "unreachable"),
    ]
    path = Path(path)
    text = page(Recorder().extend(commands).messages, f"clik reach: {robot.name}", caption, legend)
    atomic_write(path, lambda f: f.write(text), mode="w")
    path.chmod(0o644)
    return path
