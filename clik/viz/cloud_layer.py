"""Point-cloud obstacles in the scene: each cloud's points, in the obstacles' colour.

A run keeps the points a view draws (:mod:`clik.clouds.drawn`): ``result.extra``'s
``cloud_points`` (world coordinates [m], at most
:data:`~clik.clouds.drawn.MAX_DRAWN_POINTS` per cloud) and ``cloud_points_index`` (the
index in ``result.info["clouds"]`` of each point's cloud). Each cloud is a three.js
``Points`` object (what ``meshcat.geometry.PointCloud`` lowers to, with one colour for
every point) at ``/meshcat/clouds/<name>/points``, its node at the world's origin; a point
is drawn the size of the cloud's voxel (at least :data:`MIN_POINT_SIZE`). A cloud is at
rest: nothing is animated. The witness segments of its active rows are drawn with the
other distance rows' (:func:`clik.viz.witness_layer.row_segments`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clik.viz import palette
from clik.viz.commands import (
    Command,
    buffer_attribute,
    color_int,
    new_uuid,
    scene_object,
    set_object,
)
from clik.viz.robot_layer import node_name

if TYPE_CHECKING:
    from clik.outputs.result import TrackingResult

ROOT = "/meshcat/clouds"
"""Scene path of the clouds."""

MIN_POINT_SIZE = 0.003
"""Smallest drawn point [m] (a cloud of voxel 0 would be invisible)."""


def cloud_path(spec: dict[str, Any]) -> str:
    """Scene path of a cloud's node."""
    return f"{ROOT}/{node_name(str(spec['name']))}"


def points_object(points: np.ndarray, size: float, name: str = "") -> dict[str, Any]:
    """A three.js ``Points`` object: ``points`` (M, 3) [m] as squares ``size`` [m] wide."""
    geometry = {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {"attributes": {"position": buffer_attribute(np.asarray(points))}},
    }
    material = {
        "uuid": new_uuid(),
        "type": "PointsMaterial",
        "color": color_int(palette.OBSTACLE),
        "size": float(size),
        "sizeAttenuation": True,
        "vertexColors": False,
    }
    return scene_object("Points", geometry, material, name=name)


def cloud_commands(result: TrackingResult) -> list[Command]:
    """The points of every cloud of ``result.info["clouds"]`` that the run kept."""
    specs = list(result.info.get("clouds") or [])
    points, index = result.extra.get("cloud_points"), result.extra.get("cloud_points_index")
    if not specs or points is None or index is None:
        return []
    points, index = np.asarray(points).reshape(-1, 3), np.asarray(index).reshape(-1)
    commands: list[Command] = []
    for i, spec in enumerate(specs):
        mine = points[index == i]
        if not len(mine):
            continue
        size = max(float(spec.get("voxel") or 0.0), MIN_POINT_SIZE)
        obj = points_object(mine, size, f"cloud {spec['name']}")
        commands.append(set_object(f"{cloud_path(spec)}/points", obj))
    return commands
