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
:data:`MAX_NAME_LENGTH` characters. Numbers must lie in physical ranges
(:data:`~clik.model.urdf_numbers.RANGES`, :mod:`clik.model.urdf_numbers`):
positions and sizes within :data:`~clik.model.mesh_check.MAX_COORDINATE` [m],
angles within :data:`~clik.model.urdf_numbers.MAX_ANGLE` [rad], masses within
:data:`~clik.model.urdf_numbers.MAX_MASS` [kg]. Joints are checked
by :mod:`clik.model.urdf_joints`, links and their mesh files by
:mod:`clik.model.urdf_links` (with :func:`clik.model.mesh_check.check_mesh_file`:
regular file, format, size, counts, symlinks and side files that stay inside
their package).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from lxml import etree

from clik.errors import RobotLoadError
from clik.model.mesh_check import regular_file_problem
from clik.model.urdf_joints import MOVABLE_TYPES, joint_ends
from clik.model.urdf_links import check_link
from clik.model.urdf_numbers import SHOWN_NAME, Fail, shown

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

_BUDGETS = {
    "MAX_URDF_BYTES": (MAX_URDF_BYTES, "bytes"),
    "MAX_ELEMENTS": (MAX_ELEMENTS, "elements"),
    "MAX_ATTRIBUTES": (MAX_ATTRIBUTES, "attributes"),
    "MAX_NAME_LENGTH": (MAX_NAME_LENGTH, "characters"),
    "MAX_LINKS": (MAX_LINKS, "links or joints"),
    "MAX_MOVABLE_JOINTS": (MAX_MOVABLE_JOINTS, "movable joints"),
    "MAX_DEPTH": (MAX_DEPTH, "joints from the root link"),
}

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
    (:data:`~clik.model.urdf_numbers.RANGES`); ``lower <= upper`` for revolute and
    prismatic joints; no negative effort or velocity limit, mass or primitive size
    (box, cylinder, sphere; a zero radius is allowed: planar arms use segments); mesh scales in
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
    parent_of = joint_ends(links, joints, fail)
    _check_tree(links, parent_of, fail)
    if not any(joint.get("type") in MOVABLE_TYPES for joint in joints.values()):
        raise fail("the robot has no movable (revolute, continuous or prismatic) joint", root)
    for name, link in links.items():
        check_link(name, link, path, package_dirs, fail)
    return root


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
