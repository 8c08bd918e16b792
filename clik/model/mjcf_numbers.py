"""An MJCF model's numbers, checked before MuJoCo's compiler reads them.

Bodies, geoms, sites, joints, inertials, meshes and keys (in the world or in default
classes): every number finite, in its physical range (:mod:`clik.model.urdf_numbers`'s
ranges: positions and sizes within :data:`~clik.bounds.MAX_COORDINATE` [m], masses
within :data:`~clik.model.urdf_numbers.MAX_MASS`), counted right; joint ranges
``lower <= upper``; no zero axis, quaternion (all four numbers: MuJoCo writes ``w``
first, so ``quat="0 0 0 1"`` is a half turn about z) or ``zaxis``; mesh scales within
:data:`~clik.bounds.SCALE_RANGE`; no ball joint (clik's joints have one degree of
freedom) and only the geom types clik reads. :func:`unit_axis_angles` writes each
``axisangle``'s axis as a unit vector (MuJoCo normalises it too).
"""

from __future__ import annotations

import math

from lxml import etree

from clik.model.mesh_check import MAX_MESH_ELEMENTS, MeshRefused, check_scale
from clik.model.urdf_numbers import Fail, read_numbers, shown

SUPPORTED_GEOMS = ("plane", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh")
"""Geom types clik reads (a plane is dropped, see :mod:`clik.model.mjcf_geometry`)."""

# attribute -> (count or None for "any", kind for read_numbers, nonnegative)
_NUMBERS: dict[str, dict[str, tuple[int | None, str, bool]]] = {
    "body": {"pos": (3, "position", False)},
    "geom": {
        "pos": (3, "position", False),
        "fromto": (6, "position", False),
        "size": (None, "position", True),
        "mass": (1, "mass", True),
        "density": (1, "limit", True),
    },
    "site": {"pos": (3, "position", False), "size": (None, "position", True)},
    "joint": {
        "pos": (3, "position", False),
        "axis": (3, "limit", False),
        "range": (2, "limit", False),
        "ref": (1, "limit", False),
        "damping": (1, "limit", True),
        "armature": (1, "limit", True),
        "frictionloss": (1, "limit", True),
        "springref": (1, "limit", False),
        "stiffness": (1, "limit", True),
    },
    "inertial": {
        "pos": (3, "position", False),
        "mass": (1, "mass", True),
        "diaginertia": (3, "mass", True),
        "fullinertia": (6, "mass", False),
    },
    "mesh": {"vertex": (None, "position", False)},
    "key": {"qpos": (None, "limit", False)},
}
_ORIENTATIONS = {"quat": 4, "axisangle": 4, "euler": 3, "xyaxes": 6, "zaxis": 3}
_ORIENTED = ("body", "geom", "site", "joint", "inertial", "camera", "frame")


def check_numbers(element: etree._Element, fail: Fail) -> None:
    """The numbers of one element: finite, in range, well counted."""
    tag = str(element.tag)
    what = f"<{tag}>" + (f" {shown(element.get('name', ''))}" if element.get("name") else "")
    for attribute, (count, kind, nonnegative) in _NUMBERS.get(tag, {}).items():
        if element.get(attribute) is None:
            continue
        n = count if count is not None else _count(element, attribute, what, fail)
        values = read_numbers(element, attribute, n, what, fail, kind, nonnegative)
        if attribute == "range" and values[0] > values[1]:
            raise fail(f"{what} range={values} has lower > upper", element)
        if attribute == "vertex" and (n % 3 or n // 3 > MAX_MESH_ELEMENTS):
            raise fail(f"{what} vertex= has {n} numbers: not (x, y, z) triples within budget")
        if attribute == "axis" and not any(values):
            raise fail(f"{what} axis={values} is zero", element)
    if tag in _ORIENTED:
        for attribute, count in _ORIENTATIONS.items():
            if element.get(attribute) is not None:
                values = read_numbers(element, attribute, count, what, fail, "limit")
                axis = values if attribute == "quat" else values[:3]  # quat: w x y z
                if attribute in ("quat", "zaxis", "axisangle") and not any(axis):
                    raise fail(f"{what} {attribute}={values} is zero", element)
    if tag == "mesh" and element.get("scale") is not None:
        scale = read_numbers(element, "scale", 3, what, fail, "scale")
        try:
            check_scale(scale, what)
        except MeshRefused as refused:
            raise fail(str(refused), element) from None
    if tag == "joint" and element.get("type") == "ball":
        body = element.getparent()
        owner = f" of body {shown(body.get('name', '(unnamed)'))}" if body.tag == "body" else ""
        raise fail(
            f"{what}{owner} is a ball joint: clik's joints have one degree of freedom "
            "(hinge or slide); write it as three hinges about x, y and z",
            element,
        )
    if tag == "geom" and element.get("type", "sphere") not in SUPPORTED_GEOMS:
        raise fail(
            f"{what} type={element.get('type')!r}: clik reads {', '.join(SUPPORTED_GEOMS)}",
            element,
        )


def unit_axis_angles(root: etree._Element) -> None:
    """Write each ``axisangle``'s axis as a unit vector (as MuJoCo reads it)."""
    for element in root.iter():
        written = element.get("axisangle") if isinstance(element.tag, str) else None
        if written is not None:
            values = [float(v) for v in written.split()]  # checked: 4 finite, axis not zero
            norm = math.sqrt(sum(v * v for v in values[:3]))
            element.set(
                "axisangle", " ".join(repr(v) for v in [*(v / norm for v in values[:3]), values[3]])
            )


def _count(element: etree._Element, attribute: str, what: str, fail: Fail) -> int:
    """How many numbers a variable-length attribute holds (1 to 3 for a size)."""
    n = len(str(element.get(attribute)).split())
    if attribute == "size" and not 1 <= n <= 3:
        raise fail(f"{what} size={shown(str(element.get('size')))} is not 1 to 3 numbers", element)
    return n
