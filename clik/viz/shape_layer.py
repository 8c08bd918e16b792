"""Regions the constraint kinds keep a frame in, drawn translucent.

A kind describes each of its regions in ``result.info["shapes"]`` (its
:meth:`~clik.constraints.kind.ConstraintKind.finish`, one dict per region, its ``name``
a key of the kind) and says how it is drawn
(:meth:`~clik.constraints.kind.ConstraintKind.region`): surfaces and lines
(:mod:`clik.constraints.region`), in the world or following a frame's origin. This layer
finds the kind by the region's name (:func:`clik.constraints.registry.kind_of`) and draws
what it says, never naming a kind or a shape:

- a :class:`~clik.constraints.region.Surface`: a translucent mesh, both sides;
- :class:`~clik.constraints.region.Lines`: line segments;
- a region that follows a frame: its node at the frame's origin, animated along the run.

Nodes: ``/meshcat/regions/<name>/<part>``. A region of a kind this clik does not know, or
following a frame the robot lacks, is not drawn.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from clik.constraints.region import Part, Region, Surface
from clik.constraints.registry import kind_of
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
from clik.viz.geometry import mesh
from clik.viz.robot_layer import node_name
from clik.viz.timeline import Timeline

ROOT = "/meshcat/regions"
"""Scene path of the regions."""


def region_path(spec: dict[str, Any]) -> str:
    """Scene path of a region's node."""
    return f"{ROOT}/{node_name(str(spec['name']))}"


def drawn_region(spec: dict[str, Any]) -> Region | None:
    """What the kind that owns the region ``spec`` draws of it, or None: no such kind."""
    kind = kind_of(str(spec.get("name", "")))
    return None if kind is None else kind.region(spec)


def part_command(path: str, part: Part, label: str = "") -> Command:
    """The command drawing one part of a region at ``<path>/<part.name>``."""
    if isinstance(part, Surface):
        shape = mesh(part.vertices, part.triangles, flat=not part.smooth)
        material = phong_material(
            palette.REGION, opacity=palette.REGION_OPACITY, flat=shape.is_mesh, double_sided=True
        )
        obj = scene_object("Mesh", shape.geometry, material, shape.matrix, label)
    else:
        geometry = {
            "uuid": new_uuid(),
            "type": "BufferGeometry",
            "data": {"attributes": {"position": buffer_attribute(part.points)}},
        }
        obj = scene_object("LineSegments", geometry, line_material(palette.REGION))
    return set_object(f"{path}/{part.name}", obj)


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
        region = drawn_region(spec)
        if region is None:
            continue
        frame = region.follows
        if frame is not None and not robot.model.existFrame(frame):
            continue
        path = region_path(spec)
        commands += [part_command(path, part, str(spec["name"])) for part in region.parts]
        if frame is not None:
            origin = frame_origins(robot, frame, q)
            at = np.eye(4)
            at[:3, 3] = origin[0]
            commands.append(set_transform(path, at))
            if len(timeline) > 1:
                clips[path] = [track(".position", "vector3", timeline.times, origin)]
    return commands, clips
