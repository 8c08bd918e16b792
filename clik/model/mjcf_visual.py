"""Missing visual-only meshes of an MJCF model: left out with a warning, as for a URDF.

A ``<mesh>`` asset whose file is not found is refused when a collision geom (one that
can touch, ``contype`` or ``conaffinity`` not zero through its default classes, or of
``group`` 3) uses it: the
collision rows would protect a shape clik does not have. When every geom using it is
visual only (both zero), those geoms and the asset leave the document and
:class:`~clik.model.visual_meshes.MissingVisualMeshWarning` names the body, the file
and the problem: the robot loads and runs; its view lacks those geoms.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from lxml import etree

from clik.errors import user_stacklevel
from clik.model.mjcf_geoms import geom_attribute, geom_chain
from clik.model.urdf_numbers import Fail
from clik.model.visual_meshes import MissingVisualMeshWarning


def drop_visual_meshes(
    root: etree._Element, missing: list[tuple[etree._Element, str, str]], fail: Fail
) -> None:
    """Leave out the visual geoms of each missing mesh (warned); refuse a collision one.

    Args:
        root: The merged ``<mujoco>`` element.
        missing: ``(mesh element, file as written, problem)`` for each mesh not found.
        fail: Builds the error naming an element's file and line.

    Raises:
        RobotLoadError: A missing mesh is used by a geom that can touch, or by a
            default class.

    Warns:
        MissingVisualMeshWarning: For each visual geom left out.
    """
    classes = {d.get("class"): d for d in root.iter("default") if d.get("class")}
    top = root.find("default")
    for mesh, written, problem in missing:
        name = mesh.get("name") or Path(written).stem
        users = [g for g in root.iter("geom") if g.get("mesh") == name]
        if any(g.getparent().tag == "default" for g in users) or not all(
            _visual_only(g, classes, top) for g in users
        ):
            raise fail(f"{problem} (a geom that can touch uses it)", mesh)
        mesh.getparent().remove(mesh)
        for geom in users:
            body = geom.getparent().get("name", "(unnamed)")
            geom.getparent().remove(geom)
            warnings.warn(
                MissingVisualMeshWarning(body, written, _problem(problem), part="body"),
                stacklevel=user_stacklevel(),
            )


def _visual_only(
    geom: etree._Element, classes: dict[str | None, etree._Element], top: etree._Element | None
) -> bool:
    """Both ``contype`` and ``conaffinity`` zero (MuJoCo's default is 1), not group 3.

    Group 3 is collision geometry (:func:`clik.model.mjcf_geometry.is_collision`).
    """
    chain = geom_chain(geom, classes, top)
    if (geom_attribute(geom, "group", chain) or "0").strip() == "3":
        return False
    return all(
        (geom_attribute(geom, attribute, chain) or "1").strip() == "0"
        for attribute in ("contype", "conaffinity")
    )


def _problem(located: str) -> str:
    """``"not found (<path>)"`` from the checker's ``"mesh file ... (<path>) not found"``."""
    start = located.rfind("(")
    return f"not found (looked for {located[start + 1 : located.rfind(')')]})"
