"""Obstacles in the scene: the body, and its threshold shell drawn translucent.

Node ``/meshcat/obstacles/<name>`` is placed at the obstacle's pose (and moves
with its constant velocity along the animation); ``body`` and ``shell`` are its
children. The shell is the set of points within the threshold distance ``d_o``
of the body: a link entering it is what activates an obstacle row.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from clik.viz import palette
from clik.viz.commands import (
    Command,
    phong_material,
    scene_object,
    set_object,
    set_transform,
    track,
)
from clik.viz.geometry import MIN_DISPLAY_RADIUS, obstacle_shape
from clik.viz.robot_layer import node_name
from clik.viz.timeline import Timeline

ROOT = "/meshcat/obstacles"
"""Scene path of the obstacles."""

POINT_RADIUS = 2.0 * MIN_DISPLAY_RADIUS
"""Radius [m] of the marker drawn for a point obstacle (a sphere of radius 0)."""


def obstacle_path(spec: dict[str, Any]) -> str:
    """Scene path of an obstacle's node."""
    return f"{ROOT}/{node_name(str(spec['name']))}"


def placement(spec: dict[str, Any], t: float = 0.0) -> np.ndarray:
    """World placement (4x4) of an obstacle at time ``t`` [s]."""
    M = np.eye(4)
    M[:3, :3] = pin.rpy.rpyToMatrix(*np.asarray(spec.get("rpy", (0.0, 0.0, 0.0)), dtype=float))
    velocity = np.asarray(spec.get("velocity", (0.0, 0.0, 0.0)), dtype=float)
    M[:3, 3] = np.asarray(spec["position"], dtype=float) + t * velocity
    return M


def obstacle_commands(obstacles: list[dict[str, Any]], t0: float = 0.0) -> list[Command]:
    """Body and threshold shell of every obstacle, at their poses at time ``t0`` [s]."""
    commands: list[Command] = []
    for spec in obstacles:
        path = obstacle_path(spec)
        body_spec = dict(spec)
        if spec["shape"] == "sphere" and float(spec.get("radius", 0.0)) <= 0.0:
            body_spec["radius"] = POINT_RADIUS
        body = obstacle_shape(body_spec)
        commands.append(
            set_object(
                f"{path}/body",
                scene_object(
                    "Mesh",
                    body.geometry,
                    phong_material(palette.OBSTACLE, flat=body.is_mesh),
                    body.matrix,
                    f"obstacle {spec['name']}",
                ),
            )
        )
        threshold = float(spec.get("threshold") or 0.0)
        if threshold > 0.0:
            shell = obstacle_shape(spec, inflate=threshold)
            material = phong_material(
                palette.OBSTACLE_SHELL, opacity=palette.OBSTACLE_SHELL_OPACITY, flat=shell.is_mesh
            )
            commands.append(
                set_object(
                    f"{path}/shell",
                    scene_object(
                        "Mesh",
                        shell.geometry,
                        material,
                        shell.matrix,
                        f"threshold of {spec['name']}",
                    ),
                )
            )
        commands.append(set_transform(path, placement(spec, t0)))
    return commands


def obstacle_tracks(
    obstacles: list[dict[str, Any]], timeline: Timeline, t0: float = 0.0
) -> dict[str, list[dict[str, Any]]]:
    """Position tracks of the moving obstacles (straight lines: two keys each).

    Playback time 0 is run time ``t0`` [s].
    """
    clips: dict[str, list[dict[str, Any]]] = {}
    for spec in obstacles:
        if not np.any(np.asarray(spec.get("velocity", (0.0, 0.0, 0.0)), dtype=float)):
            continue
        times = np.array([0.0, timeline.duration])
        positions = np.array([placement(spec, t0 + t)[:3, 3] for t in times])
        clips[obstacle_path(spec)] = [track(".position", "vector3", times, positions)]
    return clips
