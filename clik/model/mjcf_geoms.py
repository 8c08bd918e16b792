"""An MJCF geom's attributes through default classes; its sizes checked.

A geom takes each attribute from itself, else from its class (its own ``class``, else
the nearest enclosing body's ``childclass``, else the top-level ``<default>``), each
class holding its parents' attributes, as MuJoCo reads them. A primitive shape needs
as many size numbers as its shape (a sphere 1, a capsule or cylinder 2, a box or
ellipsoid 3, one fewer with ``fromto``): :func:`check_geom_sizes` refuses a geom
without them, or with sizes that are not positive, naming the geom and its line
(MuJoCo's compiler would say "size 1 must be positive" without them).
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
        chain = geom_chain(geom, classes, top)
        shape = geom_attribute(geom, "type", chain) or "sphere"
        if shape not in NEEDED_SIZES or geom_attribute(geom, "mesh", chain) is not None:
            continue  # a mesh, a shape MuJoCo fits to a mesh (its file gives it), a plane
        fromto = geom_attribute(geom, "fromto", chain) is not None
        needed = WITH_FROMTO[shape] if fromto else NEEDED_SIZES[shape]
        written = geom_attribute(geom, "size", chain) or ""
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


def geom_chain(
    geom: etree._Element, classes: dict[str | None, etree._Element], top: etree._Element | None
) -> list[etree._Element]:
    """The ``<default>`` elements a geom's attributes come from, the first one winning.

    Its own ``class``, else the nearest enclosing body's ``childclass``; then that
    class's parents; the top-level ``<default>`` last.
    """
    name = geom.get("class")
    if name is None:
        bodies = (b.get("childclass") for b in geom.iterancestors("body"))
        name = next((c for c in bodies if c), None)
    chain: list[etree._Element] = []
    default = classes.get(name)
    while default is not None and default.tag == "default":
        chain.append(default)
        default = default.getparent()
    if top is not None and top not in chain:
        chain.append(top)
    return chain


def geom_attribute(geom: etree._Element, name: str, chain: list[etree._Element]) -> str | None:
    """The value MuJoCo gives a geom attribute: its own, else its defaults'."""
    if geom.get(name) is not None:
        return geom.get(name)
    for default in chain:
        value = next((g.get(name) for g in default.findall("geom") if g.get(name)), None)
        if value is not None:
            return value
    return None
