"""Visual meshes are optional: collision geometry is what clik's runs use.

A URDF's ``<visual>`` meshes only draw the robot; distances, constraint rows and
every run use its ``<collision>`` geometry. So a visual mesh that is missing (not
found, a broken symbolic link, a file that cannot be read, or a Git LFS pointer
left where the mesh should be) does not stop a robot from loading:
:func:`skip_visual` warns with :class:`MissingVisualMeshWarning` (naming the link
and the mesh path) and marks its ``<visual>`` element in the checked tree;
:func:`missing_visuals` lists the marked elements, and :func:`without_visuals`
removes them from the URDF text before Pinocchio reads the visual geometry (it
would throw on them). A visual mesh that exists is checked as strictly as a
collision mesh (format, size, a folder it must stay inside), and collision meshes
stay required.

Reading the visual model is slow (DAE meshes: about 0.5 s for the Panda); it is
read only when something draws it (:attr:`clik.model.robot.Robot.visual_model`).
:func:`visual_links` gives, from the checked tree, the links that have visual
geometry, so that nothing else needs the visual model.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

from lxml import etree

from clik.errors import ClikWarning, shown_path, user_stacklevel
from clik.model.urdf_numbers import shown

MISSING_MARK = "{urn:clik:visual-meshes}missing"
"""Attribute :func:`skip_visual` sets on a ``<visual>`` element whose mesh is missing."""

LFS_POINTER = b"version https://git-lfs.github.com/spec/"
"""How a Git LFS pointer file (the mesh itself not fetched: ``git lfs pull``) starts."""

_LFS_POINTER_BYTES = 1024
"""Largest Git LFS pointer file [bytes] (they are about 130 bytes)."""


class MissingVisualMeshWarning(ClikWarning):
    """A visual mesh is missing: it is left out of the visual model.

    A URDF link is then drawn with its collision geometry; an MJCF body
    (``part="body"``) without that geom.

    Attributes:
        link: The link's (or the MJCF body's) name.
        filename: The mesh's ``filename`` as the URDF writes it.
        problem: What is wrong with it, in words (e.g. "not found (looked for ...)").
    """

    def __init__(self, link: str, filename: str, problem: str, part: str = "link") -> None:
        drawn = (
            "the link is drawn with its collision geometry"
            if part == "link"
            else "the body is drawn without that geom"
        )
        super().__init__(
            f"{part} {shown(link)}: visual mesh {shown_path(filename)} {problem}; it is left "
            f"out of the visual model and {drawn} "
            "(visual meshes are optional: runs use collision geometry only)"
        )
        self.link = link
        self.filename = filename
        self.problem = problem


@dataclass(frozen=True)
class MissingVisual:
    """A ``<visual>`` element left out because its mesh is missing.

    Attributes:
        link: The link's name.
        index: Position of the element among the link's ``<visual>`` elements (from 0).
        filename: The mesh's ``filename`` as the URDF writes it.
    """

    link: str
    index: int
    filename: str


def missing_problem(file: Path) -> str | None:
    """Why a mesh path that is there (``os.path.lexists``) names no file, or None.

    A broken symbolic link, or a path that cannot be examined (``os.stat`` only).
    Anything else (a folder, a FIFO, a file of the wrong format) is left to the mesh
    checks, which refuse it.
    """
    try:
        os.stat(file)
    except FileNotFoundError:
        return f"not found ({file} is a broken symbolic link)"
    except OSError as error:
        return f"cannot be examined ({file}: {error.strerror})"
    return None


def lfs_pointer_problem(file: Path) -> str | None:
    """Why the checked mesh ``file`` is no mesh when it is a Git LFS pointer, else None.

    A repository cloned without ``git lfs`` holds, in place of each mesh, a text
    file of about 130 bytes starting with :data:`LFS_POINTER`. Only a small regular
    file is opened (call it once the mesh checks passed: it stays inside its folder).
    """
    if not os.path.isfile(file) or os.stat(file).st_size > _LFS_POINTER_BYTES:
        return None
    with open(file, "rb") as handle:
        head = handle.read(len(LFS_POINTER))
    if head != LFS_POINTER:
        return None
    return f"is a Git LFS pointer, not the mesh ({file}; fetch the meshes with 'git lfs pull')"


def skip_visual(visual: etree._Element, link: str, filename: str, problem: str) -> None:
    """Leave a ``<visual>`` element out (marked in the checked tree) and warn.

    Warns:
        MissingVisualMeshWarning: Always, naming the link, the mesh and the problem
            (at the first caller outside clik, e.g. the line calling ``Robot.load``).
    """
    visual.set(MISSING_MARK, filename)
    warnings.warn(MissingVisualMeshWarning(link, filename, problem), stacklevel=user_stacklevel())


def missing_visuals(root: etree._Element) -> tuple[MissingVisual, ...]:
    """The ``<visual>`` elements :func:`skip_visual` marked in the checked tree ``root``."""
    missing = []
    for link in root.iterfind("link"):
        for index, visual in enumerate(link.iterfind("visual")):
            filename = visual.get(MISSING_MARK)
            if filename is not None:
                missing.append(MissingVisual(str(link.get("name")), index, filename))
    return tuple(missing)


def visual_links(root: etree._Element) -> frozenset[str]:
    """Names of the links with at least one ``<visual>`` element (missing meshes included)."""
    return frozenset(str(link.get("name")) for link in root.iterfind("link[visual]"))
