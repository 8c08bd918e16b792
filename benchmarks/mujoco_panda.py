"""The Panda clik loads, as a MuJoCo model: the same URDF, with the spheres as geoms.

The URDF goes through :func:`clik.sim.mujoco_model.mujoco_urdf` (the changes MuJoCo's
URDF import needs; measured, FK of MuJoCo and Pinocchio agree to 1e-15 on
example-robot-data's ``panda.urdf``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import clik
from clik.sim.mujoco_model import mujoco_urdf as model_urdf

SPHERE_PREFIX = "sphere"
"""Name prefix of the sphere geoms (``sphere0``, ``sphere1``, ...)."""


def mujoco_urdf(robot: clik.Robot) -> str:
    """The robot's URDF as MuJoCo can load it (:func:`clik.sim.mujoco_model.mujoco_urdf`)."""
    return model_urdf(robot)[0]


def panda_with_spheres(
    mujoco: Any, robot: clik.Robot, centres: Sequence[Sequence[float]], radius: float
) -> Any:
    """The robot as a MuJoCo model, with one sphere geom per centre on the world body.

    Args:
        mujoco: The imported ``mujoco`` module.
        robot: The robot.
        centres: Sphere centres [m] (none: the robot alone).
        radius: Sphere radius [m].

    Returns:
        The compiled ``mujoco.MjModel``; the spheres are the geoms named
        ``sphere0``, ``sphere1``, ...
    """
    spec = mujoco.MjSpec.from_string(mujoco_urdf(robot))
    for i, centre in enumerate(centres):
        spec.worldbody.add_geom(
            name=f"{SPHERE_PREFIX}{i}",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[radius, 0.0, 0.0],
            pos=[float(x) for x in centre],
        )
    return spec.compile()
