"""A URDF's links: inertials, primitive shapes, and mesh files that stay inside their folder.

Masses are never negative, nor are the sizes of boxes, cylinders and spheres (a
zero radius is allowed: planar arms use segments); mesh scales lie in
:data:`~clik.model.mesh_check.SCALE_RANGE`. A mesh file must pass
:func:`~clik.model.mesh_check.check_mesh_file`: ``package://pkg/rest`` is
``rest`` in the folder of the package ``pkg`` and must not leave that folder
(symlinks and OBJ ``mtllib`` files included). The package is found by a
:class:`PackageFinder` when the package folders are one
(:class:`~clik.model.packages.PackageDirs`, what ``Robot.load`` passes: by its
``package.xml`` name under the folders, searched recursively), else as
``<dir>/pkg/rest`` for each ``dir`` of a plain list of folders; a
relative filename is relative to the URDF's folder (a symlink must not lead out
of the folder its path names). Visual meshes are optional: one that is missing (or
unreadable, or a Git LFS pointer) is left out with a warning
(:mod:`clik.model.visual_meshes`); one that is there is checked like any other.
"""

from __future__ import annotations

import os
import posixpath
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol, runtime_checkable

from lxml import etree

from clik.errors import RobotLoadError, shown_path
from clik.model.mesh_check import (
    MeshRefused,
    check_mesh_file,
    check_scale,
    regular_file_problem,
)
from clik.model.urdf_numbers import Fail, check_origin, read_numbers, shown
from clik.model.visual_meshes import lfs_pointer_problem, missing_problem, skip_visual


@runtime_checkable
class PackageFinder(Protocol):
    """Package folders that find a package by name (:class:`clik.model.packages.PackageDirs`)."""

    def package_folder(self, name: str) -> Path | None:
        """The folder of the package ``name`` (symlinks resolved), or None."""

    def searched(self) -> str:
        """The folders searched, in words (for messages)."""


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
                    missing = _check_mesh(
                        shape, f"{what} {kind} mesh", urdf, package_dirs, fail, kind == "visual"
                    )
                    if missing is not None:  # a visual mesh is optional: left out, warned
                        skip_visual(element, name, str(shape.get("filename")), missing)


def _check_mesh(
    mesh: etree._Element,
    what: str,
    urdf: Path,
    package_dirs: Sequence[str | Path],
    fail: Fail,
    optional: bool = False,
) -> str | None:
    """A mesh file must pass the cheap mesh checks and stay inside its folder.

    Returns:
        None, or for an ``optional`` (visual) mesh that is missing, cannot be read or
        is a Git LFS pointer (:mod:`clik.model.visual_meshes`), the problem in words
        (a required mesh raises it).
    """
    scale = [1.0, 1.0, 1.0]
    if mesh.get("scale") is not None:
        scale = read_numbers(mesh, "scale", 3, what, fail, "scale")  # range: check_scale
    filename = mesh.get("filename")
    if not filename:
        raise fail("a <mesh> has no filename", mesh)
    try:
        file, root = _mesh_location(filename, mesh, urdf, package_dirs, fail)
    except _NotFound as not_found:
        if optional:
            return str(not_found)
        raise fail(f"mesh file {shown_path(filename)} {not_found}", mesh) from None
    missing = missing_problem(file) if optional else None
    if missing is not None:
        return missing
    try:
        check_scale(scale, what)
        facts = check_mesh_file(file, scale, root, what=f"{what} {shown_path(filename)}: file")
        for side in facts.side_files:  # an OBJ's material files: inside the folder too
            _check_side_file(facts.path.parent / side, root)
        unusable = lfs_pointer_problem(facts.path)
    except MeshRefused as refused:
        raise fail(str(refused), mesh) from None
    except OSError as error:  # e.g. no permission to read it
        unusable = f"cannot be read ({file}: {error.strerror})"
    if unusable is not None and not optional:
        raise fail(f"{what} {shown_path(filename)} {unusable}", mesh)
    return unusable


class _NotFound(Exception):
    """A mesh file is not where its filename points; the message says where it was looked for."""


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
        if isinstance(package_dirs, PackageFinder):  # Robot.load's: workspaces searched
            found = package_dirs.package_folder(package)
            if found is None:
                raise _NotFound(f"not found (package folders: {package_dirs.searched()})")
            if not os.path.lexists(found / inside):
                raise _NotFound(f"not found (package {package!r} is the folder {found})")
            return found / inside, found
        for folder in package_dirs:  # the first folder holding it, as Pinocchio looks
            candidate = Path(folder) / package / inside
            if os.path.lexists(candidate):
                return candidate, Path(folder) / package
        searched = ", ".join(map(str, package_dirs)) or "none given"
        raise _NotFound(f"not found (package folders: {searched})")
    if "://" in filename and not filename.startswith("file://"):
        raise fail(f"mesh {shown_path(filename)} uses an unsupported URI scheme", mesh)
    file = urdf.parent / filename.removeprefix("file://")
    if not os.path.lexists(file):
        raise _NotFound(f"not found (looked for {file})")
    return file, Path(os.path.normpath(file.absolute().parent))


def checked_mesh_file(filename: str, urdf: Path, package_dirs: Sequence[str | Path]) -> Path | None:
    """The file a ``<mesh filename>`` names, as :func:`check_link` found it, or None.

    Symlinks resolved: the file the checks read. None when the filename names no file
    (a missing visual mesh) or is refused (which :func:`check_link` has said).
    """

    def fail(problem: str, element: object = None) -> RobotLoadError:
        return RobotLoadError(urdf, problem)

    try:
        file, _ = _mesh_location(filename, etree.Element("mesh"), urdf, package_dirs, fail)
    except (RobotLoadError, _NotFound):
        return None
    return file.resolve()
