"""Strict checks on a URDF file before any robotics library reads it.

Pinocchio and yourdfpy are lenient readers: yourdfpy recovers from malformed XML
and accepts a joint whose child link is missing, and neither gives a line number.
:func:`check_urdf` parses the file with a strict XML parser that never reads
another file or the network, refuses a DOCTYPE that declares entities (external
entities, "billion laughs") or points at an external DTD, then checks that the
description is a well-formed kinematic tree whose numbers are finite and whose
mesh files exist. Each problem raises :class:`~clik.errors.RobotLoadError` with
the problem in plain words and, when known, its line.
"""

from __future__ import annotations

import math
import posixpath
import re
from collections.abc import Callable, Sequence
from pathlib import Path

from lxml import etree

from clik.errors import RobotLoadError

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")
"""Joint types that add a degree of freedom to a fixed-base arm."""

JOINT_TYPES = (*MOVABLE_TYPES, "fixed", "floating", "planar")

Fail = Callable[..., RobotLoadError]
"""Builds the error for a problem found at an element: ``fail(problem, element)``."""

_ENTITY = re.compile(rb"<!ENTITY")
_XINCLUDE = "{http://www.w3.org/2001/XInclude}"
_DOCTYPE = re.compile(rb"<!DOCTYPE\s+[^\s\[>]+\s*([^\[>]*)")


def parse_xml(path: str | Path, data: bytes | None = None) -> etree._ElementTree:
    """Parse an XML file strictly, without reading any other file.

    The raw bytes are scanned first: entity declarations and external DTD
    references are refused before the XML parser sees them, so neither an
    external entity (XXE) nor an entity bomb is ever expanded. The parser
    itself never loads a DTD, resolves an entity or touches the network, and
    XInclude elements are refused (nothing downstream would expand them, but
    a URDF that asks for another file is not one to hand on).

    Args:
        path: The XML file.
        data: The document's bytes when they are not read from ``path`` (e.g. a
            URDF expanded from xacro); ``path`` then only names it in errors.

    Returns:
        The parsed document.

    Raises:
        RobotLoadError: The file is missing, empty, not well-formed XML, its
            DOCTYPE declares entities or an external reference, or it holds an
            XInclude element.
    """
    path = Path(path)
    if data is None:
        if not path.is_file():
            problem = "is a folder, not a file" if path.is_dir() else "file not found"
            raise RobotLoadError(path, problem)
        data = path.read_bytes()
    if not data.strip():
        raise RobotLoadError(path, "file is empty")
    entity = _ENTITY.search(data)
    if entity:
        raise RobotLoadError(
            path,
            "the DOCTYPE declares XML entities, which are refused "
            "(they can read other files or expand without bound)",
            line=_line_of(data, entity.start()),
        )
    doctype = _DOCTYPE.search(data)
    if doctype and re.search(rb"\b(SYSTEM|PUBLIC)\b", doctype.group(1)):
        raise RobotLoadError(
            path,
            "the DOCTYPE refers to an external DTD, which is refused",
            line=_line_of(data, doctype.start()),
        )
    parser = etree.XMLParser(
        recover=False, resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False
    )
    try:
        tree = etree.ElementTree(etree.fromstring(data, parser))
    except etree.XMLSyntaxError as error:
        raise RobotLoadError(path, f"malformed XML: {error.msg}", line=error.lineno) from None
    dtd = tree.docinfo.internalDTD  # second line of defence, e.g. for UTF-16 files
    if tree.docinfo.system_url or tree.docinfo.public_id or (dtd and list(dtd.iterentities())):
        raise RobotLoadError(path, "the DOCTYPE declares entities or an external reference")
    for element in tree.iter():
        if isinstance(element.tag, str) and element.tag.startswith(_XINCLUDE):
            raise RobotLoadError(
                path,
                "XInclude elements are refused (they can read other files)",
                line=element.sourceline,
            )
    return tree


def check_urdf(
    path: str | Path, package_dirs: Sequence[str | Path] = (), text: str | None = None
) -> etree._Element:
    """Check that a URDF file describes a valid kinematic tree.

    Checks, in order: strict XML (see :func:`parse_xml`); a ``<robot>`` root;
    named, unique links and joints; known joint types; parent and child links
    that exist; a tree (no cycle, a single root link, each link the child of at
    most one joint); at least one movable joint; finite numbers in origins, axes,
    limits and geometry; ``lower <= upper`` for revolute and prismatic joints;
    no negative effort or velocity limit, mass or primitive size (box, cylinder,
    sphere; a zero radius is allowed: planar arms use segments); mesh files that
    exist, where ``package://pkg/rest`` is looked up as ``<dir>/pkg/rest`` for
    each ``dir`` in ``package_dirs`` and must not leave the ``pkg`` folder, and a
    relative filename is relative to the URDF's folder.

    Args:
        path: The URDF file.
        package_dirs: Folders holding the packages named by ``package://`` URIs.
        text: The URDF itself when it is not the content of ``path``: the
            expansion of the xacro file ``path`` (relative mesh files are still
            relative to its folder; errors name it "as expanded by xacro", with
            lines of the expanded text).

    Returns:
        The ``<robot>`` element.

    Raises:
        RobotLoadError: The first problem found, with its line when known.
    """
    path = Path(path)
    source = path if text is None else Path(f"{path} (as expanded by xacro)")
    root = parse_xml(source, None if text is None else text.encode("utf-8")).getroot()

    def fail(problem: str, element: etree._Element | None = None) -> RobotLoadError:
        line = None if element is None else element.sourceline
        return RobotLoadError(source, problem, line=line)

    if root.tag != "robot":
        raise fail(f"the root element is <{root.tag}>, expected <robot>", root)
    links = _named(root, "link", fail)
    joints = _named(root, "joint", fail)
    if not links:
        raise fail("the robot has no <link>", root)

    parent_of: dict[str, str] = {}  # child link -> parent link
    joint_of: dict[str, str] = {}  # child link -> joint name
    for name, joint in joints.items():
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise fail(
                f"joint {name!r} has type {kind!r}; known types: {', '.join(JOINT_TYPES)}", joint
            )
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = None if element is None else element.get("link")
            if link is None:
                raise fail(f"joint {name!r} has no <{end} link=...>", joint)
            if link not in links:
                raise fail(f"joint {name!r} names {end} link {link!r} that does not exist", element)
            ends[end] = link
        child = ends["child"]
        if child in joint_of:
            raise fail(
                f"link {child!r} is the child of two joints ({joint_of[child]!r} and {name!r}): "
                "the joints do not form a tree",
                joint,
            )
        parent_of[child], joint_of[child] = ends["parent"], name
        _check_joint_numbers(name, joint, fail)

    _check_tree(links, parent_of, fail)
    if not any(joint.get("type") in MOVABLE_TYPES for joint in joints.values()):
        raise fail("the robot has no movable (revolute, continuous or prismatic) joint", root)
    for name, link in links.items():
        _check_link(name, link, path, package_dirs, fail)
    return root


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _named(root: etree._Element, tag: str, fail: Fail) -> dict[str, etree._Element]:
    """The direct children ``<tag>`` of the robot by name, checking names are unique."""
    named: dict[str, etree._Element] = {}
    for element in root.findall(tag):
        name = element.get("name")
        if not name:
            raise fail(f"a <{tag}> has no name", element)
        if name in named:
            raise fail(
                f"{tag} name {name!r} appears twice (lines {named[name].sourceline} "
                f"and {element.sourceline})",
                element,
            )
        named[name] = element
    return named


def _check_tree(links: dict[str, etree._Element], parent_of: dict[str, str], fail: Fail) -> None:
    """Refuse cycles and forests: exactly one link may lack a parent."""
    for start in parent_of:
        seen = [start]
        link = start
        while link in parent_of:
            link = parent_of[link]
            if link in seen:
                cycle = seen[seen.index(link) :]
                raise fail(
                    "the joints form a cycle through links " + ", ".join(map(repr, cycle)),
                    links[link],
                )
            seen.append(link)
    roots = [name for name in links if name not in parent_of]
    if len(roots) > 1:
        raise fail(
            "the links do not form a single tree: several root links "
            f"({', '.join(map(repr, roots))}); every link but one must be a joint's child",
            links[roots[1]],
        )


def _numbers(
    element: etree._Element,
    attribute: str,
    count: int,
    what: str,
    fail: Fail,
    nonnegative: bool = False,
) -> list[float]:
    """Read ``count`` finite numbers from an attribute (each ``>= 0`` when ``nonnegative``)."""
    text = element.get(attribute)
    try:
        values = [float(word) for word in text.split()] if text is not None else []
    except ValueError:
        values = []
    if len(values) != count:
        raise fail(f"{what} {attribute}={text!r} is not {count} number(s)", element)
    if not all(math.isfinite(value) for value in values):
        raise fail(f"{what} {attribute}={text!r} is not finite", element)
    if nonnegative and any(value < 0.0 for value in values):
        raise fail(f"{what} {attribute}={text!r} is negative", element)
    return values


def _check_origin(parent: etree._Element, what: str, fail: Fail) -> None:
    origin = parent.find("origin")
    if origin is not None:
        for attribute in ("xyz", "rpy"):
            if origin.get(attribute) is not None:
                _numbers(origin, attribute, 3, f"{what} origin", fail)


def _check_joint_numbers(name: str, joint: etree._Element, fail: Fail) -> None:
    what = f"joint {name!r}"
    _check_origin(joint, what, fail)
    kind = joint.get("type")
    axis = joint.find("axis")
    if axis is not None and axis.get("xyz") is not None:
        direction = _numbers(axis, "xyz", 3, f"{what} axis", fail)
        if kind in MOVABLE_TYPES and not any(direction):
            raise fail(f"{what} has a zero axis", axis)
    limit = joint.find("limit")
    if limit is None:
        if kind in ("revolute", "prismatic"):
            raise fail(f"{what} is {kind} but has no <limit>", joint)
        return
    values = {  # effort and velocity are bounds on magnitudes: never negative
        attribute: _numbers(limit, attribute, 1, f"{what} limit", fail, attribute in _MAGNITUDES)[0]
        for attribute in ("lower", "upper", *_MAGNITUDES)
        if limit.get(attribute) is not None
    }
    lower, upper = values.get("lower", 0.0), values.get("upper", 0.0)
    if kind in ("revolute", "prismatic") and lower > upper:
        raise fail(f"{what} has lower limit {lower:g} above its upper limit {upper:g}", limit)


_MAGNITUDES = ("effort", "velocity")

_SHAPES = {"box": {"size": 3}, "cylinder": {"radius": 1, "length": 1}, "sphere": {"radius": 1}}
"""Primitive shapes and their size attributes (finite, >= 0; a radius 0 is a segment)."""


def _check_link(
    name: str, link: etree._Element, urdf: Path, package_dirs: Sequence[str | Path], fail: Fail
) -> None:
    what = f"link {name!r}"
    inertial = link.find("inertial")
    if inertial is not None:
        _check_origin(inertial, f"{what} inertial", fail)
        mass = inertial.find("mass")
        if mass is not None:
            _numbers(mass, "value", 1, f"{what} mass", fail, nonnegative=True)
        inertia = inertial.find("inertia")
        for attribute in () if inertia is None else inertia.attrib:
            _numbers(inertia, attribute, 1, f"{what} inertia", fail)
    for kind in ("visual", "collision"):
        for element in link.findall(kind):
            _check_origin(element, f"{what} {kind}", fail)
            for shape in element.iterfind("geometry/*"):
                for attribute, count in _SHAPES.get(shape.tag, {}).items():
                    _numbers(shape, attribute, count, f"{what} {kind} {shape.tag}", fail, True)
                if shape.tag == "mesh":
                    if shape.get("scale") is not None:
                        _numbers(shape, "scale", 3, f"{what} {kind} mesh", fail)
                    _check_mesh(shape, urdf, package_dirs, fail)


def _check_mesh(
    mesh: etree._Element, urdf: Path, package_dirs: Sequence[str | Path], fail: Fail
) -> None:
    """A mesh file must exist; a ``package://`` one must stay inside its package."""
    filename = mesh.get("filename")
    if not filename:
        raise fail("a <mesh> has no filename", mesh)
    if filename.startswith("package://"):
        # "package:///pkg/..." (extra slash) is read as "package://pkg/..." like Pinocchio does
        package, _, rest = filename.removeprefix("package://").lstrip("/").partition("/")
        inside = posixpath.normpath(rest or ".")
        if not package or package in (".", "..") or inside.startswith(("..", "/")):
            raise fail(f"mesh {filename!r} leaves its package folder", mesh)
        candidates = [Path(folder) / package / inside for folder in package_dirs]
        if not any(candidate.is_file() for candidate in candidates):
            searched = ", ".join(map(str, package_dirs)) or "none given"
            raise fail(f"mesh file {filename!r} not found (package folders: {searched})", mesh)
        return
    if "://" in filename and not filename.startswith("file://"):
        raise fail(f"mesh {filename!r} uses an unsupported URI scheme", mesh)
    file = urdf.parent / filename.removeprefix("file://")
    if not file.is_file():
        raise fail(f"mesh file {filename!r} not found (looked for {file})", mesh)
