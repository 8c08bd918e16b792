"""The robot descriptions in a ROS workspace: what ``clik robots --path WS`` lists.

:func:`robot_descriptions` finds the packages under a folder as
:class:`~clik.model.packages.PackageDirs` does (by their ``package.xml``, skipping
ignored, hidden and symlinked folders, within the same budgets), then, inside each
package (not in the packages nested in it), the files named ``*.urdf`` or
``*.xacro`` whose root element is ``<robot>``, read strictly
(:func:`~clik.model.urdf_check.parse_xml`). A xacro file of macros only (a
``<robot>`` root with neither a ``name`` nor a ``<link>``, included by the
descriptions) is left out. A file that cannot be read strictly is listed among
the files skipped, with the reason.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from lxml import etree

from clik.errors import InputError, RobotLoadError
from clik.model.packages import MANIFEST, MAX_FOLDERS_VISITED, PackageDirs, is_skipped
from clik.model.urdf_check import parse_xml

SRDF_TAGS = frozenset(
    {"group", "group_state", "disable_collisions", "virtual_joint", "end_effector"}
)
"""Elements of an SRDF (its root is ``<robot>`` too): a file holding one is not listed."""

_XACRO_KEYWORDS = frozenset(
    {
        "macro",
        "property",
        "arg",
        "include",
        "if",
        "unless",
        "insert_block",
        "element",
        "attribute",
        "call",
    }
)
"""Xacro's own elements (anything else in its namespace calls a macro)."""

DESCRIPTION_SUFFIXES = (".urdf", ".xacro")
"""Names of the files examined (``arm.urdf``, ``arm.urdf.xacro``, ``arm.xacro``)."""


@dataclass(frozen=True)
class Description:
    """A robot description file in a package.

    Attributes:
        package: The package's name.
        path: The file.
        robot: The ``<robot name>`` as written (a xacro file may write ``$(arg name)``).
    """

    package: str
    path: Path
    robot: str


@dataclass(frozen=True)
class Skipped:
    """A file that looks like a description but cannot be read strictly.

    Attributes:
        path: The file.
        problem: Why, in words.
    """

    path: Path
    problem: str


def robot_descriptions(folder: str | Path) -> tuple[list[Description], list[Skipped]]:
    """The robot descriptions in the packages under ``folder``, sorted by package and path.

    Raises:
        InputError: ``folder`` is not a folder, or the search goes past its budgets
            (:data:`~clik.model.packages.MAX_PACKAGE_DEPTH`,
            :data:`~clik.model.packages.MAX_FOLDERS_VISITED`).
        RobotLoadError: A ``package.xml`` is not strict XML or has no name.
    """
    top = Path(folder)
    if not top.is_dir():
        raise InputError("--path", "a folder holding ROS packages (a workspace's src)", str(top))
    found: list[Description] = []
    skipped: list[Skipped] = []
    for package in sorted(PackageDirs([top]).packages(), key=lambda p: (p.name, p.folder)):
        for path in _package_files(package.folder):
            try:
                root = parse_xml(path).getroot()
            except RobotLoadError as error:
                skipped.append(Skipped(path, error.problem))
                continue
            if root.tag == "robot" and is_description(path, root):
                found.append(Description(package.name, path, root.get("name") or ""))
    return found, skipped


def is_description(path: Path, root: etree._Element) -> bool:
    """Whether the ``<robot>`` file ``path`` describes a robot (not macros, not an SRDF).

    Outside ``<xacro:macro>`` definitions it must hold a ``<link>`` or call a macro, and
    hold no SRDF element (:data:`SRDF_TAGS`); a name ending ``.srdf`` or ``.srdf.xacro``
    is an SRDF.
    """
    if path.name.endswith((".srdf", ".srdf.xacro")):
        return False
    links = calls = False
    for element in _outside_macros(root):
        tag = element.tag
        if not isinstance(tag, str):
            continue  # a comment
        if tag in SRDF_TAGS:
            return False
        links = links or tag == "link"
        calls = calls or (_is_xacro(tag) and etree.QName(tag).localname not in _XACRO_KEYWORDS)
    return links or calls


def _is_xacro(tag: str) -> bool:
    """Whether ``tag`` is in a xacro namespace (any URI ending in ``xacro``).

    ``http://www.ros.org/wiki/xacro`` and ``http://wiki.ros.org/xacro`` are both in use.
    """
    namespace = etree.QName(tag).namespace
    return namespace is not None and namespace.rstrip("/#").endswith("xacro")


def _outside_macros(root: etree._Element) -> list[etree._Element]:
    """The elements below ``root`` that are not inside a ``<xacro:macro>``."""
    found: list[etree._Element] = []
    todo = list(root)
    while todo:
        element = todo.pop()
        tag = element.tag
        if not (isinstance(tag, str) and _is_xacro(tag) and etree.QName(tag).localname == "macro"):
            found.append(element)
            todo.extend(element)
    return found


def _package_files(package: Path) -> list[Path]:
    """The description files in ``package``: not in hidden, ignored or nested packages.

    Raises:
        InputError: More than :data:`~clik.model.packages.MAX_FOLDERS_VISITED` folders.
    """
    files: list[Path] = []
    todo = [package]
    visited = 0
    while todo:
        folder = todo.pop()
        visited += 1
        if visited > MAX_FOLDERS_VISITED:
            raise InputError(
                "--path",
                f"packages of at most {MAX_FOLDERS_VISITED} folders (MAX_FOLDERS_VISITED); "
                f"{package} holds more",
            )
        try:
            with os.scandir(folder) as scan:
                entries = sorted(scan, key=lambda e: e.name)
        except OSError:
            continue
        for entry in entries:
            path = Path(entry.path)
            if entry.is_dir(follow_symlinks=False):
                if not is_skipped(path) and not (path / MANIFEST).is_file():
                    todo.append(path)
            elif entry.is_file(follow_symlinks=False) and entry.name.endswith(DESCRIPTION_SUFFIXES):
                files.append(path)
    return sorted(files)
