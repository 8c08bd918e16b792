"""The task frame's paths: the reference as a line, the followed path as a growing trail.

The trail is cut into one piece per frame, each made visible (a discrete
``visible`` track) when the animation reaches it, so the trail grows behind the
end effector while the animation plays and when it is scrubbed.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from clik.viz import palette
from clik.viz.commands import (
    Command,
    buffer_attribute,
    line_material,
    new_uuid,
    scene_object,
    set_object,
    track,
)
from clik.viz.timeline import Timeline

ROOT = "/meshcat/paths"
"""Scene path of the reference and the trail."""

MAX_POINTS = 2000
"""Most points drawn for a path (longer ones are subsampled)."""

MAX_PIECES = 200
"""Most pieces of the growing trail."""


def line_object(
    points: np.ndarray, rgb: tuple[float, float, float], name: str, opacity: float = 1.0
) -> dict[str, Any]:
    """A polyline through ``points`` (N, 3) [m] in colour ``rgb``, translucent below 1."""
    geometry = {
        "uuid": new_uuid(),
        "type": "BufferGeometry",
        "data": {"attributes": {"position": buffer_attribute(points)}},
    }
    material = line_material(rgb)
    if opacity < 1.0:
        material.update(transparent=True, opacity=float(opacity), depthWrite=False)
    return scene_object("Line", geometry, material, name=name)


def subsample(points: np.ndarray, limit: int = MAX_POINTS) -> np.ndarray:
    """At most ``limit`` of ``points`` (N, 3), first and last kept."""
    points = np.asarray(points, dtype=float)
    if len(points) <= limit:
        return points
    keep = np.unique(np.linspace(0, len(points) - 1, limit).round().astype(int))
    return points[keep]


def reference_commands(reference: np.ndarray | None) -> list[Command]:
    """The reference path (nothing for an orientation-only task)."""
    if reference is None or len(reference) < 2 or not np.all(np.isfinite(reference)):
        return []
    return [
        set_object(
            f"{ROOT}/reference", line_object(subsample(reference), palette.REFERENCE, "reference")
        )
    ]


def trail_commands(
    position: np.ndarray,
    timeline: Timeline,
    root: str = f"{ROOT}/trail",
    rgb: tuple[float, float, float] = palette.TRAIL,
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """Trail pieces (under ``root``, in colour ``rgb``) and their visibility tracks.

    Piece ``k`` joins the samples shown between two consecutive frames and
    appears at the later frame's time.
    """
    commands: list[Command] = []
    clips: dict[str, list[dict[str, Any]]] = {}
    n = len(timeline)
    if n < 2 or len(position) < 2:
        return commands, clips
    bounds = np.unique(np.linspace(0, n - 1, min(n, MAX_PIECES + 1)).round().astype(int))
    per_piece = max(2, MAX_POINTS // max(len(bounds) - 1, 1))
    for a, b in itertools.pairwise(bounds):
        i0, i1 = int(timeline.index[a]), int(timeline.index[b])
        if i1 <= i0:
            continue
        points = subsample(position[i0 : i1 + 1], per_piece)
        path = f"{root}/{b:04d}"
        commands.append(set_object(path, line_object(points, rgb, f"trail {b}")))
        appear = float(timeline.times[b])
        times, values = [0.0, appear], [False, True]
        if appear < timeline.duration:
            times, values = [*times, timeline.duration], [*values, True]
        clips[path] = [track(".visible", "bool", np.array(times), values, discrete=True)]
    return commands, clips
