"""Witness segments: what the obstacle rows see, frame by frame.

An obstacle row (docs/method.md, eqs. (13)-(15)) acts along the segment between its
two witness points, ``p_o`` on the link and ``c`` on the obstacle. Two kinds
of segments are drawn:

- one per distance row that was ever active (obstacle, self-collision, cloud: every
  row whose kind gives witness points), in :data:`~clik.viz.palette.ROW_ACTIVE`,
  between the witness points the run recorded (``result.extra["witness"]``), visible
  while the row is active;
- one per obstacle for the closest link (computed here with the same convex
  geometry as the constraints), visible while no row of that obstacle is
  active and the link is near, in :data:`~clik.viz.palette.MONITOR_NEAR` inside
  the threshold and :data:`~clik.viz.palette.MONITOR_CLEAR` outside it.

A segment is a unit cylinder along y whose position, quaternion and scale
tracks stretch it between the two points.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.viz import palette
from clik.viz.commands import Command, new_uuid, phong_material, scene_object, set_object, track
from clik.viz.robot_layer import node_name
from clik.viz.timeline import Timeline

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult

ROOT = "/meshcat/witness"
"""Scene path of the witness segments."""

SEGMENT_RADIUS = 0.0025
"""Radius of a drawn segment [m]."""

_Y = np.array([0.0, 1.0, 0.0])


def _segment(rgb: tuple[float, float, float], name: str) -> dict[str, Any]:
    geometry = {
        "uuid": new_uuid(),
        "type": "CylinderGeometry",
        "radiusTop": SEGMENT_RADIUS,
        "radiusBottom": SEGMENT_RADIUS,
        "height": 1.0,
        "radialSegments": 12,
    }
    return scene_object("Mesh", geometry, phong_material(rgb), name=name)


def segment_tracks(
    ends: np.ndarray, visible: np.ndarray, timeline: Timeline
) -> list[dict[str, Any]]:
    """Tracks placing a unit y-cylinder between ``ends[k, 0]`` and ``ends[k, 1]`` at frame k.

    Hidden frames keep the nearest shown pose, so interpolation never sweeps a
    segment across the scene.
    """
    shown = np.flatnonzero(visible)
    ends = ends.copy()
    if shown.size:
        nearest = shown[np.clip(np.searchsorted(shown, np.arange(len(ends))), 0, shown.size - 1)]
        ends[~visible] = ends[nearest[~visible]]
    else:
        ends[:] = 0.0
    position = 0.5 * (ends[:, 0] + ends[:, 1])
    direction = ends[:, 1] - ends[:, 0]
    length = np.linalg.norm(direction, axis=1)
    quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (len(ends), 1))
    for k in np.flatnonzero(length > 1e-12):
        quaternion[k] = pin.Quaternion.FromTwoVectors(_Y, direction[k] / length[k]).coeffs()
        if k and quaternion[k] @ quaternion[k - 1] < 0.0:
            quaternion[k] = -quaternion[k]
    scale = np.column_stack([np.ones(len(ends)), np.maximum(length, 1e-6), np.ones(len(ends))])
    return [
        track(".position", "vector3", timeline.times, position),
        track(".quaternion", "quaternion", timeline.times, quaternion),
        track(".scale", "vector3", timeline.times, scale),
        track(".visible", "bool", timeline.times, list(visible), discrete=True),
    ]


def row_segments(
    result: TrackingResult, timeline: Timeline
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """Segments of the active distance rows, from the recorded witnesses.

    A row's kind records its witness points (:attr:`~clik.constraints.kind.Candidate.witness`:
    obstacle, self-collision and cloud rows); the other rows' are NaN, and not drawn.
    """
    commands: list[Command] = []
    clips: dict[str, list[dict[str, Any]]] = {}
    active, witness = result.extra.get("active"), result.extra.get("witness")
    names = list(result.info.get("constraint_names", []))
    if active is None or witness is None or not names:
        return commands, clips
    active = np.asarray(active)[timeline.index]
    witness = np.asarray(witness)[timeline.index]
    for code, name in enumerate(names):
        hit = active == code
        if not hit.any():
            continue
        ends = np.zeros((len(timeline), 2, 3))
        visible = np.zeros(len(timeline), dtype=bool)
        for k, s in zip(*np.nonzero(hit), strict=True):
            if np.all(np.isfinite(witness[k, s])):
                ends[k], visible[k] = witness[k, s], True
        if not visible.any():
            continue
        path = f"{ROOT}/{node_name(name.replace(':', '-'))}"
        commands.append(set_object(path, _segment(palette.ROW_ACTIVE, name)))
        clips[path] = segment_tracks(ends, visible, timeline)
    return commands, clips


def closest_points(
    robot: Robot, result: TrackingResult, timeline: Timeline
) -> tuple[np.ndarray, np.ndarray] | None:
    """Closest link-obstacle distance and witness points per frame and obstacle.

    Returns:
        Distances (K, n_obs) [m] and points (K, n_obs, 2, 3) [m] (link, obstacle),
        or None when the robot has no collision geometry or an obstacle cannot be built.
    """
    from clik.constraints.collision_scene import CollisionScene
    from clik.constraints.obstacle import Obstacle
    from clik.errors import ClikError

    specs = result.info.get("obstacles") or []
    if not specs:
        return None
    try:
        obstacles = [Obstacle(**spec) for spec in specs]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                scene = CollisionScene(robot, obstacles, links=result.info.get("links"))
            except ClikError:
                scene = CollisionScene(robot, obstacles)
    except (ClikError, TypeError, ValueError):
        return None
    if scene.n_links == 0:
        return None
    model = robot.model
    data = model.createData()
    distance = np.full((len(timeline), len(obstacles)), np.inf)
    points = np.zeros((len(timeline), len(obstacles), 2, 3))
    for k, i in enumerate(timeline.index):
        pin.forwardKinematics(model, data, result.q[i])
        scene.update(data, float(result.t[i]))
        for o in range(len(obstacles)):
            for link in range(scene.n_links):
                d, p_link, p_obs, _ = scene.distance(int(scene.obstacle_pairs[link, o]))
                if d < distance[k, o]:
                    distance[k, o] = d
                    points[k, o, 0], points[k, o, 1] = p_link, p_obs
    return distance, points


def monitor_segments(
    robot: Robot, result: TrackingResult, timeline: Timeline
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """Closest-link segment of each obstacle, shown while it has no active row."""
    commands: list[Command] = []
    clips: dict[str, list[dict[str, Any]]] = {}
    found = closest_points(robot, result, timeline)
    if found is None:
        return commands, clips
    distance, points = found
    specs = result.info["obstacles"]
    names = list(result.info.get("constraint_names", []))
    active = result.extra.get("active")
    for o, spec in enumerate(specs):
        threshold = float(spec.get("threshold") or 0.0)
        rows = [code for code, n in enumerate(names) if n.startswith(f"obstacle:{spec['name']}:")]
        row_active = np.zeros(len(timeline), dtype=bool)
        if active is not None and rows:
            np.isin(np.asarray(active)[timeline.index], rows).any(axis=1, out=row_active)
        near = distance[:, o] < threshold
        visible = ~row_active & (distance[:, o] < threshold + max(2.0 * threshold, 0.05))
        if not visible.any():
            continue
        path = f"{ROOT}/closest-{node_name(str(spec['name']))}"
        commands.append(
            set_object(path, _segment(palette.MONITOR_CLEAR, f"closest {spec['name']}"))
        )
        clips[path] = segment_tracks(points[:, o], visible, timeline)
        colors = np.where(near[:, None], palette.MONITOR_NEAR, palette.MONITOR_CLEAR)
        clips[f"{path}/<object>"] = [
            track(".material.color", "color", timeline.times, colors, discrete=True)
        ]
    return commands, clips
