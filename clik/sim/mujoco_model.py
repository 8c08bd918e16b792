"""A clik robot as MuJoCo compiles it: its URDF through MuJoCo's own URDF reader, or its MJCF.

MuJoCo's URDF import needs four changes to a robot's URDF (measured on example-robot-data's
Panda: forward kinematics of MuJoCo and Pinocchio agree to 1e-15): no ``<visual>``
elements (only collision geometry is simulated), meshes by absolute path (``package://``
resolved against the robot's package folders), the joints clik locks made ``fixed`` at
their locked value, and ``<mujoco><compiler fusestatic="false" .../></mujoco>`` so that
every link stays a body. MuJoCo reads STL, OBJ and MSH meshes: a collision mesh in another
format (Collada) is left out and named (:attr:`MujocoRobot.dropped`). MuJoCo collides a
mesh as its convex hull, as clik does.

Joints are matched by name. A robot on a planar or floating base is refused: the replay
drives joints through position servos, and a base needs contacts and a balance controller
that a replay does not have.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from lxml import etree

from clik.errors import InputError
from clik.model.joint_order import JointOrder
from clik.model.robot import Robot

PACKAGE_PREFIX = "package://"
POINT_RADIUS = 1e-6
"""The radius [m] a geom of radius 0 (a segment, a point) gets in MuJoCo."""
MESH_FORMATS = (".stl", ".obj", ".msh")
"""The mesh files MuJoCo reads (lower case)."""


@dataclass
class MujocoRobot:
    """A robot's MuJoCo model specification and how its joints map to clik's.

    Attributes:
        spec: The ``mujoco.MjSpec`` (not compiled: servos and obstacles are added to it).
        joints: clik's joints, one value each (:class:`~clik.model.joint_order.JointOrder`).
        dropped: Collision meshes MuJoCo cannot read, left out (file names).
        pads: Geoms of radius 0 (segments, points) given :data:`POINT_RADIUS` for
            MuJoCo, by name: their distances get it back.
    """

    spec: Any
    joints: JointOrder
    dropped: list[str] = field(default_factory=list)
    pads: dict[str, float] = field(default_factory=dict)


def _floats(text: str | None, default: str) -> np.ndarray:
    return np.array([float(x) for x in (text or default).split()])


def _resolve_meshes(root: Any, package_dirs: Sequence[str], urdf_dir: Path) -> None:
    """Every ``<mesh filename>`` as an absolute path."""
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if name.startswith("file://"):
            name = name[len("file://") :]
        if name.startswith(PACKAGE_PREFIX):
            relative = name[len(PACKAGE_PREFIX) :]
            found = [Path(d) / relative for d in package_dirs if (Path(d) / relative).is_file()]
            if not found:
                parts = relative.split("/", 1)
                found = [
                    Path(d) / parts[-1]
                    for d in package_dirs
                    if Path(d).name == parts[0] and (Path(d) / parts[-1]).is_file()
                ]
            if not found:
                raise InputError(
                    "robot.meshes",
                    f"{name} under one of the robot's package folders {list(package_dirs)}",
                )
            mesh.set("filename", str(found[0]))
        elif not Path(name).is_absolute():
            mesh.set("filename", str(urdf_dir / name))
        else:
            mesh.set("filename", name)


def _drop_unreadable(root: Any) -> list[str]:
    """Collision meshes MuJoCo cannot read, removed; their file names."""
    dropped = []
    for collision in list(root.iter("collision")):
        mesh = collision.find("geometry/mesh")
        if mesh is None:
            continue
        name = mesh.get("filename", "")
        if not name.lower().endswith(MESH_FORMATS):
            collision.getparent().remove(collision)
            dropped.append(name)
    return dropped


def _thin_geoms(root: Any) -> tuple[list[str], list[str]]:
    """Radius-0 spheres and cylinders given :data:`POINT_RADIUS`.

    Returns:
        Their collision names, and those Pinocchio's ``<collision_checking><capsule>``
        makes capsules.
    """
    thin = []
    for collision in root.iter("collision"):
        for shape in ("geometry/sphere", "geometry/cylinder"):
            node = collision.find(shape)
            if node is not None and float(node.get("radius", "1")) == 0.0:
                node.set("radius", repr(POINT_RADIUS))
                thin.append(collision.get("name", ""))
    capsules = [
        c.get("name", "") for c in root.iter("capsule") if c.getparent().tag == "collision_checking"
    ]
    for checking in list(root.iter("collision_checking")):
        checking.getparent().remove(checking)
    return thin, capsules


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


def mujoco_urdf(robot: Robot) -> tuple[str, list[str], list[str], list[str]]:
    """The robot's URDF as MuJoCo can load it (see the module's docstring).

    Args:
        robot: A robot loaded from a URDF or xacro file.

    Returns:
        The URDF text, the collision meshes left out (formats MuJoCo does not read), the
        collisions of radius 0 given :data:`POINT_RADIUS`, and those to make capsules.

    Raises:
        InputError: The robot has no URDF, or a mesh is not under its package folders.
    """
    if robot.source_path is None and robot.urdf_text is None:
        raise InputError("robot", "a robot loaded from a URDF, xacro or MJCF file", robot.name)
    parser = etree.XMLParser(resolve_entities=False, no_network=True, remove_comments=True)
    urdf_dir = Path(robot.source_path).parent if robot.source_path else Path.cwd()
    if robot.urdf_text is not None:
        root = etree.fromstring(robot.urdf_text.encode(), parser)
    else:
        root = etree.parse(str(robot.source_path), parser).getroot()
    for visual in list(root.iter("visual")):
        visual.getparent().remove(visual)
    _resolve_meshes(root, list(robot.package_dirs or []), urdf_dir)
    dropped = _drop_unreadable(root)
    thin, capsules = _thin_geoms(root)
    _fix_locked(root, dict(robot.locked or {}))
    for old in root.findall("mujoco"):
        root.remove(old)
    extension = etree.SubElement(root, "mujoco")
    etree.SubElement(
        extension,
        "compiler",
        fusestatic="false",
        strippath="false",
        balanceinertia="true",
        discardvisual="false",
    )
    return str(etree.tostring(root, encoding="unicode")), dropped, thin, capsules


def _massless(robot: Robot) -> None:
    """Refuse a kinematic model: links without mass cannot be simulated."""
    model = robot.model
    massless = [str(model.names[j]) for j in range(1, model.njoints) if model.inertias[j].mass <= 0]
    if massless:
        raise InputError(
            "robot.inertial",
            "links with mass and inertia (a physics replay moves masses; the links moved "
            f"by {', '.join(massless)} have none: a kinematic model)",
            robot.name,
        )


def robot_spec(mujoco: Any, robot: Robot) -> MujocoRobot:
    """The robot as a MuJoCo specification, with clik's joints mapped.

    Args:
        mujoco: The imported ``mujoco`` module.
        robot: A robot on a fixed base, from a URDF, xacro or MJCF file.

    Raises:
        InputError: A base, a joint of several degrees of freedom, a file MuJoCo refuses,
            or a joint of clik's that MuJoCo's model lacks.
    """
    joints = JointOrder.of(
        robot, "the replay drives joints through position servos; a base needs contacts "
        "and a balance controller",
    )  # fmt: skip
    _massless(robot)
    dropped: list[str] = []
    thin: list[str] = []
    capsules: list[str] = []
    try:
        if robot.mjcf is not None and robot.source_path is not None:
            spec = mujoco.MjSpec.from_file(str(robot.source_path))
        else:
            text, dropped, thin, capsules = mujoco_urdf(robot)
            spec = mujoco.MjSpec.from_string(text)
    except ValueError as exc:
        raise InputError("robot", f"a model MuJoCo compiles ({exc})", robot.name) from None
    present = {j.name for j in spec.joints}
    missing = [n for n in joints.names if n not in present]
    if missing:
        raise InputError(
            "robot.joints", f"joints MuJoCo's model of {robot.name} has", ", ".join(missing)
        )
    for geom in spec.geoms:
        if geom.name and geom.name in capsules:
            geom.type = mujoco.mjtGeom.mjGEOM_CAPSULE
    pads = {name: POINT_RADIUS for name in thin if name}
    return MujocoRobot(spec, joints, dropped, pads)
