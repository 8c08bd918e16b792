"""The robot in the scene: one node per joint, its geometry below, animated by the run.

Node ``/meshcat/robot/<joint>`` is placed at the joint's world placement
``oMi`` at every frame (position and quaternion tracks); each geometry object
of that joint's body is a child node at its fixed placement ``jMg``. Links of
a joint whose range row is active turn :data:`~clik.viz.palette.JOINT_LIMIT_ACTIVE`
(inside the threshold without an active row: :data:`~clik.viz.palette.JOINT_LIMIT_NEAR`),
by discrete ``material.color`` tracks.

What is drawn (:func:`drawn_geometry`): the visual geometry, except that a link
whose visual mesh was missing at loading
(:attr:`~clik.model.robot.Robot.missing_visuals`) is drawn with its collision
geometry instead, and a robot with no visual geometry at all is drawn with its
collision geometry; or, on request, the collision geometry alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.constraints.joint_limits import limits_by_q
from clik.viz import palette
from clik.viz.commands import (
    Command,
    phong_material,
    scene_object,
    set_object,
    set_transform,
    track,
)
from clik.viz.geometry import Shape, geometry_object_shape
from clik.viz.timeline import Timeline

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult

ROOT = "/meshcat/robot"
"""Scene path of the robot."""

NORMAL, NEAR, ACTIVE = 0, 1, 2
"""Joint-range states of a joint at a frame."""


def node_name(name: str) -> str:
    """A scene-tree path element (no ``/``)."""
    return name.replace("/", "_") or "_"


def joint_path(model: pin.Model, joint: int) -> str:
    """Scene path of joint ``joint``'s node."""
    return f"{ROOT}/{node_name(model.names[joint])}"


def drawn_geometry(robot: Robot, geometry: str = "visual") -> pin.GeometryModel:
    """The geometry that draws ``robot``: ``"visual"`` (with fallbacks) or ``"collision"``.

    With ``"visual"``, a link with a missing visual mesh shows its collision geometry in
    place of all its visual geometry (never half drawn), and a robot whose visual model
    is empty shows its collision model.

    Args:
        robot: The robot.
        geometry: ``"visual"`` or ``"collision"`` (checked by the caller).

    Returns:
        The robot's own collision or visual model, or a new model holding visual and
        collision geometry objects (the same shapes, not copied).
    """
    if geometry == "collision":
        return robot.collision_model
    visual = robot.visual_model
    if visual.ngeoms == 0:
        return robot.collision_model
    if not robot.missing_visuals:
        return visual
    frames = robot.model.frames
    stand_in = {missing.link for missing in robot.missing_visuals}
    drawn = pin.GeometryModel()
    for go in visual.geometryObjects:
        if frames[go.parentFrame].name not in stand_in:
            drawn.addGeometryObject(go)
    for go in robot.collision_model.geometryObjects:
        if frames[go.parentFrame].name in stand_in:
            drawn.addGeometryObject(go)
    return drawn


def robot_commands(
    robot: Robot, gmodel: pin.GeometryModel
) -> tuple[list[Command], dict[int, list[tuple[str, tuple[float, float, float]]]]]:
    """Draw every geometry object of ``gmodel`` under its joint's node.

    Returns:
        The commands, and for each joint the ``<object>`` paths of its geometry
        with their colours (for the highlight tracks).
    """
    model = robot.model
    commands: list[Command] = []
    parts: dict[int, list[tuple[str, tuple[float, float, float]]]] = {}
    cache: dict[Any, Shape] = {}
    used: set[str] = set()
    for go in gmodel.geometryObjects:
        shape = geometry_object_shape(go, cache)
        if shape is None:
            continue
        name = node_name(go.name)
        while f"{go.parentJoint}/{name}" in used:
            name += "_"
        used.add(f"{go.parentJoint}/{name}")
        path = f"{joint_path(model, go.parentJoint)}/{name}"
        rgba = np.asarray(go.meshColor, dtype=float)
        rgb = palette.link_color((float(rgba[0]), float(rgba[1]), float(rgba[2])))
        material = phong_material(rgb, opacity=float(rgba[3]), flat=shape.is_mesh)
        commands.append(
            set_object(path, scene_object("Mesh", shape.geometry, material, shape.matrix, go.name))
        )
        commands.append(set_transform(path, go.placement.homogeneous))
        parts.setdefault(go.parentJoint, []).append((f"{path}/<object>", rgb))
    return commands, parts


def joint_tracks(
    model: pin.Model, placements: np.ndarray, timeline: Timeline
) -> dict[str, list[dict[str, Any]]]:
    """Position and quaternion tracks of every moving joint node.

    Args:
        model: The kinematic model.
        placements: Joint world placements per frame (K, njoints, 4, 4).
        timeline: The frames.
    """
    clips: dict[str, list[dict[str, Any]]] = {}
    for j in range(1, model.njoints):
        position = placements[:, j, :3, 3]
        quaternion = np.array([pin.Quaternion(M[:3, :3]).coeffs() for M in placements[:, j]])
        # Keep consecutive quaternions in the same hemisphere (smooth interpolation).
        for k in range(1, len(quaternion)):
            if quaternion[k] @ quaternion[k - 1] < 0.0:
                quaternion[k] = -quaternion[k]
        clips[joint_path(model, j)] = [
            track(".position", "vector3", timeline.times, position),
            track(".quaternion", "quaternion", timeline.times, quaternion),
        ]
    return clips


def joint_range_states(robot: Robot, result: TrackingResult, timeline: Timeline) -> np.ndarray:
    """Joint-range state (:data:`NORMAL`, :data:`NEAR`, :data:`ACTIVE`) per frame and joint.

    ``ACTIVE`` when a ``joint:<name>:lower|upper`` row is in the result's active
    set; ``NEAR`` when the joint is inside its threshold of the limits the run
    used (``summary_extra.joint_limits_used``) without an active row.
    """
    model = robot.model
    states = np.zeros((len(timeline), model.njoints), dtype=np.int8)
    used = result.info.get("summary_extra", {}).get("joint_limits_used")
    by_q = limits_by_q(used, robot, model.nq) if used else None
    if by_q is not None:
        lower, upper, threshold = by_q
        q = result.q[timeline.index]
        for j in range(1, model.njoints):
            joint = model.joints[j]
            i = joint.idx_q
            if joint.nq != 1 or not np.isfinite(threshold[i]):
                continue  # no range row (continuous, other joints)
            near = (q[:, i] >= upper[i] - threshold[i]) | (q[:, i] <= lower[i] + threshold[i])
            states[near, j] = NEAR
    active = result.extra.get("active")
    names = result.info.get("constraint_names", [])
    if active is not None and len(names):
        codes = {
            code: name.split(":")[1]
            for code, name in enumerate(names)
            if name.startswith("joint:") and name.count(":") == 2
        }
        for k, i in enumerate(timeline.index):
            for code in np.asarray(active[i]).reshape(-1):
                joint_name = codes.get(int(code))
                if joint_name is not None and model.existJointName(joint_name):
                    states[k, model.getJointId(joint_name)] = ACTIVE
    return states


def highlight_tracks(
    states: np.ndarray,
    parts: dict[int, list[tuple[str, tuple[float, float, float]]]],
    timeline: Timeline,
) -> dict[str, list[dict[str, Any]]]:
    """Colour tracks for the links of joints that come near or onto a range limit."""
    clips: dict[str, list[dict[str, Any]]] = {}
    for j, objects in parts.items():
        if j == 0 or not np.any(states[:, j]):
            continue
        for path, rgb in objects:
            colors = np.array([rgb, palette.JOINT_LIMIT_NEAR, palette.JOINT_LIMIT_ACTIVE])
            clips[path] = [
                track(
                    ".material.color", "color", timeline.times, colors[states[:, j]], discrete=True
                )
            ]
    return clips
