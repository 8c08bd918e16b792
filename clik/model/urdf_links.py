"""A URDF's links: inertials, primitive shapes, and mesh files that stay inside their folder.

Masses are never negative, nor are the sizes of boxes, cylinders and spheres (a
zero radius is allowed: planar arms use segments); mesh scales lie in
:data:`~clik.model.mesh_check.SCALE_RANGE`. A mesh file must pass
:func:`~clik.model.mesh_check.check_mesh_file`: ``package://pkg/rest`` is looked
up as ``<dir>/pkg/rest`` for each ``dir`` of the package folders and must not
leave the ``pkg`` folder (symlinks and OBJ ``mtllib`` files included); a
relative filename is relative to the URDF's folder (a symlink must not lead out
of the folder its path names).
"""

from __future__ import annotations

import os
import posixpath
from collections.abc import Sequence
from pathlib import Path

from lxml import etree

from clik.errors import shown_path
from clik.model.mesh_check import (
    MeshRefused,
    check_mesh_file,
    check_scale,
    regular_file_problem,
)
from clik.model.urdf_numbers import Fail, check_origin, read_numbers, shown

_SHAPES = {"box": {"size": 3}, "cylinder": {"radius": 1, "length": 1}, "sphere": {"radius": 1}}
"""Primitive shapes and their size attributes (finite, >= 0; a radius 0 is a segment)."""


def check_link(
    name: str, link: etree._Element, urdf: Path, package_dirs: Sequence[str | Path], fail: Fail
) -> None:
    """Check a link's inertial, its visual and collision origins, shapes and mesh files."""
    what = f"link {shown(name)}"
    inertial = link.find("inertial")
    if inertial is not None:
        check_origin(inertial, f"{what} inertial", fail)
        mass = inertial.find("mass")
        if mass is not None:
            read_numbers(mass, "value", 1, f"{what} mass", fail, "mass", nonnegative=True)
        inertia = inertial.find("inertia")
        for attribute in () if inertia is None else inertia.attrib:
            read_numbers(inertia, attribute, 1, f"{what} inertia", fail, "mass")
    for kind in ("visual", "collision"):
        for element in link.findall(kind):
            check_origin(element, f"{what} {kind}", fail)
            for shape in element.iterfind("geometry/*"):
                for attribute, count in _SHAPES.get(shape.tag, {}).items():
                    read_numbers(
                        shape,
                        attribute,
                        count,
                        f"{what} {kind} {shape.tag}",
                        fail,
                        "position",
                        True,
                    )
                if shape.tag == "mesh":
                    _check_mesh(shape, f"{what} {kind} mesh", urdf, package_dirs, fail)


def _check_mesh(
    mesh: etree._Element,
    what: str,
    urdf: Path,
    package_dirs: Sequence[str | Path],
    fail: Fail,
) -> None:
    """A mesh file must pass the cheap mesh checks and stay inside its folder."""
    scale = [1.0, 1.0, 1.0]
    if mesh.get("scale") is not None:
        scale = read_numbers(mesh, "scale", 3, what, fail, "scale")  # range: check_scale
    filename = mesh.get("filename")
    if not filename:
        raise fail("a <mesh> has no filename", mesh)
    file, root = _mesh_location(filename, mesh, urdf, package_dirs, fail)
    try:
        check_scale(scale, what)
        facts = check_mesh_file(file, scale, root, what=f"{what} {shown_path(filename)}: file")
        for side in facts.side_files:  # an OBJ's material files: inside the folder too
            _check_side_file(facts.path.parent / side, root)
    except MeshRefused as refused:
        raise fail(str(refused), mesh) from None


def _check_side_file(side: Path, root: Path) -> None:
    """An OBJ ``mtllib`` file must stay inside ``root`` and, if it exists, be a regular file."""
    if not side.resolve().is_relative_to(root.resolve()):
        raise MeshRefused(f"its material file (mtllib) {side} leaves the folder {root}")
    if os.path.lexists(side):
        problem = regular_file_problem(side)
        if problem is not None:
            raise MeshRefused(f"its material file (mtllib) {side} {problem}")


def _mesh_location(
    filename: str,
    mesh: etree._Element,
    urdf: Path,
    package_dirs: Sequence[str | Path],
    fail: Fail,
) -> tuple[Path, Path]:
    """The mesh file a ``filename`` names and the folder it must stay inside."""
    if filename.startswith("package://"):
        # "package:///pkg/..." (extra slash) is read as "package://pkg/..." like Pinocchio does
        package, _, rest = filename.removeprefix("package://").lstrip("/").partition("/")
        inside = posixpath.normpath(rest or ".")
        if not package or package in (".", "..") or inside.startswith(("..", "/")):
            raise fail(f"mesh {shown_path(filename)} leaves its package folder", mesh)
        for folder in package_dirs:  # the first folder holding it, as Pinocchio looks
            candidate = Path(folder) / package / inside
            if os.path.lexists(candidate):
                return candidate, Path(folder) / package
        searched = ", ".join(map(str, package_dirs)) or "none given"
        raise fail(
            f"mesh file {shown_path(filename)} not found (package folders: {searched})", mesh
        )
    if "://" in filename and not filename.startswith("file://"):
        raise fail(f"mesh {shown_path(filename)} uses an unsupported URI scheme", mesh)
    file = urdf.parent / filename.removeprefix("file://")
    if not os.path.lexists(file):
        raise fail(f"mesh file {shown_path(filename)} not found (looked for {file})", mesh)
    return file, Path(os.path.normpath(file.absolute().parent))
