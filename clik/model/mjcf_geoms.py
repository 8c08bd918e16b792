"""An MJCF geom's shape as Pinocchio reads it: its type and sizes, through default classes.

Pinocchio's MJCF reader takes a geom's attributes from the top-level ``<default>``,
then its body's ``childclass``, then its own ``class`` (each class holding its
parents' attributes), then the geom itself; it reads as many size numbers as the
shape needs (a sphere 1, a capsule or cylinder 2, a box or ellipsoid 3, one fewer
with ``fromto``) and takes whatever memory holds for the ones missing. MuJoCo
refuses such a geom ("size 1 must be positive"); :func:`check_geom_sizes` refuses it
before Pinocchio reads it, and sizes that are not positive.
"""

from __future__ import annotations

from lxml import etree

from clik.model.urdf_numbers import Fail, shown

NEEDED_SIZES = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
"""Size numbers each primitive shape needs without ``fromto`` (radii, half-lengths [m])."""

WITH_FROMTO = {"capsule": 1, "cylinder": 1, "box": 1, "ellipsoid": 1}
"""Size numbers needed with ``fromto`` (which gives the length)."""


def check_geom_sizes(root: etree._Element, fail: Fail) -> None:
    """Every primitive geom of the world gets the sizes its shape needs, all positive.

    Args:
        root: The merged ``<mujoco>`` element (one top-level ``<default>``).
        fail: Builds the error for a problem and an element.

    Raises:
        RobotLoadError: Through ``fail``, naming the geom and what it lacks.
    """
    classes = {d.get("class"): d for d in root.iter("default") if d.get("class")}
    top = root.find("default")
    world = root.find("worldbody")
    for geom in [] if world is None else world.iter("geom"):
        chain = _chain(geom, classes, top)
        shape = _attribute(geom, "type", chain) or "sphere"
        if shape not in NEEDED_SIZES:
            continue  # a mesh (its file gives the shape), a plane (dropped)
        fromto = _attribute(geom, "fromto", chain) is not None
        needed = WITH_FROMTO[shape] if fromto else NEEDED_SIZES[shape]
        written = _attribute(geom, "size", chain) or ""
        try:
            sizes = [float(v) for v in written.split()]
        except ValueError:
            sizes = []  # a bad number on the geom itself was refused before
        name = f"geom {shown(geom.get('name', ''))}" if geom.get("name") else "a geom"
        if len(sizes) < needed:
            raise fail(
                f"{name} of type {shape!r} has size={written!r} (its own or its default "
                f"class's): {needed} number(s) needed{' with fromto' if fromto else ''}",
                geom,
            )
        if not all(s > 0.0 for s in sizes[:needed]):
            raise fail(f"{name} of type {shape!r} has size={written!r}: not positive", geom)


def _chain(
    geom: etree._Element, classes: dict[str | None, etree._Element], top: etree._Element | None
) -> list[etree._Element]:
    """The ``<default>`` elements a geom's attributes come from, the first one winning."""
    names = [geom.get("class")]
    for body in geom.iterancestors("body"):
        if body.get("childclass"):
            names.append(body.get("childclass"))
            break
    chain: list[etree._Element] = []
    for name in names:
        default = classes.get(name)
        while default is not None and default.tag == "default":
            chain.append(default)
            default = default.getparent()
    if top is not None:
        chain.append(top)
    return chain


def _attribute(geom: etree._Element, name: str, chain: list[etree._Element]) -> str | None:
    """The value Pinocchio gives a geom attribute: its own, else its defaults'."""
    if geom.get(name) is not None:
        return geom.get(name)
    for default in chain:
        value = next((g.get(name) for g in default.findall("geom") if g.get(name)), None)
        if value is not None:
            return value
    return None
