"""A tracking result as a list of meshcat commands: robot, obstacles, paths, animation.

The same commands feed a live meshcat server (:func:`clik.viz.show`) and the
self-contained HTML file (:func:`clik.viz.export_html`). Scene tree:

- ``/meshcat/robot/<joint>/<geometry>``: the robot (visual or collision geometry);
- ``/meshcat/obstacles/<name>/{body,shell}``: obstacles and threshold shells;
- ``/meshcat/clouds/<name>/points``: point-cloud obstacles (:mod:`clik.viz.cloud_layer`);
- ``/meshcat/paths/reference`` and ``/meshcat/paths/trail/<k>``: the task frame's paths;
- ``/meshcat/tasks/<name>/...``: a several-task run's other tasks, when the scene is
  given the run's goals (:mod:`clik.viz.task_layer`);
- ``/meshcat/regions/<name>``: the regions the kinds report (:mod:`clik.viz.shape_layer`);
- ``/meshcat/witness/...``: witness segments of the obstacle, self-collision and cloud rows;

then one animation (real time, ``fps`` frames per second, looping) and the
default camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from clik.errors import InputError
from clik.viz import palette
from clik.viz.camera import View, default_view, is_planar
from clik.viz.cloud_layer import cloud_commands
from clik.viz.commands import Command, delete, set_animation, set_property
from clik.viz.obstacle_layer import obstacle_commands, obstacle_tracks, placement
from clik.viz.path_layer import reference_commands, trail_commands
from clik.viz.robot_layer import (
    drawn_geometry,
    highlight_tracks,
    joint_range_states,
    joint_tracks,
    robot_commands,
)
from clik.viz.shape_layer import region_layer
from clik.viz.task_layer import Legend, scene_legend, task_layer
from clik.viz.task_paths import TaskPath, task_paths
from clik.viz.timeline import Timeline, frame_origins, joint_placements
from clik.viz.witness_layer import monitor_segments, row_segments

if TYPE_CHECKING:
    from collections.abc import Sequence

    import pinocchio as pin

    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.tasks.goal import Goal

Geometry = Literal["visual", "collision"]
"""Which of the robot's geometry models is drawn."""

GEOMETRIES = ("visual", "collision")


@dataclass
class Scene:
    """The commands that draw and animate one result.

    Attributes:
        commands: Viewer commands, in order (the animation comes last but the camera).
        timeline: The animation's frames.
        view: Default camera.
        robot_nodes: Scene paths of the robot's joint nodes.
        obstacle_nodes: Scene paths of the obstacles.
        tasks: The tasks' paths drawn (a several-task run's, when its goals were given).
        legend: ``(colour, label)`` of each legend entry (the HTML caption).
    """

    commands: list[Command]
    timeline: Timeline
    view: View
    robot_nodes: list[str] = field(default_factory=list)
    obstacle_nodes: list[str] = field(default_factory=list)
    tasks: list[TaskPath] = field(default_factory=list)
    legend: Legend = field(default_factory=lambda: list(palette.LEGEND))


def result_robot(result: TrackingResult, robot: Robot | None) -> Robot:
    """The robot to draw a result with, checked against the result's configurations."""
    robot = robot if robot is not None else result.robot
    if robot is None:
        raise InputError(
            "robot",
            "the Robot the result was computed with (a result read with "
            "TrackingResult.load has none: pass robot=clik.Robot.load(...))",
        )
    q = np.asarray(result.q)
    if q.ndim != 2 or q.shape[1] != robot.nq or len(q) != len(result.t):
        raise InputError(
            "result.q",
            f"an array of shape ({len(result.t)}, {robot.nq}) for {robot.name}",
            got=f"an array of shape {q.shape}",
        )
    return robot


def build_scene(
    result: TrackingResult,
    robot: Robot | None = None,
    geometry: Geometry = "visual",
    fps: float = 30.0,
    play: bool = True,
    tasks: Sequence[Goal] | None = None,
) -> Scene:
    """Commands that draw ``result`` and animate it in real time.

    Args:
        result: A tracking result (with its ``robot``, or pass ``robot``).
        robot: The robot, when ``result.robot`` is not set.
        geometry: ``"visual"`` meshes, or the lighter ``"collision"`` geometry.
            A robot without visual geometry is drawn with its collision geometry.
        fps: Animation frames per second of run time [1/s].
        play: Start playing when the scene is loaded.
        tasks: A several-task run's goals (a result does not keep them): each task's
            reference and path in a colour of its own, named in the legend.

    Returns:
        The scene.

    Raises:
        InputError: No robot, a configuration size that does not match it, an
            unknown ``geometry``, a bad ``fps``, or ``tasks`` not the run's goals.
    """
    robot = result_robot(result, robot)
    gmodel = _geometry_model(robot, geometry)
    timeline = Timeline.from_times(result.t, fps)
    model = robot.model
    q = np.asarray(result.q)[timeline.index]

    commands: list[Command] = [
        delete("/meshcat"),
        set_property("/Background", "top_color", list(palette.BACKGROUND_TOP)),
        set_property("/Background", "bottom_color", list(palette.BACKGROUND_BOTTOM)),
    ]
    clips: dict[str, list[dict[str, Any]]] = {}

    robot_cmds, parts = robot_commands(robot, gmodel)
    commands += robot_cmds
    placements = joint_placements(model, q)
    clips.update(joint_tracks(model, placements, timeline))
    states = joint_range_states(robot, result, timeline)
    clips.update(highlight_tracks(states, parts, timeline))

    obstacles = list(result.info.get("obstacles") or [])
    obstacle_cmds, obstacle_nodes = _obstacle_layer(result, obstacles)
    commands += obstacle_cmds
    clips.update(obstacle_tracks(obstacles, timeline, float(result.t[0])))

    region_cmds, region_clips = region_layer(
        robot, list(result.info.get("shapes") or []), q, timeline
    )
    commands += region_cmds
    clips.update(region_clips)

    paths = [] if tasks is None else task_paths(result, tasks, robot)
    for layer in (
        _path_layer(result, paths, timeline),
        row_segments(result, timeline),
        monitor_segments(robot, result, timeline),
    ):
        commands += layer[0]
        clips.update(layer[1])

    # A single frame still gets an (empty) animation: it replaces a live server's previous one.
    animated = len(timeline) > 1
    commands.append(set_animation(clips if animated else {}, play=play and animated))

    motion, extents = _shown_points(robot, result, q, obstacles)
    motion = np.vstack([motion, *_task_points(paths)])
    view = default_view(np.vstack([motion, extents]), planar=is_planar(motion))
    commands += view.commands()
    robot_nodes = sorted(
        {p for p in clips if p.startswith("/meshcat/robot/") and not p.endswith("<object>")}
    )
    return Scene(commands, timeline, view, robot_nodes, obstacle_nodes, paths, scene_legend(paths))


def _obstacle_layer(
    result: TrackingResult, obstacles: list[dict[str, Any]]
) -> tuple[list[Command], list[str]]:
    """The obstacles (at their poses at the run's start) and the clouds; their nodes."""
    commands = obstacle_commands(obstacles, float(result.t[0]))
    clouds = cloud_commands(result)
    nodes = [f"/meshcat/obstacles/{o['name']}" for o in obstacles]
    nodes += [c["path"].rpartition("/")[0] for c in clouds]
    return commands + clouds, nodes


def _geometry_model(robot: Robot, geometry: Geometry) -> pin.GeometryModel:
    """The geometry drawn: visual meshes, collision geometry where they are missing.

    See :func:`~clik.viz.robot_layer.drawn_geometry`.

    Raises:
        InputError: An unknown ``geometry``.
    """
    if geometry not in GEOMETRIES:
        raise InputError("geometry", " or ".join(repr(g) for g in GEOMETRIES), got=geometry)
    return drawn_geometry(robot, geometry)


def _path_layer(
    result: TrackingResult, paths: list[TaskPath], timeline: Timeline
) -> tuple[list[Command], dict[str, list[dict[str, Any]]]]:
    """The primary task's reference and trail, then the other tasks' (when given)."""
    commands = reference_commands(result.reference_position)
    trail, clips = trail_commands(np.asarray(result.position), timeline)
    task_cmds, task_clips = task_layer(paths, timeline)
    return commands + trail + task_cmds, {**clips, **task_clips}


def _task_points(paths: list[TaskPath]) -> list[np.ndarray]:
    """The tasks' paths and references (finite points), for framing the view."""
    points = [np.empty((0, 3))]
    for path in paths:
        for p in (path.achieved, path.reference):
            if p is not None:
                points.append(p[np.all(np.isfinite(p), axis=1)])
    return points


def _shown_points(
    robot: Robot, result: TrackingResult, q: np.ndarray, obstacles: list[dict[str, Any]]
) -> tuple[np.ndarray, np.ndarray]:
    """Points the default view must fit: the motion (frames, paths), and obstacle extents."""
    motion = [frame_origins(robot.model, q).reshape(-1, 3), np.asarray(result.position)]
    if result.reference_position is not None:
        motion.append(np.asarray(result.reference_position))
    extents = [np.empty((0, 3))]
    duration = float(result.t[-1] - result.t[0])
    for spec in obstacles:
        extent = float(spec.get("threshold") or 0.0) + _obstacle_radius(spec)
        for t in (0.0, duration):
            center = placement(spec, float(result.t[0]) + t)[:3, 3]
            extents.append(center + extent * np.vstack([np.eye(3), -np.eye(3)]))
    return np.vstack(motion), np.vstack(extents)


def _obstacle_radius(spec: dict[str, Any]) -> float:
    """A rough size of an obstacle [m] for framing the view."""
    if spec["shape"] == "box":
        return 0.5 * float(np.linalg.norm(spec.get("size", (0.0, 0.0, 0.0))))
    if spec["shape"] in ("capsule", "cylinder"):
        return float(spec.get("radius", 0.0)) + 0.5 * float(spec.get("length", 0.0))
    return float(spec.get("radius", 0.0) or 0.0)
