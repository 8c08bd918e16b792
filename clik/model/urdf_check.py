"""Strict checks on a URDF file before any robotics library reads it.

Pinocchio and yourdfpy are lenient readers: yourdfpy recovers from malformed XML
and accepts a joint whose child link is missing, and neither gives a line number.
:func:`check_urdf` parses the file with a strict XML parser that never reads
another file or the network, refuses a DOCTYPE that declares entities (external
entities, "billion laughs") or points at an external DTD, then checks that the
description is a well-formed kinematic tree whose numbers are finite and whose
mesh files exist. Each problem raises :class:`~clik.errors.RobotLoadError` with
the problem in plain words and, when known, its line.

Budgets keep every check fast (each is linear in the number of elements, up
to a sort): a file of at most :data:`MAX_URDF_BYTES`, :data:`MAX_ELEMENTS`
elements and :data:`MAX_ATTRIBUTES` attributes per element, counted on the raw
bytes before the XML parser runs; at most :data:`MAX_LINKS` links and joints,
:data:`MAX_MOVABLE_JOINTS` movable joints, :data:`MAX_DEPTH` joints from the root
to any link, and names of at most
:data:`MAX_NAME_LENGTH` characters. Numbers must lie in physical ranges (:data:`RANGES`): positions
and sizes within :data:`~clik.model.mesh_check.MAX_COORDINATE` [m], angles within
:data:`MAX_ANGLE` [rad], masses within :data:`MAX_MASS` [kg]. Mesh files are
checked by :func:`clik.model.mesh_check.check_mesh_file` (regular file, format,
size, counts, symlinks and side files that stay inside their package).
"""

from __future__ import annotations

import math
import os
import posixpath
import re
from collections.abc import Callable, Sequence
from pathlib import Path

from lxml import etree

from clik import errors
from clik.errors import RobotLoadError
from clik.model.mesh_check import (
    MAX_COORDINATE,
    MeshRefused,
    check_mesh_file,
    check_scale,
    regular_file_problem,
)

MOVABLE_TYPES = ("revolute", "continuous", "prismatic")
"""Joint types that add a degree of freedom to a fixed-base arm."""

JOINT_TYPES = (*MOVABLE_TYPES, "fixed", "floating", "planar")

Fail = Callable[..., RobotLoadError]
"""Builds the error for a problem found at an element: ``fail(problem, element)``."""

MAX_URDF_BYTES = 64 * 2**20
"""Largest URDF (or SRDF, or xacro expansion) read [bytes]."""

MAX_ELEMENTS = 500_000
"""Most elements (counted as ``<`` signs: tags, comments) in a URDF."""

MAX_ATTRIBUTES = 100
"""Most attributes on one element (the XML parser's duplicate check is quadratic)."""

MAX_LINKS = 20_000
"""Most links (and joints) in a URDF (a wide tree of 10,000 loads in about 1 s)."""

MAX_DEPTH = 1000
"""Most joints between the root link and any link: Pinocchio's URDF reader recurses
along the tree and crashes (stack overflow) on chains of about 4,000 links."""

MAX_MOVABLE_JOINTS = 128
"""Most movable joints: Pinocchio's ``Data`` grows as ``nv^3`` (250 joints: 1 GB, 500: 8 GB)."""

MAX_NAME_LENGTH = 1000
"""Longest link or joint name [characters]."""

MAX_ANGLE = 4 * math.pi
"""Largest absolute angle in an origin's ``rpy`` [rad] (two turns)."""

MAX_MASS = 1e6
"""Largest mass [kg] and largest inertia entry [kg m^2]."""

MAX_LIMIT = 1e16
"""Largest absolute joint limit (position [rad or m], effort, velocity), dynamics value
(damping, friction) and mesh scale factor: 1e16 is the URDF convention for "no limit"."""

RANGES = {
    "position": MAX_COORDINATE,
    "angle": MAX_ANGLE,
    "mass": MAX_MASS,
    "limit": MAX_LIMIT,
    "scale": math.inf,  # each factor's magnitude in clik.model.mesh_check.SCALE_RANGE
}
"""Largest absolute value of each kind of URDF number."""

_BUDGETS = {
    "MAX_URDF_BYTES": (MAX_URDF_BYTES, "bytes"),
    "MAX_ELEMENTS": (MAX_ELEMENTS, "elements"),
    "MAX_ATTRIBUTES": (MAX_ATTRIBUTES, "attributes"),
    "MAX_NAME_LENGTH": (MAX_NAME_LENGTH, "characters"),
    "MAX_LINKS": (MAX_LINKS, "links or joints"),
    "MAX_MOVABLE_JOINTS": (MAX_MOVABLE_JOINTS, "movable joints"),
    "MAX_DEPTH": (MAX_DEPTH, "joints from the root link"),
}

SHOWN_NAME = 60
"""Characters of a long name shown in messages."""

_ENTITY = re.compile(rb"<!ENTITY")
_XINCLUDE = "{http://www.w3.org/2001/XInclude}"
_DOCTYPE = re.compile(rb"<!DOCTYPE\s+[^\s\[>]+\s*([^\[>]*)")
_ATTRIBUTE = re.compile(rb"=\s*[\"']")


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
        problem = regular_file_problem(path)
        if problem is not None:
            missing = problem == "no such file"
            raise RobotLoadError(path, "file not found" if missing else problem)
        size = path.stat().st_size
        if size > MAX_URDF_BYTES:
            raise RobotLoadError(path, _over_budget(f"{size} bytes", "MAX_URDF_BYTES"))
        data = path.read_bytes()
    if not data.strip():
        raise RobotLoadError(path, "file is empty")
    _check_budgets(path, data)
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


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _over_budget(found: str, name: str) -> str:
    """The problem "``found``, above the budget ``name``" (a constant of this module)."""
    budget = _BUDGETS[name]
    return f"{found}, above the budget of {budget[0]} {budget[1]} (clik.model.urdf_check.{name})"


def _check_budgets(path: Path, data: bytes) -> None:
    """Refuse a file over the size, element or attribute budget, on its raw bytes.

    Runs before the XML parser: libxml2 compares each attribute of an element
    with the ones before it, so 20,000 attributes take seconds.
    """
    if len(data) > MAX_URDF_BYTES:
        raise RobotLoadError(path, _over_budget(f"{len(data)} bytes", "MAX_URDF_BYTES"))
    elements = data.count(b"<")
    if elements > MAX_ELEMENTS:
        raise RobotLoadError(path, _over_budget(f"{elements} elements", "MAX_ELEMENTS"))
    offset = 0
    for chunk in data.split(b"<"):  # one chunk per tag (with the text after it)
        if chunk.count(b"=") > MAX_ATTRIBUTES:
            attributes = len(_ATTRIBUTE.findall(chunk.split(b">", 1)[0]))
            if attributes > MAX_ATTRIBUTES:
                problem = _over_budget(f"an element has {attributes} attributes", "MAX_ATTRIBUTES")
                raise RobotLoadError(path, problem, _line_of(data, offset))
        offset += len(chunk) + 1


def shown(name: str) -> str:
    """A name as messages show it: quoted, cut to :data:`SHOWN_NAME` characters when long."""
    return errors.shown(name, SHOWN_NAME)


def check_urdf(
    path: str | Path, package_dirs: Sequence[str | Path] = (), text: str | None = None
) -> etree._Element:
    """Check that a URDF file describes a valid kinematic tree.

    Checks, in order: strict XML within the budgets (see :func:`parse_xml`); a
    ``<robot>`` root; named, unique links and joints (names of at most
    :data:`MAX_NAME_LENGTH` characters); known joint types; parent and child
    links that exist; a tree (no cycle, a single root link, each link the child
    of at most one joint); at least one movable joint; numbers in origins, axes,
    limits, dynamics, inertials and geometry that are finite and in their range
    (:data:`RANGES`); ``lower <= upper`` for revolute and prismatic joints; no
    negative effort or velocity limit, mass or primitive size (box, cylinder,
    sphere; a zero radius is allowed: planar arms use segments); mesh scales in
    :data:`~clik.model.mesh_check.SCALE_RANGE`; mesh files that pass
    :func:`~clik.model.mesh_check.check_mesh_file`, where ``package://pkg/rest`` is
    looked up as ``<dir>/pkg/rest`` for each ``dir`` in ``package_dirs`` and must
    not leave the ``pkg`` folder (symlinks and OBJ ``mtllib`` files included),
    and a relative filename is relative to the URDF's folder (a symlink must not
    lead out of the folder its path names).

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
        raise fail(f"the root element is <{str(root.tag)[:SHOWN_NAME]}>, expected <robot>", root)
    links = _named(root, "link", fail)
    joints = _named(root, "joint", fail)
    if not links:
        raise fail("the robot has no <link>", root)
    if max(len(links), len(joints)) > MAX_LINKS:
        found = f"the robot has {len(links)} links and {len(joints)} joints"
        raise fail(_over_budget(found, "MAX_LINKS"), root)
    movable = sum(joint.get("type") in MOVABLE_TYPES for joint in joints.values())
    if movable > MAX_MOVABLE_JOINTS:
        raise fail(
            _over_budget(f"the robot has {movable} movable joints", "MAX_MOVABLE_JOINTS"), root
        )
    parent_of = _joint_ends(links, joints, fail)
    _check_tree(links, parent_of, fail)
    if not any(joint.get("type") in MOVABLE_TYPES for joint in joints.values()):
        raise fail("the robot has no movable (revolute, continuous or prismatic) joint", root)
    for name, link in links.items():
        _check_link(name, link, path, package_dirs, fail)
    return root


def _joint_ends(
    links: dict[str, etree._Element], joints: dict[str, etree._Element], fail: Fail
) -> dict[str, str]:
    """Child link -> parent link, checking each joint's type, ends and numbers."""
    parent_of: dict[str, str] = {}  # child link -> parent link
    joint_of: dict[str, str] = {}  # child link -> joint name
    for name, joint in joints.items():
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise fail(
                f"joint {shown(name)} has type {shown(str(kind))}; "
                f"known types: {', '.join(JOINT_TYPES)}",
                joint,
            )
        ends = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = None if element is None else element.get("link")
            if link is None:
                raise fail(f"joint {shown(name)} has no <{end} link=...>", joint)
            if link not in links:
                raise fail(
                    f"joint {shown(name)} names {end} link {shown(link)} that does not exist",
                    element,
                )
            ends[end] = link
        child = ends["child"]
        if child in joint_of:
            raise fail(
                f"link {shown(child)} is the child of two joints ({shown(joint_of[child])} and "
                f"{shown(name)}): the joints do not form a tree",
                joint,
            )
        parent_of[child], joint_of[child] = ends["parent"], name
        _check_joint_numbers(name, joint, fail)
    return parent_of


def _named(root: etree._Element, tag: str, fail: Fail) -> dict[str, etree._Element]:
    """The direct children ``<tag>`` of the robot by name, checking names are unique."""
    named: dict[str, etree._Element] = {}
    for element in root.findall(tag):
        name = element.get("name")
        if not name:
            raise fail(f"a <{tag}> has no name", element)
        if len(name) > MAX_NAME_LENGTH:
            found = f"{tag} name {shown(name)} is too long"
            raise fail(_over_budget(found, "MAX_NAME_LENGTH"), element)
        if name in named:
            raise fail(
                f"{tag} name {shown(name)} appears twice (lines {named[name].sourceline} "
                f"and {element.sourceline})",
                element,
            )
        named[name] = element
    return named


def _check_tree(links: dict[str, etree._Element], parent_of: dict[str, str], fail: Fail) -> None:
    """Refuse cycles, forests and chains deeper than :data:`MAX_DEPTH`.

    Exactly one link may lack a parent. Each link is walked up to once: a walk
    stops at a link already known to reach the root (its depth known), so the
    check is linear in the number of links.
    """
    depth = {name: 0 for name in links if name not in parent_of}
    reaches_root: set[str] = set()
    for start in parent_of:
        path: list[str] = []
        on_path: set[str] = set()
        link = start
        while link in parent_of and link not in reaches_root:
            if link in on_path:
                cycle = path[path.index(link) :]
                raise fail(
                    "the joints form a cycle through links "
                    + ", ".join(map(shown, cycle[:20]))
                    + (f", ... ({len(cycle)} links)" if len(cycle) > 20 else ""),
                    links[link],
                )
            path.append(link)
            on_path.add(link)
            link = parent_of[link]
        reaches_root.update(path)
        below = depth[link]  # the root or a link whose depth is known
        for step, name in enumerate(reversed(path), start=1):
            depth[name] = below + step
        if below + len(path) > MAX_DEPTH:
            found = f"link {shown(start)} is {below + len(path)} joints from the root link"
            raise fail(_over_budget(found, "MAX_DEPTH"), links[start])
    roots = [name for name in links if name not in parent_of]
    if len(roots) > 1:
        listed = ", ".join(map(shown, roots[:20])) + (", ..." if len(roots) > 20 else "")
        raise fail(
            f"the links do not form a single tree: several root links ({listed}); "
            "every link but one must be a joint's child",
            links[roots[1]],
        )


_UNITS = {"position": "m", "angle": "rad", "mass": "kg or kg m^2", "limit": "", "scale": ""}


def _numbers(
    element: etree._Element,
    attribute: str,
    count: int,
    what: str,
    fail: Fail,
    kind: str = "position",
    nonnegative: bool = False,
) -> list[float]:
    """Read ``count`` finite numbers from an attribute, each within ``RANGES[kind]``.

    Each must also be ``>= 0`` when ``nonnegative``.
    """
    text = element.get(attribute)
    try:
        values = [float(word) for word in text.split()] if text is not None else []
    except ValueError:
        values = []
    written = shown(str(text))
    if len(values) != count:
        raise fail(f"{what} {attribute}={written} is not {count} number(s)", element)
    if not all(math.isfinite(value) for value in values):
        raise fail(f"{what} {attribute}={written} is not finite", element)
    if nonnegative and any(value < 0.0 for value in values):
        raise fail(f"{what} {attribute}={written} is negative", element)
    bound = RANGES[kind]
    if any(abs(value) > bound for value in values):
        low = 0 if nonnegative else -bound
        raise fail(
            f"{what} {attribute}={written} is out of range: each value must be within "
            f"[{low:g}, {bound:g}] {_UNITS[kind]}".rstrip(),
            element,
        )
    return values


def _check_origin(parent: etree._Element, what: str, fail: Fail) -> None:
    origin = parent.find("origin")
    if origin is not None:
        for attribute, kind in (("xyz", "position"), ("rpy", "angle")):
            if origin.get(attribute) is not None:
                _numbers(origin, attribute, 3, f"{what} origin", fail, kind)


def _check_joint_numbers(name: str, joint: etree._Element, fail: Fail) -> None:
    what = f"joint {shown(name)}"
    _check_origin(joint, what, fail)
    kind = joint.get("type")
    axis = joint.find("axis")
    if axis is not None and axis.get("xyz") is not None:
        direction = _numbers(axis, "xyz", 3, f"{what} axis", fail)
        if kind in MOVABLE_TYPES and not any(direction):
            raise fail(f"{what} has a zero axis", axis)
    dynamics = joint.find("dynamics")
    for attribute in ("damping", "friction"):
        if dynamics is not None and dynamics.get(attribute) is not None:
            _numbers(dynamics, attribute, 1, f"{what} dynamics", fail, "limit")
    limit = joint.find("limit")
    if limit is None:
        if kind in ("revolute", "prismatic"):
            raise fail(f"{what} is {kind} but has no <limit>", joint)
        return
    values = {  # effort and velocity are bounds on magnitudes: never negative
        attribute: _numbers(
            limit, attribute, 1, f"{what} limit", fail, "limit", attribute in _MAGNITUDES
        )[0]
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
    what = f"link {shown(name)}"
    inertial = link.find("inertial")
    if inertial is not None:
        _check_origin(inertial, f"{what} inertial", fail)
        mass = inertial.find("mass")
        if mass is not None:
            _numbers(mass, "value", 1, f"{what} mass", fail, "mass", nonnegative=True)
        inertia = inertial.find("inertia")
        for attribute in () if inertia is None else inertia.attrib:
            _numbers(inertia, attribute, 1, f"{what} inertia", fail, "mass")
    for kind in ("visual", "collision"):
        for element in link.findall(kind):
            _check_origin(element, f"{what} {kind}", fail)
            for shape in element.iterfind("geometry/*"):
                for attribute, count in _SHAPES.get(shape.tag, {}).items():
                    _numbers(
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
        scale = _numbers(mesh, "scale", 3, what, fail, "scale")  # range: check_scale
    filename = mesh.get("filename")
    if not filename:
        raise fail("a <mesh> has no filename", mesh)
    file, root = _mesh_location(filename, mesh, urdf, package_dirs, fail)
    try:
        check_scale(scale, what)
        facts = check_mesh_file(file, scale, root, what=f"{what} {shown(filename)}: file")
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
            raise fail(f"mesh {shown(filename)} leaves its package folder", mesh)
        for folder in package_dirs:  # the first folder holding it, as Pinocchio looks
            candidate = Path(folder) / package / inside
            if os.path.lexists(candidate):
                return candidate, Path(folder) / package
        searched = ", ".join(map(str, package_dirs)) or "none given"
        raise fail(f"mesh file {shown(filename)} not found (package folders: {searched})", mesh)
    if "://" in filename and not filename.startswith("file://"):
        raise fail(f"mesh {shown(filename)} uses an unsupported URI scheme", mesh)
    file = urdf.parent / filename.removeprefix("file://")
    if not os.path.lexists(file):
        raise fail(f"mesh file {shown(filename)} not found (looked for {file})", mesh)
    return file, Path(os.path.normpath(file.absolute().parent))
