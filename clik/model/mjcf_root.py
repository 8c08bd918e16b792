"""The root body of an MJCF model: its free joint, its pose and its keys.

Part of :func:`clik.model.mjcf_check.check_mjcf`. The root body's free joint is removed
(its 7 ``qpos`` values leave every key: :attr:`MjcfDocument.home_base` keeps the ``home``
key's), and so is the root body's pose (``pos``, ``quat``, ``euler``, ...): the base is
clik's choice (fixed, planar, floating) and :mod:`clik.model.mjcf` places the root body
itself, at :attr:`MjcfDocument.root_probe`'s
pose. With a fixed base a removed free joint is warned (:class:`FreeJointWeldedWarning`);
with a planar or floating base the ``<keyframe>`` leaves the document too and clik reads
the ``home`` key (:attr:`MjcfDocument.home_joints`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from clik.errors import ClikWarning, user_stacklevel
from clik.model.base import FIXED
from clik.model.urdf_check import MAX_LINKS, MAX_MOVABLE_JOINTS
from clik.model.urdf_numbers import Fail, shown

SOURCE_ATTRIBUTE = "clik-source"
"""Attribute naming an element's file while the document is merged (removed after)."""

MAX_BODIES = MAX_LINKS
"""Most bodies (and most geoms) in an MJCF model, as many as a URDF's links."""

FREE_JOINT_VALUES = 7
"""Values of a free joint in a MuJoCo ``qpos``: 3 for its position, 4 for its quaternion
``(w, x, y, z)`` (MuJoCo writes the scalar first; Pinocchio's free-flyer last)."""

HOME_KEY = "home"
"""Name of the ``<key>`` used as the reference configuration when the model has one."""

POSE_ATTRIBUTES = ("pos", "quat", "axisangle", "euler", "xyaxes", "zaxis")
"""A body's pose in its parent (MuJoCo allows one orientation attribute)."""


class FreeJointWeldedWarning(ClikWarning):
    """With a fixed base, the root body's free joint was removed.

    The body is welded where the file places it; ``base="floating"`` keeps it free.
    """


class EqualityIgnoredWarning(ClikWarning):
    """The model's ``<equality>`` constraints are not applied by clik.

    MuJoCo holds them by forces in simulation (closed chains, a gripper's coupled
    fingers); clik's joints move independently. Lock the joints or write the coupling
    as a URDF mimic joint when it matters.
    """


@dataclass
class MjcfDocument:
    """An MJCF model as clik hands it to MuJoCo's compiler: one checked, self-contained document.

    Attributes:
        path: The main model file.
        text: The document: includes expanded, sections merged, mesh and texture files
            as absolute paths (resolved), ``meshdir``/``texturedir``/``assetdir``/
            ``strippath`` removed.
        files: Every file read, resolved: the main file, the includes, the meshes,
            the textures.
        degrees: The file's angles are in degrees (``<compiler angle>``, MuJoCo's
            default).
        welded: Name of the root body's free joint removed (welded, or replaced by the
            base's root joint), or None.
        base: The base the document was checked for (:data:`clik.model.base.BASES`).
        root_probe: A one-body document holding the root body's pose attributes (removed
            from ``text``) and a hinge: MuJoCo compiles that body's pose. None when
            the root body has no pose attributes (it is at the world's origin).
        home_base: The ``home`` key's 7 free-joint values as MuJoCo writes them
            (``x, y, z`` [m], quaternion ``w, x, y, z``), or None (no such key, or no
            free joint).
        home_joints: With a planar or floating base (the ``<keyframe>`` removed from
            ``text``): the ``home`` key's values of the joints (after the free joint's),
            or None when there is no ``home`` key with ``qpos``.
        lines: For each line of ``text`` (one element per line), the file and line the
            element came from: MuJoCo's compiler's messages name lines of ``text``.
        qpos0: MuJoCo's ``qpos0`` of the compiled document (each joint's ``ref``; the
            root body's free joint is not in it), set when the model is built.
        root_index: The root body's rank among the ``<worldbody>``'s bodies; the others
            hold no joint and no geom (frames such as a ``world_link``, welded to the
            world).
    """

    path: Path
    text: str
    files: list[Path] = field(default_factory=list)
    degrees: bool = True
    welded: str | None = None
    base: str = FIXED
    root_probe: str | None = None
    home_base: list[float] | None = None
    home_joints: list[float] | None = None
    lines: dict[int, tuple[str, int]] = field(default_factory=dict)
    qpos0: list[float] | None = None
    root_index: int = 0


def _in_world(element: etree._Element) -> bool:
    """True for an element under ``<worldbody>`` (not in a ``<default>``)."""
    return any(parent.tag == "worldbody" for parent in element.iterancestors())


def check_world(root: etree._Element, path: Path, fail: Fail, document: MjcfDocument) -> None:
    """The root bodies, budgets; the first one's free joint and pose removed into ``document``.

    Several root bodies (a bimanual cell) load with a fixed base only, the others
    welded where the file places them; empty bodies (no joint, no geom) are frames.
    """
    world = root.find("worldbody")
    world_bodies = [] if world is None else world.findall("body")
    bodies = [b for b in world_bodies if not _empty(b)]  # empty ones: frames on the world
    if not bodies:
        raise fail("the model has no <body> in its <worldbody>: no robot to load", world)
    document.root_index = world_bodies.index(bodies[0])
    if len(bodies) > 1:
        _check_more_roots(bodies, document, fail)
    all_bodies = [b for body in bodies for b in body.iter("body")]
    geoms = [g for g in root.iter("geom") if _in_world(g)]
    if max(len(all_bodies), len(geoms)) > MAX_BODIES:
        found = f"{len(all_bodies)} bodies and {len(geoms)} geoms"
        raise fail(f"the model has {found}, above the budget of {MAX_BODIES} (MAX_BODIES)")
    joints = [j for body in bodies for j in body.iter("joint", "freejoint")]
    free = [j for j in joints if j.tag == "freejoint" or j.get("type") == "free"]
    welded = None
    for joint in free:
        if joint.getparent() is not bodies[0]:
            raise fail("a free joint below the root body (MuJoCo allows none)", joint)
        welded = joint.get("name") or f"{bodies[0].get('name', 'root')} (free joint)"
        bodies[0].remove(joint)
        joints.remove(joint)
    _read_keys(root, welded is not None, fail, document)
    document.welded = welded
    document.root_probe = _root_probe(root, bodies[0])
    if welded is not None and document.base == FIXED:
        warnings.warn(
            FreeJointWeldedWarning(
                f"{path}: the root body's free joint {welded!r} was removed: the robot is "
                "loaded with a fixed base, welded at the pose the file gives its root body "
                '(base="floating" keeps it free)'
            ),
            stacklevel=user_stacklevel(),
        )
    if not joints:
        raise fail("the robot has no movable (hinge or slide) joint", bodies[0])
    if len(joints) > MAX_MOVABLE_JOINTS:
        raise fail(
            f"the robot has {len(joints)} joints, above the budget of {MAX_MOVABLE_JOINTS} "
            "(clik.model.urdf_check.MAX_MOVABLE_JOINTS)",
            bodies[0],
        )


def _check_more_roots(bodies: list[etree._Element], document: MjcfDocument, fail: Fail) -> None:
    """Several root bodies (two arms on a table): fixed base only, no free body among them.

    The first is the root body (its free joint, if any, handled as for one root); the
    others are welded to the world where the file places them.
    """
    names = ", ".join(shown(b.get("name", "(unnamed)")) for b in bodies[:10])
    if document.base != FIXED:
        raise fail(
            f"the <worldbody> holds {len(bodies)} bodies ({names}): a {document.base} base "
            'moves one root body; load it with base="fixed" (each body welded where the '
            "file places it) or keep one robot per file",
            bodies[1],
        )
    for body in bodies[1:]:
        for joint in body.iter("joint", "freejoint"):
            if joint.tag == "freejoint" or joint.get("type") == "free":
                raise fail(
                    f"body {shown(body.get('name', '(unnamed)'))} has a free joint: a second "
                    "free body is an object, not part of the robot (give it as an obstacle)",
                    joint,
                )


def _empty(body: etree._Element) -> bool:
    """A body holding no joint and no geom (a frame, possibly with sites): kept, welded."""
    return not any(True for _ in body.iter("joint", "freejoint", "geom"))


def _read_keys(root: etree._Element, free: bool, fail: Fail, document: MjcfDocument) -> None:
    """Drop a free joint's values from every key; keep the ``home`` key's in ``document``.

    With a planar or floating base the ``<keyframe>`` leaves the document: its keys
    hold no values for the base's root joint.
    """
    for key in root.iter("key"):
        written = key.get("qpos")
        if written is None:
            continue
        values = [float(v) for v in written.split()]  # checked: finite numbers
        if free and len(values) < FREE_JOINT_VALUES:
            raise fail(
                f"<key> {shown(key.get('name', ''))} has {len(values)} qpos values: the free "
                f"joint alone needs {FREE_JOINT_VALUES} (x y z qw qx qy qz)",
                key,
            )
        joint_values = values[FREE_JOINT_VALUES:] if free else values
        if key.get("name") == HOME_KEY and document.home_joints is None:
            document.home_base = values[:FREE_JOINT_VALUES] if free else None
            document.home_joints = joint_values
        if free:
            key.set("qpos", " ".join(written.split()[FREE_JOINT_VALUES:]))
    if document.base != FIXED:
        for keyframe in root.findall("keyframe"):
            root.remove(keyframe)
    else:
        document.home_joints = None  # the compiled model's keys are read on a fixed base


def _root_probe(root: etree._Element, body: etree._Element) -> str | None:
    """Move the root body's pose out of the document into a one-body probe document.

    The probe keeps the model's ``<compiler>`` (angle unit, Euler sequence) and puts a
    hinge in a body with the root body's pose attributes: MuJoCo's compiler places that
    body as it places any body. None when the body has no pose.
    """
    pose = {a: str(body.get(a)) for a in POSE_ATTRIBUTES if body.get(a) is not None}
    if not pose:
        return None
    for attribute in pose:
        del body.attrib[attribute]
    probe = etree.Element("mujoco", model="probe")
    compiler = root.find("compiler")
    if compiler is not None:
        kept = {k: v for k, v in compiler.attrib.items() if k != SOURCE_ATTRIBUTE}
        probe.append(etree.Element("compiler", kept))
    placed = etree.SubElement(etree.SubElement(probe, "worldbody"), "body", name="probe", **pose)
    etree.SubElement(placed, "joint", name="probe", type="hinge")
    etree.SubElement(placed, "geom", type="sphere", size="0.1")
    return etree.tostring(probe, encoding="unicode")
