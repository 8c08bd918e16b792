"""Planar serial arms as URDF, like the paper's 4-DOF case study.

The arm moves in the base frame's x-y plane. Joint ``i`` turns about ``-z``, so
a positive angle turns ``+y`` toward ``+x``, and each link points along its own
``+y``. With :math:`\\theta_i = q_1 + \\dots + q_i` the end point is

.. math::

    p = \\sum_i l_i \\, (\\sin \\theta_i, \\cos \\theta_i),

the paper's convention (docs/method.md, "The paper's case study"); a fixed frame
``tip`` sits at the end of the last link. Each link's collision geometry is a
capsule along the link (a segment when its radius is 0), written as a URDF
cylinder that Pinocchio turns into a capsule because the link lists it under
``<collision_checking><capsule name=.../>`` (URDF itself has no capsule).

The shipped ``robots/planar4r.urdf`` is
``write_planar_arm("robots/planar4r.urdf", [0.3] * 4, name="planar4r")``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yourdfpy
from lxml import etree

from clik.errors import InputError

LINK_RADIUS_VISUAL = 0.01
"""Radius of the cylinder drawn for each link [m]."""

_COLORS = ((0.95, 0.55, 0.1, 1.0), (0.2, 0.45, 0.8, 1.0))
_GREY = (0.4, 0.4, 0.4, 1.0)
_RED = (0.85, 0.1, 0.1, 1.0)


def planar_forward_kinematics(lengths: Sequence[float], q: np.ndarray) -> np.ndarray:
    """End point of a planar arm in closed form.

    Args:
        lengths: Link lengths :math:`l_i` [m], n of them.
        q: Joint angles [rad], shape (n,) or (N, n).

    Returns:
        End points (x, y) [m], shape (2,) or (N, 2).
    """
    theta = np.cumsum(np.asarray(q, dtype=float), axis=-1)
    lengths = np.asarray(lengths, dtype=float)
    return np.stack([np.sin(theta) @ lengths, np.cos(theta) @ lengths], axis=-1)


def planar_arm_urdf(
    lengths: Sequence[float],
    lower: Sequence[float] | None = None,
    upper: Sequence[float] | None = None,
    name: str = "planar_arm",
    capsule_radius: float = 0.0,
) -> str:
    """URDF text of a planar arm.

    Links are ``base``, ``link1`` ... ``linkN`` and ``tip``; joints are
    ``joint1`` ... ``jointN`` (revolute) and ``tip_joint`` (fixed).

    Args:
        lengths: Link lengths [m], all positive.
        lower: Lower joint limits [rad]; default ``-2 pi`` for joint 1 and
            ``-pi`` for the others.
        upper: Upper joint limits [rad]; default ``2 pi`` for joint 1 and ``pi``
            for the others.
        name: The robot's name.
        capsule_radius: Radius of the collision capsules [m] (0: segments).

    Returns:
        The URDF document (UTF-8 XML text).

    Raises:
        InputError: Bad lengths, limits or radius.
    """
    lengths = _checked("lengths", lengths, None)
    n = len(lengths)
    if np.any(lengths <= 0):
        raise InputError("lengths", "positive link lengths [m]", got=lengths.tolist())
    wide = np.full(n, math.pi)
    wide[0] = 2 * math.pi
    lower = -wide if lower is None else _checked("lower", lower, n)
    upper = wide if upper is None else _checked("upper", upper, n)
    if np.any(lower > upper):
        raise InputError("lower", "limits below the upper limits", got=lower.tolist())
    if not (math.isfinite(capsule_radius) and capsule_radius >= 0):
        raise InputError("capsule_radius", "a finite radius >= 0 [m]", got=capsule_radius)

    links = [_link("base", [_visual("base", yourdfpy.Cylinder(0.03, 0.02), _GREY)])]
    joints = []
    for i, length in enumerate(lengths, start=1):
        along = _along_y(length)
        visuals = [
            _visual(f"link{i}_joint", yourdfpy.Sphere(2 * LINK_RADIUS_VISUAL), _GREY),
            _visual(
                f"link{i}", yourdfpy.Cylinder(LINK_RADIUS_VISUAL, length), _COLORS[i % 2], along
            ),
        ]
        capsule = yourdfpy.Collision(
            f"link{i}_capsule",
            along,
            yourdfpy.Geometry(cylinder=yourdfpy.Cylinder(capsule_radius, length)),
        )
        links.append(_link(f"link{i}", visuals, [capsule]))
        joints.append(
            yourdfpy.Joint(
                f"joint{i}",
                type="revolute",
                parent="base" if i == 1 else f"link{i - 1}",
                child=f"link{i}",
                origin=_translation(0.0 if i == 1 else lengths[i - 2]),
                axis=np.array([0.0, 0.0, -1.0]),
                limit=yourdfpy.Limit(
                    effort=10.0, velocity=3.0, lower=lower[i - 1], upper=upper[i - 1]
                ),
            )
        )
    links.append(_link("tip", [_visual("tip", yourdfpy.Sphere(1.5 * LINK_RADIUS_VISUAL), _RED)]))
    joints.append(
        yourdfpy.Joint(
            "tip_joint",
            type="fixed",
            parent=f"link{n}",
            child="tip",
            origin=_translation(lengths[-1]),
        )
    )

    urdf = yourdfpy.URDF(
        yourdfpy.Robot(name, links=links, joints=joints), build_scene_graph=False, load_meshes=False
    )
    if not urdf.validate():
        raise InputError("planar arm", "a valid URDF", got=[str(e) for e in urdf.errors])
    root = urdf.write_xml().getroot()
    root.insert(0, etree.Comment(f" generated by clik.planar_arm: lengths {lengths.tolist()} [m] "))
    for element in root.iterfind("link"):  # mark each link's cylinder as a capsule
        if element.find("collision") is not None:
            checking = etree.SubElement(element, "collision_checking")
            etree.SubElement(checking, "capsule", name=element.find("collision").get("name"))
    return etree.tostring(root, pretty_print=True, xml_declaration=True, encoding="UTF-8").decode()


def write_planar_arm(path: str | Path, lengths: Sequence[float], **options: object) -> Path:
    """Write :func:`planar_arm_urdf` to a file.

    Args:
        path: The URDF file to write.
        lengths: Link lengths [m].
        **options: ``lower``, ``upper``, ``name``, ``capsule_radius`` as in
            :func:`planar_arm_urdf`.

    Returns:
        The path written.
    """
    path = Path(path)
    path.write_text(planar_arm_urdf(lengths, **options), encoding="utf-8")
    return path


def _checked(field: str, values: Sequence[float], size: int | None) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        array = np.array([np.nan])
    expected = f"{size or 'one or more'} finite numbers"
    if array.ndim != 1 or not array.size or (size and array.size != size):
        raise InputError(field, expected, got=values)
    if not np.all(np.isfinite(array)):
        raise InputError(field, expected, got=array.tolist())
    return array


def _translation(y: float) -> np.ndarray:
    transform = np.eye(4)
    transform[1, 3] = y
    return transform


def _along_y(length: float) -> np.ndarray:
    """Placement of a cylinder (axis z) spanning the segment from 0 to ``length`` on +y."""
    transform = _translation(length / 2)
    transform[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]  # Rx(-pi/2)
    return transform


def _visual(
    name: str, shape: object, rgba: Sequence[float], origin: np.ndarray | None = None
) -> yourdfpy.Visual:
    kind = type(shape).__name__.lower()
    material = yourdfpy.Material(f"{name}_color", yourdfpy.Color(np.array(rgba)))
    return yourdfpy.Visual(name, origin, yourdfpy.Geometry(**{kind: shape}), material)


def _link(name: str, visuals: list, collisions: list | None = None) -> yourdfpy.Link:
    return yourdfpy.Link(name, visuals=visuals, collisions=collisions or [])
