"""A several-task run's other tasks in the scene: each one's reference and growing path.

The primary task keeps the scene's reference (blue) and path (dark) lines; every
other frame, relative or centre-of-mass task (:func:`~clik.viz.task_paths.task_paths`)
gets a colour of its own from :data:`~clik.viz.palette.TASKS`, in row order: its
reference as a translucent line, the path it followed as an opaque trail that grows
with the animation like the primary's. The legend names each task:

- ``/meshcat/tasks/<name>/reference``: the reference line;
- ``/meshcat/tasks/<name>/trail/<k>``: the trail's pieces.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from clik.viz import palette
from clik.viz.commands import Command, set_object
from clik.viz.path_layer import line_object, subsample, trail_commands
from clik.viz.robot_layer import node_name
from clik.viz.task_paths import TaskPath
from clik.viz.timeline import Timeline

ROOT = "/meshcat/tasks"
"""Scene path of the other tasks' lines."""

Legend = list[tuple[tuple[float, float, float], str]]
"""``(colour, label)`` swatches of a page's caption."""


def task_node(name: str) -> str:
    """Scene path of task ``name``'s lines."""
    return f"{ROOT}/{node_name(name)}"


def task_colours(paths: list[TaskPath]) -> dict[str, tuple[float, float, float]]:
    """The colour of each non-primary task, by name, in order (reused past eight)."""
    others = [p.name for p in paths if not p.primary]
    return {n: palette.TASKS[i % len(palette.TASKS)] for i, n in enumerate(others)}


def task_layer(
    paths: list[TaskPath], timeline: Timeline
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """Commands and animation tracks of the non-primary tasks' lines.

    Args:
        paths: The run's task paths (:func:`~clik.viz.task_paths.task_paths`).
        timeline: The animation's frames (indices into the paths' samples).

    Returns:
        ``(commands, clips)``.
    """
    commands: list[Command] = []
    clips: dict[str, list[dict[str, Any]]] = {}
    colours = task_colours(paths)
    for path in paths:
        if path.primary:
            continue
        rgb, node = colours[path.name], task_node(path.name)
        ref = path.reference
        if ref is not None and len(ref) >= 2 and np.all(np.isfinite(ref)):
            line = line_object(
                subsample(ref), rgb, f"{path.name} reference", palette.TASK_REFERENCE_OPACITY
            )
            commands.append(set_object(f"{node}/reference", line))
        trail, trail_clips = trail_commands(path.achieved, timeline, f"{node}/trail", rgb)
        commands += trail
        clips.update(trail_clips)
    return commands, clips


def scene_legend(paths: list[TaskPath]) -> Legend:
    """The scene's legend with the tasks: the primary named, then each other task.

    Without tasks, :data:`~clik.viz.palette.LEGEND`.
    """
    primary = next((p.name for p in paths if p.primary), None)
    colours = task_colours(paths)
    legend: Legend = []
    for rgb, label in palette.LEGEND:
        if primary is not None and rgb in (palette.REFERENCE, palette.TRAIL):
            label = f"{label} ({primary})"
        legend.append((rgb, label))
    return legend + [(colours[p.name], p.name) for p in paths if not p.primary]
