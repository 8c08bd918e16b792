"""Strict checks on an MJCF (MuJoCo) model before MuJoCo's compiler reads it.

:func:`check_mjcf` reads the model and every file it names with clik's strict XML
reader and hands MuJoCo's compiler (:mod:`clik.model.mjcf_compiled`) one
self-contained document (:class:`MjcfDocument`); MuJoCo never opens the user's files
itself but the checked mesh files:

- every file is parsed by :func:`clik.model.urdf_check.parse_xml` (no entities,
  no external DTD, no XInclude, the byte, element and attribute budgets);
- ``<include file=...>`` elements are replaced by the children of the included
  file's ``<mujoco>``, recursively, paths relative to the main file's folder (as
  MuJoCo reads them), at most :data:`MAX_INCLUDES` files, :data:`MAX_INCLUDE_DEPTH`
  deep, each file once;
- repeated sections are merged (later ``<compiler>`` attributes override earlier
  ones, other sections' children are appended), as MuJoCo reads them;
- mesh and texture files are located as MuJoCo does (``meshdir``, ``texturedir``,
  ``assetdir``, ``strippath``), checked (:func:`clik.model.mesh_check.check_mesh_file`
  for meshes: regular file, format, size, counts, an OBJ's ``mtllib`` files) and
  written into the document as absolute paths. A missing mesh used only by visual
  geoms (``contype="0" conaffinity="0"``) is warned
  (:class:`~clik.model.visual_meshes.MissingVisualMeshWarning`) and those geoms are
  left out, as for a URDF's visual meshes; a missing collision mesh is refused;
- every file read (the includes, meshes, textures, an OBJ's material files) must
  resolve, symlinks followed, inside the main file's folder;
- numbers of bodies, joints, geoms, sites, inertials, meshes and keys are finite
  and in range, joint ranges ``lower <= upper`` (:mod:`clik.model.mjcf_numbers`), and
  each primitive geom gets the sizes its shape needs (:mod:`clik.model.mjcf_geoms`);
- elements that would change the robot in ways clik does not load (``<frame>`` or
  ``<replicate>`` directly in the world, ``<attach>``, ``<composite>``,
  ``<flexcomp>``, height fields, ball joints, a second body in the world) are refused;
- the root body's free joint is removed (its 7 ``qpos`` values leave every key:
  :attr:`MjcfDocument.home_base` keeps the ``home`` key's), and so is the root body's
  pose (``pos``, ``quat``, ``euler``, ...): :mod:`clik.model.mjcf` places the root body
  itself, at :attr:`MjcfDocument.root_probe`'s pose (the base is clik's choice:
  ``base="fixed"``, ``"planar"`` or ``"floating"``). With a fixed base a removed free
  joint is warned (:class:`FreeJointWeldedWarning`); with a planar or floating base the
  ``<keyframe>`` leaves the document too and clik reads the ``home`` key
  (:attr:`MjcfDocument.home_joints`).

Each problem raises :class:`~clik.errors.RobotLoadError` naming the file (the included
one, when it is there) and the line.
"""

from __future__ import annotations

import os
from pathlib import Path

from lxml import etree

from clik.errors import RobotLoadError, shown_path
from clik.model.base import FIXED, check_base
from clik.model.mesh_check import (
    MAX_MESH_BYTES,
    MeshRefused,
    check_mesh_file,
    regular_file_problem,
)
from clik.model.mjcf_geoms import check_geom_sizes
from clik.model.mjcf_numbers import check_numbers, unit_axis_angles
from clik.model.mjcf_root import SOURCE_ATTRIBUTE as _SOURCE
from clik.model.mjcf_root import MjcfDocument, check_world
from clik.model.mjcf_visual import drop_visual_meshes
from clik.model.urdf_check import (
    MAX_ELEMENTS,
    parse_xml,
)
from clik.model.urdf_numbers import SHOWN_NAME, Fail, shown

MAX_INCLUDES = 100
"""Most files an MJCF model may include (``<include>``, all levels)."""

MAX_INCLUDE_DEPTH = 8
"""Most nested levels of ``<include>`` (a file including one that includes ...)."""

MERGED_SECTIONS = ("default", "asset", "worldbody", "keyframe")
"""Top-level sections merged into their first copy (MuJoCo reads them all)."""

REFUSED_ELEMENTS = {
    "attach": "clik loads one model file (and its includes): attach the model with <include>",
    "composite": "clik loads rigid bodies: a <composite> makes soft or particle bodies",
    "flexcomp": "clik loads rigid bodies: a <flexcomp> makes a deformable body",
    "hfield": "height fields (<hfield>) are terrain, not part of a robot: give obstacles",
}
"""Elements refused, with why: clik would load a different robot."""

WORLD_REFUSED = ("frame", "replicate")
"""Elements refused directly in ``<worldbody>`` (they would hide or repeat the root body);
inside a body MuJoCo's compiler reads them."""

CHECKED_FILES = ("include", "mesh", "texture")
"""Elements whose file attributes clik checks; a file attribute elsewhere is refused."""

TEXTURE_FILES = ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")
"""A ``<texture>``'s file attributes (one image, or a cube's six)."""

_LEADING = ("compiler", "default", "asset")  # before the bodies, as MuJoCo reads them


def is_mjcf(path: str | Path) -> bool:
    """True for an existing file, not ending ``.urdf`` or ``.xacro``, whose root is ``<mujoco>``.

    The file is parsed strictly (:func:`~clik.model.urdf_check.parse_xml`); one that
    cannot be parsed is not called MJCF here (the URDF checks then report it).
    """
    path = Path(path)
    if path.suffix.lower() in (".urdf", ".xacro") or regular_file_problem(path) is not None:
        return False
    try:
        return parse_xml(path).getroot().tag == "mujoco"
    except RobotLoadError:
        return False


def check_mjcf(path: str | Path, base: str = FIXED) -> MjcfDocument:
    """Check an MJCF model and every file it reads; the document MuJoCo may compile.

    Args:
        path: The main model file (root element ``<mujoco>``).
        base: The base the robot is loaded with (:data:`clik.model.base.BASES`): a fixed
            base warns about a removed free joint; a planar or floating one has the
            ``<keyframe>`` removed from the document (read into the document's fields).

    Returns:
        The checked, self-contained document.

    Raises:
        RobotLoadError: The first problem found, naming its file and line.

    Warns:
        FreeJointWeldedWarning: With a fixed base, the root body has a free joint; it was
            removed.
    """
    check_base(base)
    path = Path(path)
    folder = path.parent.absolute()
    expansion = _Expansion(path, folder)
    root = expansion.root
    _merge_sections(root)
    fail = _failing(path)
    if root.get("model") is None:
        root.set("model", path.stem)  # MuJoCo's default
    compiler = root.find("compiler")
    compiler = compiler if compiler is not None else etree.SubElement(root, "compiler")
    degrees = compiler.get("angle", "degree") != "radian"
    _check_world_elements(root, fail)
    unit_axis_angles(root)
    files = [path.resolve(), *expansion.included]
    missing: list[tuple[etree._Element, str, str]] = []
    files += _locate_assets(root, compiler, folder, fail, missing)
    drop_visual_meshes(root, missing, fail)
    for attribute in ("meshdir", "texturedir", "assetdir", "strippath"):
        compiler.attrib.pop(attribute, None)
    compiler.set("fusestatic", "false")  # every body stays a frame (not fused into its parent)
    document = MjcfDocument(path, "", files, degrees, base=base)
    check_world(root, path, fail, document)
    check_geom_sizes(root, fail)
    document.text, document.lines = _serialised(root, path)
    return document


def _serialised(root: etree._Element, path: Path) -> tuple[str, dict[int, tuple[str, int]]]:
    """The document, one element per line, and each line's element's file and line.

    MuJoCo's compiler names the line of the document it refuses: :data:`MjcfDocument.lines
    <clik.model.mjcf_root.MjcfDocument.lines>` turns it back into the user's file and line.
    """
    elements = [e for e in root.iter() if isinstance(e.tag, str)]
    origins = [(_source_of(e) or str(path), e.sourceline) for e in elements]
    for element in root.iter():
        element.attrib.pop(_SOURCE, None)
        if element.text is not None and not element.text.strip():
            element.text = None
        if element.tail is not None and not element.tail.strip():
            element.tail = None
    text = etree.tostring(root, encoding="unicode", pretty_print=True)
    written = [e for e in etree.fromstring(text).iter() if isinstance(e.tag, str)]
    lines = {
        int(e.sourceline): (source, int(line))
        for e, (source, line) in zip(written, origins, strict=True)
        if e.sourceline is not None and line is not None
    }
    return text, lines


def _failing(path: Path) -> Fail:
    """A ``fail(problem, element)`` naming the element's own file (an included one) and line."""

    def fail(problem: str, element: etree._Element | None = None) -> RobotLoadError:
        if element is None:
            return RobotLoadError(path, problem)
        source = _source_of(element) or path
        return RobotLoadError(source, problem, line=element.sourceline)

    return fail


def _source_of(element: etree._Element) -> str | None:
    """The file an element came from (set on each element while includes are expanded)."""
    return element.get(_SOURCE)


class _Expansion:
    """The main file with its ``<include>`` elements replaced, each file checked on the way."""

    def __init__(self, path: Path, folder: Path) -> None:
        self.folder = folder
        self.included: list[Path] = []
        self.seen = {path.resolve()}
        self.elements = 0
        self.root = self._read(path, path, depth=0)

    def _read(self, path: Path, shown_as: Path, depth: int) -> etree._Element:
        root = parse_xml(path).getroot()
        fail = _failing(shown_as)
        if root.tag != "mujoco":
            raise fail(f"the root element is <{shown(str(root.tag))}>, expected <mujoco>", root)
        self.elements += sum(1 for _ in root.iter())
        if self.elements > MAX_ELEMENTS:
            raise fail(
                f"the model and its includes have more than {MAX_ELEMENTS} elements "
                "(clik.model.urdf_check.MAX_ELEMENTS)"
            )
        for element in root.iter():
            if isinstance(element.tag, str):
                element.set(_SOURCE, str(shown_as))
        _check_elements(root, fail)
        for include in list(root.iter("include")):
            self._expand(include, fail, depth)
        return root

    def _expand(self, include: etree._Element, fail: Fail, depth: int) -> None:
        written = include.get("file")
        if not written:
            raise fail("an <include> has no file", include)
        if depth + 1 > MAX_INCLUDE_DEPTH:
            raise fail(
                f"<include file={shown_path(written)}> is {depth + 1} levels deep, above the "
                f"budget of {MAX_INCLUDE_DEPTH} (clik.model.mjcf_check.MAX_INCLUDE_DEPTH)",
                include,
            )
        file = _inside(self.folder / written, self.folder, f"included file {shown_path(written)}")
        if isinstance(file, str):
            raise fail(file, include)
        if file in self.seen:
            raise fail(
                f"included file {shown_path(written)} is included twice (or in a cycle)", include
            )
        self.seen.add(file)
        self.included.append(file)
        if len(self.included) > MAX_INCLUDES:
            raise fail(
                f"more than {MAX_INCLUDES} included files (clik.model.mjcf_check.MAX_INCLUDES)",
                include,
            )
        child = self._read(self.folder / written, self.folder / written, depth + 1)
        parent = include.getparent()
        position = parent.index(include)
        parent.remove(include)
        for offset, element in enumerate(list(child)):
            parent.insert(position + offset, element)


def _inside(file: Path, folder: Path, what: str) -> Path | str:
    """``file`` resolved, if it is a regular file inside ``folder``; else the problem."""
    problem = regular_file_problem(file)
    if problem is not None:
        return f"{what} ({file}) {'not found' if problem == 'no such file' else problem}"
    resolved = file.resolve()
    if not resolved.is_relative_to(folder.resolve()):
        return f"{what} resolves to {resolved}, which leaves the model's folder {folder}"
    return resolved


def _check_elements(root: etree._Element, fail: Fail) -> None:
    """Refused elements, file attributes clik does not check, and every number, in one file."""
    for element in root.iter():
        if not isinstance(element.tag, str):
            continue  # a comment or processing instruction
        tag = element.tag
        if tag in REFUSED_ELEMENTS:
            raise fail(f"<{tag}> is refused: {REFUSED_ELEMENTS[tag]}", element)
        if tag not in CHECKED_FILES and any(a.startswith("file") for a in element.attrib):
            raise fail(
                f"<{tag[:SHOWN_NAME]}> names a file, which clik does not read (files are read only "
                f"through {', '.join(f'<{t}>' for t in CHECKED_FILES)})",
                element,
            )
        check_numbers(element, fail)


def _merge_sections(root: etree._Element) -> None:
    """One ``<compiler>``, ``<default>``, ``<asset>``, ``<worldbody>``, ``<keyframe>`` each."""
    compilers = root.findall("compiler")
    for later in compilers[1:]:
        for name, value in later.attrib.items():
            if name != _SOURCE:
                compilers[0].set(name, value)
        root.remove(later)
    for tag in MERGED_SECTIONS:
        sections = root.findall(tag)
        for later in sections[1:]:
            sections[0].extend(list(later))
            root.remove(later)
    for position, tag in enumerate(_LEADING):  # read before the bodies, as MuJoCo does
        section = root.find(tag)
        if section is not None:
            root.insert(position, section)


def _check_world_elements(root: etree._Element, fail: Fail) -> None:
    """No ``<frame>`` or ``<replicate>`` directly in the world (around the root body)."""
    for world in root.iter("worldbody"):
        for element in world:
            if element.tag in WORLD_REFUSED:
                raise fail(
                    f"<{element.tag}> directly in <worldbody> is refused: clik loads one robot "
                    "from one root body; put the <frame> or <replicate> inside the root body",
                    element,
                )


def _locate_assets(
    root: etree._Element,
    compiler: etree._Element,
    folder: Path,
    fail: Fail,
    missing: list[tuple[etree._Element, str, str]],
) -> list[Path]:
    """Check every mesh and texture file; write its absolute path in the document.

    A mesh file not found is appended to ``missing`` (element, file as written, problem)
    instead of refused: :func:`~clik.model.mjcf_visual.drop_visual_meshes` decides.
    """
    strip = compiler.get("strippath") == "true"
    asset_dir = compiler.get("assetdir", "")
    dirs = {
        "mesh": compiler.get("meshdir", asset_dir),
        "texture": compiler.get("texturedir", asset_dir),
    }
    files: list[Path] = []
    for tag in ("mesh", "texture"):
        for element in root.iter(tag):
            for attribute in TEXTURE_FILES if tag == "texture" else ("file",):
                written = element.get(attribute)
                if written is None:
                    continue
                name = Path(written).name if strip else written
                file = folder / dirs[tag] / name  # an absolute name or dir stays absolute
                what = f"{tag} file {shown_path(written)}"
                located = _inside(file, folder, what)
                if isinstance(located, str) and tag == "mesh" and "not found" in located:
                    missing.append((element, written, located))
                    break
                if isinstance(located, str):
                    raise fail(located, element)
                if tag == "mesh":
                    _check_mesh(element, file, folder, what, fail)
                elif os.stat(located).st_size > MAX_MESH_BYTES:
                    raise fail(f"{what} is above {MAX_MESH_BYTES} bytes (MAX_MESH_BYTES)", element)
                if tag == "mesh" and element.get("name") is None:
                    element.set("name", Path(written).stem)  # MuJoCo's and Pinocchio's name
                element.set(attribute, str(located))
                files.append(located)
    return files


def _check_mesh(element: etree._Element, file: Path, folder: Path, what: str, fail: Fail) -> None:
    """The cheap mesh checks, an OBJ's material files inside the folder."""
    scale = [float(s) for s in element.get("scale", "1 1 1").split()]
    try:
        facts = check_mesh_file(file, scale, folder, what=what)
        for side in facts.side_files:
            located = _inside(facts.path.parent / side, folder, f"its material file {side!r}")
            if isinstance(located, str) and "not found" not in located:
                raise MeshRefused(f"{what}: {located}")
    except MeshRefused as refused:
        raise fail(str(refused), element) from None
