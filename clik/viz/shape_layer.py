"""Regions the constraint kinds keep a frame in: boxes and cones, drawn translucent.

A kind describes its region in ``result.info["shapes"]`` (see
:meth:`clik.constraints.kind.ConstraintKind.finish`), one dict per region, and this
layer draws each by its ``shape``, never by its kind:

- ``"box"``: ``lower``, ``upper`` [m] (world frame): the walls, translucent, and their
  edges; ``threshold`` [m]: the inner box where the rows switch on, as edges.
- ``"cone"``: ``frame`` (its apex follows the frame's origin along the animation),
  ``direction`` (world), ``angle`` [rad]: a cone of :data:`CONE_LENGTH`.

Nodes: ``/meshcat/regions/<name>``.
"""

from __future__ import annotations

import math
from itertools import product
from typing import Any

import numpy as np
import pinocchio as pin

from clik.model.robot import Robot
from clik.viz import palette
from clik.viz.commands import (
    Command,
    buffer_attribute,
    line_material,
    new_uuid,
    phong_material,
    scene_object,
    set_object,
    set_transform,
    track,
)
from clik.viz.geometry import box
from clik.viz.robot_layer import node_name
from clik.viz.timeline import Timeline

ROOT = "/meshcat/regions"
"""Scene path of the regions."""
CONE_LENGTH = 0.25
"""Length [m] of a drawn cone, apex to base."""
MAX_DRAWN_ANGLE = math.radians(80.0)
"""A wider cone is drawn at this half-angle (its base would be huge)."""


def region_path(spec: dict[str, Any]) -> str:
    """Scene path of a region's node."""
    return f"{ROOT}/{node_name(str(spec['name']))}"


def _edges(lower: np.ndarray, upper: np.ndarray) -> dict[str, Any]:
    """The 12 edges of a box as a line-segment geometry."""
    corners = [np.where(np.array(bits), upper, lower) for bits in product((0, 1), repeat=3)]
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    points = np.array([corners[i] for pair in pairs for i in pair], dtype=float)
    return {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {"attributes": {"position": buffer_attribute(points)}},
    }


def _box_commands(spec: dict[str, Any]) -> list[Command]:
    path = region_path(spec)
    lower, upper = np.asarray(spec["lower"], float), np.asarray(spec["upper"], float)
    walls = box(upper - lower)
    centre = np.eye(4)
    centre[:3, 3] = 0.5 * (lower + upper)
    material = phong_material(palette.REGION, opacity=palette.REGION_OPACITY, double_sided=True)
    commands = [
        set_object(
            f"{path}/walls",
            scene_object("Mesh", walls.geometry, material, centre, str(spec["name"])),
        ),
        set_object(
            f"{path}/edges",
            scene_object("LineSegments", _edges(lower, upper), line_material(palette.REGION)),
        ),
    ]
    thr = float(spec.get("threshold") or 0.0)
    if thr > 0.0 and np.all(upper - lower > 2 * thr):
        inner = _edges(lower + thr, upper - thr)
        commands.append(
            set_object(
                f"{path}/threshold",
                scene_object("LineSegments", inner, line_material(palette.REGION)),
            )
        )
    return commands


def _cone_commands(spec: dict[str, Any], apex: np.ndarray) -> list[Command]:
    """A cone opening along ``direction`` from its apex (three.js cones lie along y)."""
    path = region_path(spec)
    angle = min(float(spec["angle"]), MAX_DRAWN_ANGLE)
    geometry = {
        "uuid": new_uuid(),
        "type": "ConeGeometry",
        "radius": CONE_LENGTH * math.tan(angle),
        "height": CONE_LENGTH,
        "radialSegments": 32,
        "openEnded": True,
    }
    u = np.asarray(spec["direction"], float)
    u = u / np.linalg.norm(u)
    along = np.eye(4)  # apex (+y/2 in three.js) to the origin, opening along -y, then -y -> u
    along[:3, 3] = [0.0, -0.5 * CONE_LENGTH, 0.0]
    turn = np.eye(4)
    turn[:3, :3] = pin.Quaternion.FromTwoVectors(np.array([0.0, -1.0, 0.0]), u).matrix()
    material = phong_material(palette.REGION, opacity=palette.REGION_OPACITY, double_sided=True)
    at = np.eye(4)
    at[:3, 3] = apex
    return [
        set_object(
            f"{path}/cone", scene_object("Mesh", geometry, material, turn @ along, spec["name"])
        ),
        set_transform(path, at),
    ]


def frame_origins(robot: Robot, frame: str, q: np.ndarray) -> np.ndarray:
    """The origin of ``frame`` (K, 3) [m] at each configuration of ``q`` (K, nq)."""
    model = robot.model
    data = model.createData()
    fid = model.getFrameId(frame)
    out = np.empty((len(q), 3))
    for k, qk in enumerate(q):
        pin.framesForwardKinematics(model, data, qk)
        out[k] = data.oMf[fid].translation
    return out


def region_layer(
    robot: Robot, shapes: list[dict[str, Any]], q: np.ndarray, timeline: Timeline
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """Commands drawing every region, and the tracks of those that follow a frame.

    Args:
        robot: The run's robot.
        shapes: ``result.info["shapes"]``.
        q: The configuration shown at each playback time (K, nq).
        timeline: The playback times.
    """
    commands: list[Command] = []
    clips: dict[str, list[dict[str, Any]]] = {}
    for spec in shapes:
        if spec.get("shape") == "box":
            commands += _box_commands(spec)
        elif spec.get("shape") == "cone" and robot.model.existFrame(str(spec.get("frame"))):
            apex = frame_origins(robot, str(spec["frame"]), q)
            commands += _cone_commands(spec, apex[0])
            if len(timeline) > 1:
                clips[region_path(spec)] = [track(".position", "vector3", timeline.times, apex)]
    return commands, clips
