"""A live 3-D view of a running controller: the robot, its obstacles and targets, as they move.

:class:`LiveView` draws the robot and the obstacles once in the process's meshcat server
(:func:`clik.viz.live.live_server`, on 127.0.0.1), then :meth:`LiveView.update` moves
them: one transform per joint, per obstacle (its pose at time ``t``) and per target
marker. Call it at the view's rate (30 Hz is smooth), not at every control tick.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.clouds.drawn import MAX_DRAWN_POINTS
from clik.viz import palette
from clik.viz.cloud_layer import MIN_POINT_SIZE, cloud_path, points_object
from clik.viz.commands import (
    Command,
    delete,
    phong_material,
    scene_object,
    set_object,
    set_property,
    set_transform,
)
from clik.viz.geometry import sphere
from clik.viz.live import live_server
from clik.viz.obstacle_layer import obstacle_commands, obstacle_path, placement
from clik.viz.robot_layer import drawn_geometry, joint_path, robot_commands

if TYPE_CHECKING:
    from clik.constraints import ConstraintSet
    from clik.model.robot import Robot
    from clik.viz.server import MeshcatServer

TARGET_ROOT = "/meshcat/targets"
"""Scene path of the target markers."""

TARGET_RADIUS = 0.015
"""Radius of a target's marker [m]."""


class LiveView:
    """The robot, its obstacles and its targets in the meshcat server, moved by :meth:`update`.

    Args:
        robot: The robot.
        constraints: Its constraint set (its obstacles are drawn), or None.
        targets: Names of the target markers to draw (e.g. the controller's task names).
        geometry: ``"collision"`` (lighter, the default) or ``"visual"`` geometry.
        server: A meshcat server (default: the process's, started if none runs).
    """

    def __init__(
        self, robot: Robot, constraints: ConstraintSet | None = None,
        targets: Sequence[str] = (), geometry: str = "collision",
        server: MeshcatServer | None = None,
    ) -> None:  # fmt: skip
        self.robot = robot
        self.server = live_server() if server is None else server
        self.data = robot.model.createData()
        self.obstacles: list[dict[str, Any]] = (
            [] if constraints is None else constraints.obstacle_info()
        )
        gmodel = drawn_geometry(robot, geometry)
        commands: list[Command] = [
            delete("/meshcat"),
            set_property("/Background", "top_color", list(palette.BACKGROUND_TOP)),
            set_property("/Background", "bottom_color", list(palette.BACKGROUND_BOTTOM)),
        ]
        commands += robot_commands(robot, gmodel)[0]
        commands += obstacle_commands(self.obstacles)
        marker = sphere(TARGET_RADIUS)
        material = phong_material(palette.REFERENCE, opacity=0.8)
        for name in targets:
            commands.append(
                set_object(_target_path(name), scene_object("Mesh", marker.geometry, material))
            )
        self.server.send_all(commands)
        self.frames = 0
        """Updates sent so far."""

    @property
    def url(self) -> str:
        """The viewer's address (on 127.0.0.1)."""
        return str(self.server.web_url)

    def update(
        self, q: np.ndarray, t: float = 0.0, targets: Mapping[str, Any] | None = None,
        clouds: Mapping[str, np.ndarray] | None = None,
    ) -> None:  # fmt: skip
        """Move the robot to ``q``, the obstacles to their poses at ``t`` [s], the targets.

        Args:
            q: The robot's configuration (nq,).
            t: The time [s] (moving obstacles: ``position + t velocity``).
            targets: Target positions (3,) [m] or poses (``pin.SE3`` or 4x4) by name.
            clouds: Point clouds drawn anew, by name: ``(N, 3)`` world points [m]
                (at most :data:`~clik.clouds.drawn.MAX_DRAWN_POINTS` drawn, evenly).
        """
        model, data = self.robot.model, self.data
        pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
        commands = [
            set_transform(joint_path(model, j), data.oMi[j].homogeneous)
            for j in range(1, model.njoints)
        ]
        commands += [
            set_transform(obstacle_path(spec), placement(spec, t))
            for spec in self.obstacles
            if np.any(np.asarray(spec.get("velocity", (0.0, 0.0, 0.0))) != 0.0)
        ]
        for name, target in (targets or {}).items():
            commands.append(set_transform(_target_path(name), _marker(target)))
        for name, points in (clouds or {}).items():
            commands.append(live_cloud(name, np.asarray(points, dtype=float).reshape(-1, 3)))
        self.server.send_all(commands)
        self.frames += 1


def live_cloud(name: str, points: np.ndarray) -> Command:
    """A cloud's points (world [m], thinned to at most MAX_DRAWN_POINTS) as its scene object."""
    stride = max(1, -(-len(points) // MAX_DRAWN_POINTS))
    shown = points[::stride]
    return set_object(f"{cloud_path({'name': name})}/points", points_object(shown, MIN_POINT_SIZE))


def _target_path(name: str) -> str:
    return f"{TARGET_ROOT}/{name.replace('/', '_') or '_'}"


def _marker(target: Any) -> np.ndarray:
    """A marker's placement (4x4) at a target: its position (a pose's translation)."""
    M = np.eye(4)
    if isinstance(target, pin.SE3):
        M[:3, 3] = target.translation
        return M
    a = np.asarray(target, dtype=float)
    M[:3, 3] = a[:3, 3] if a.shape == (4, 4) else a[:3]
    return M
