"""An SRDF's ``<robot>`` element, expanded by xacro first when the file holds xacro markup.

MoveIt configurations often write their SRDF as xacro (``xarm.srdf.xacro``,
``panda_arm_hand.srdf.xacro``): link names built from a ``prefix`` argument
(``${prefix}link1``), pairs written by macros, files included with
``$(find pkg)``. Read raw, such a file names links no robot has. An SRDF is
expanded when its name ends with ``.xacro`` or, read strictly first
(:func:`clik.model.urdf_check.parse_xml`), it holds xacro markup
(:func:`has_xacro_markup`): a xacro namespace, an element in it, or a
``${...}`` / ``$(...)`` substitution in an attribute or a text.

The expansion is the URDF's (:func:`clik.model.xacro_expand.expand_xacro`):
the same arguments (``xacro_args``), the same package lookup for ``$(find)``
and the same folders a file may read, the same errors, which name the SRDF
file. The expanded text is then read as strictly as the file.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

from lxml import etree

from clik.errors import RobotLoadError, shown
from clik.model.urdf_check import parse_xml
from clik.model.xacro_expand import expand_xacro, is_xacro

XACRO_NAMESPACE_WORD = "xacro"
"""Xacro's namespaces (``http://www.ros.org/wiki/xacro``, ``http://wiki.ros.org/xacro``,
...) all hold this word."""

SUBSTITUTIONS = ("${", "$(")
"""Xacro's substitutions: a property expression ``${...}``, ``$(arg ...)``, ``$(find ...)``."""


def has_xacro_markup(root: etree._Element) -> bool:
    """Whether the document under ``root`` holds xacro markup.

    A xacro namespace declared or used, or a substitution (:data:`SUBSTITUTIONS`)
    in an attribute value or an element's text; comments are not read.
    """
    if any(XACRO_NAMESPACE_WORD in (uri or "") for uri in root.nsmap.values()):
        return True
    for element in root.iter(tag=etree.Element):
        if XACRO_NAMESPACE_WORD in (etree.QName(element).namespace or ""):
            return True
        texts = [element.text or "", *element.attrib.values()]
        if any(mark in text for text in texts for mark in SUBSTITUTIONS):
            return True
    return False


def srdf_root(
    path: Path,
    xacro_args: Mapping[str, str] | None = None,
    package_dirs: Sequence[str | Path] = (),
    extra_args: bool = False,
) -> tuple[etree._Element, bool]:
    """The SRDF's ``<robot>`` element, and whether xacro expanded the file.

    Args:
        path: The SRDF file (``.srdf`` or ``.srdf.xacro``).
        xacro_args: Arguments of its xacro markup (the URDF's ``xacro_args``).
        package_dirs: Folders holding the packages its ``$(find pkg)`` name.
        extra_args: Whether ``xacro_args`` may hold arguments the SRDF does not
            use (they were given for, and checked against, the URDF).

    Raises:
        RobotLoadError: The file is missing or not strict XML, xacro cannot expand
            it (names the file), or its root (expanded) is not ``<robot>``.
        InputError: ``xacro_args`` or ``package_dirs`` do not fit its xacro markup
            (see :func:`~clik.model.xacro_expand.expand_xacro`).
    """
    root = parse_xml(path).getroot()
    expanded = is_xacro(path) or has_xacro_markup(root)
    if expanded:
        text = expand_xacro(path, xacro_args, package_dirs, extra_args=extra_args)
        root = parse_xml(path, text.encode("utf-8")).getroot()
    if root.tag != "robot":
        raise RobotLoadError(
            path, f"expected an SRDF, whose root element is <robot>, got <{shown(root.tag)}>"
        )
    return root, expanded


@contextlib.contextmanager
def expansion_lines(path: Path, expanded: bool) -> Iterator[None]:
    """Errors reading an expanded SRDF give their line in the expansion, not in the file."""
    try:
        yield
    except RobotLoadError as error:
        if not expanded or error.line is None:
            raise
        problem = f"{error.problem} (line {error.line} of its xacro expansion)"
        raise RobotLoadError(path, problem) from None
