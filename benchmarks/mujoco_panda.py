"""The Panda clik loads, as a MuJoCo model: the same URDF, with the spheres as geoms.

MuJoCo's URDF import needs four changes to example-robot-data's ``panda.urdf``
(measured, FK of MuJoCo and Pinocchio agree to 1e-15): no ``<visual>`` elements,
the collision meshes by absolute path (``package://`` resolved against the robot's
package folders), the joints clik locks (the fingers) made ``fixed`` at their locked
value, and ``<mujoco><compiler fusestatic="false" .../></mujoco>`` so that every
link, ``panda_hand`` among them, stays a body. MuJoCo collides a mesh as its convex
hull, as clik does.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from lxml import etree

import clik

PACKAGE_PREFIX = "package://"
SPHERE_PREFIX = "sphere"
"""Name prefix of the sphere geoms (``sphere0``, ``sphere1``, ...)."""


def _floats(text: str | None, default: str) -> np.ndarray:
    return np.array([float(x) for x in (text or default).split()])


def _resolve_meshes(root: Any, package_dirs: Sequence[str], urdf: Path) -> None:
    """Every ``<mesh filename>`` as an absolute path."""
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if name.startswith(PACKAGE_PREFIX):
            relative = name[len(PACKAGE_PREFIX) :]
            found = [Path(d) / relative for d in package_dirs if (Path(d) / relative).is_file()]
            if not found:
                raise FileNotFoundError(f"{name}: not under any of {list(package_dirs)}")
            mesh.set("filename", str(found[0]))
        elif not Path(name).is_absolute():
            mesh.set("filename", str(urdf.parent / name))


def _fix_locked(root: Any, locked: dict[str, float]) -> None:
    """Each locked joint ``fixed``, its origin moved by its locked value along its axis."""
    for joint in root.iter("joint"):
        value = locked.get(joint.get("name", ""))
        if value is None:
            continue
        origin = joint.find("origin")
        if origin is None:
            origin = etree.SubElement(joint, "origin")
        xyz = _floats(origin.get("xyz"), "0 0 0")
        rpy = _floats(origin.get("rpy"), "0 0 0")
        axis_node = joint.find("axis")
        axis = _floats(None if axis_node is None else axis_node.get("xyz"), "1 0 0")
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz)
        if joint.get("type") == "prismatic":
            placement = placement * pin.SE3(np.eye(3), axis * value)
        elif joint.get("type") in ("revolute", "continuous"):
            placement = placement * pin.SE3(pin.exp3(axis * value), np.zeros(3))
        origin.set("xyz", " ".join(repr(float(x)) for x in placement.translation))
        origin.set("rpy", " ".join(repr(float(x)) for x in pin.rpy.matrixToRpy(placement.rotation)))
        joint.set("type", "fixed")
        for tag in ("axis", "limit", "mimic", "dynamics", "safety_controller", "calibration"):
            for child in joint.findall(tag):
                joint.remove(child)


def mujoco_urdf(robot: clik.Robot) -> str:
    """The robot's URDF as MuJoCo can load it (see the module's docstring).

    Args:
        robot: A robot loaded from a URDF file.
    """
    if robot.source_path is None:
        raise ValueError(f"robot {robot.name} has no URDF file")
    urdf = Path(robot.source_path)
    parser = etree.XMLParser(resolve_entities=False, no_network=True, remove_comments=True)
    root = etree.parse(str(urdf), parser).getroot()
    for visual in list(root.iter("visual")):
        visual.getparent().remove(visual)
    _resolve_meshes(root, robot.package_dirs, urdf)
    _fix_locked(root, dict(getattr(robot, "locked", {}) or {}))
    extension = etree.SubElement(root, "mujoco")
    etree.SubElement(
        extension, "compiler", fusestatic="false", strippath="false", balanceinertia="true"
    )
    return str(etree.tostring(root, encoding="unicode"))


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
