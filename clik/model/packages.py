"""ROS packages found the way ROS finds them: by the name in their ``package.xml``.

A ``package://pkg/...`` mesh and a xacro ``$(find pkg)`` name a *package*. ROS
finds it by the ``<name>`` in its ``package.xml``, anywhere under a workspace's
``src`` folder, whatever its folder is called; clik does the same, under each folder
of ``package_dirs`` (:class:`PackageDirs`), in order:

1. ``<dir>/pkg``, a folder directly inside ``dir``: found as before workspaces were
   searched (and as Pinocchio looks ``package://`` up), without a search, whatever
   name its ``package.xml`` gives (example-robot-data's folder
   ``example-robot-data`` holds the package ``example_robot_data``, and its URDFs
   say ``package://example-robot-data/...``); unless it holds no ``package.xml``
   and a folder directly inside it is the package ``pkg`` (a repository named
   after the package it holds); when its ``package.xml`` names ``pkg``, another
   package ``pkg`` below ``dir`` is an error naming both (as step 2 says), so that a
   namesake directly in ``dir`` never hides a duplicate;
2. else the packages under ``dir``, searched recursively as colcon and rospack do
   (:meth:`PackageDirs.packages_under`): a folder holding ``COLCON_IGNORE``,
   ``AMENT_IGNORE`` or ``CATKIN_IGNORE`` is skipped with everything below it; hidden
   folders (``.git``) are skipped; the search does not enter a package (a package
   inside another is not one); symbolic links to folders are not followed (a link
   *directly* inside ``dir`` still names a package by its own name, step 1). Two
   packages of one name under ``dir`` are an error naming both.

Then, when set, each folder of ``ROS_PACKAGE_PATH`` (colon-separated, searched like
``package_dirs``), then each prefix of ``AMENT_PREFIX_PATH``
(``<prefix>/share/pkg/package.xml``). The first folder holding the package wins
(an overlay shadows its underlay, as in ROS).

Folders that cannot be looked into are skipped, and the filesystem root is never
searched (a string given as ``package_dirs`` names it: one folder per character).
Every ``package.xml`` read is parsed strictly (:func:`clik.model.urdf_check.parse_xml`).
The search is bounded: at most :data:`MAX_PACKAGE_DEPTH` folder levels below a
searched folder and :data:`MAX_FOLDERS_VISITED` folders per searched folder; past
either it stops with an :class:`~clik.errors.InputError` on ``package_dirs`` naming
the folder (pass a narrower folder, e.g. ``ws/src``, or add a ``COLCON_IGNORE``).

One :class:`PackageDirs` is made per :meth:`Robot.load <clik.model.robot.Robot.load>`:
it searches each folder once, when a package is first not found directly, and keeps
what it found for the rest of that load only (the files may change between loads).
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import overload

from clik.errors import InputError, RobotLoadError
from clik.model.urdf_check import parse_xml

MANIFEST = "package.xml"
"""The file that makes a folder a ROS package (catkin and ament alike)."""

IGNORE_MARKERS = ("COLCON_IGNORE", "AMENT_IGNORE", "CATKIN_IGNORE")
"""A folder holding one of these files is skipped, with everything below it."""

MAX_PACKAGE_DEPTH = 12
"""Most folder levels searched below a package folder (``ws/src``: ``src/repo/group/pkg``
is 3 levels deep)."""

MAX_FOLDERS_VISITED = 20_000
"""Most folders one search of a package folder visits (a large colcon workspace's
``src`` holds a few thousand)."""


@dataclass(frozen=True)
class Package:
    """A ROS package found on disk.

    Attributes:
        name: Its name (the ``<name>`` of its ``package.xml``, else its folder's name).
        folder: Its folder, symlinks resolved: every file read from the package must
            stay inside it.
        manifest: Its ``package.xml``, or None for a folder found by its name alone.
    """

    name: str
    folder: Path
    manifest: Path | None = None


def package_name(manifest: Path) -> str:
    """The ``<name>`` of a ``package.xml``, read strictly.

    Raises:
        RobotLoadError: The file is not strict XML, its root is not ``<package>``, or it
            has no usable ``<name>`` (empty, or with a slash or a dot-only name).
    """
    root = parse_xml(manifest).getroot()
    if root.tag != "package":
        raise RobotLoadError(
            manifest, f"the root element is <{str(root.tag)[:40]}>, expected <package>"
        )
    name = (root.findtext("name") or "").strip()
    if name in ("", ".", "..") or "/" in name or "\\" in name or len(name) > 200:
        raise RobotLoadError(
            manifest,
            "expected a <name> holding the package's name (no slash)",
            line=root.sourceline,
        )
    return name


def is_skipped(folder: Path) -> bool:
    """Whether the search skips ``folder``: hidden, holding an ignore marker, or unreadable.

    A folder the user may not look into (``/proc/1/fdinfo``) is skipped, as colcon
    skips it, rather than stopping the search.
    """
    try:
        return folder.name.startswith(".") or any(
            (folder / marker).exists() for marker in IGNORE_MARKERS
        )
    except OSError:  # no permission to look into it
        return True


class PackageDirs(Sequence[Path]):
    """The folders holding packages, and the packages found in them (one load's worth).

    A sequence of the folders given (``package_dirs``), so it passes wherever a list
    of folders does; :meth:`find` looks a package up by name as the module says.

    Args:
        folders: The package folders, in the order they are searched.
        environ: Where ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` are read
            (default: ``os.environ``, read now).
    """

    def __init__(
        self, folders: Sequence[str | Path], environ: Mapping[str, str] | None = None
    ) -> None:
        env = os.environ if environ is None else environ
        self.folders = [Path(f) for f in folders]
        self.ros_folders = _path_list(env.get("ROS_PACKAGE_PATH", ""))
        self.ament_prefixes = _path_list(env.get("AMENT_PREFIX_PATH", ""))
        self._searched: dict[Path, dict[str, list[Package]]] = {}
        self._found: dict[str, Package | None] = {}
        self._unsearchable: set[Path] = set()

    @overload
    def __getitem__(self, index: int) -> Path: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[Path]: ...
    def __getitem__(self, index: int | slice) -> Path | Sequence[Path]:
        return self.folders[index]

    def __len__(self) -> int:
        return len(self.folders)

    def __repr__(self) -> str:
        return f"PackageDirs({[str(f) for f in self.folders]})"

    def searched(self) -> str:
        """The folders searched, in words (for messages).

        A folder that does not exist says so (a misspelt ``package_dirs``); folders of one
        character each are a string given where a list was expected.
        """
        parts = [", ".join(map(_folder_in_words, self.folders)) or "none given"]
        if len(self.folders) > 1 and all(len(str(f)) == 1 for f in self.folders):
            parts[0] += " (a single string given as package_dirs: pass a list, ['ws/src'])"
        if self.ros_folders:
            parts.append("ROS_PACKAGE_PATH: " + ", ".join(map(str, self.ros_folders)))
        if self.ament_prefixes:
            parts.append("AMENT_PREFIX_PATH: " + ", ".join(map(str, self.ament_prefixes)))
        return "; ".join(parts)

    def find(self, name: str) -> Package | None:
        """The package called ``name``, or None when no searched folder holds it.

        Raises:
            InputError: Two packages of that name under one searched folder (both
                named), or a search past :data:`MAX_PACKAGE_DEPTH` or
                :data:`MAX_FOLDERS_VISITED`.
            RobotLoadError: A ``package.xml`` met on the way is not strict XML or has
                no name.
        """
        if name not in self._found:
            self._found[name] = self._find(name)
        return self._found[name]

    def _find(self, name: str) -> Package | None:
        """:meth:`find`, not remembered."""
        if name in ("", ".", "..") or "/" in name or "\\" in name:
            return None
        for folder in [*self.folders, *self.ros_folders]:
            direct = _direct_package(folder, name)
            if direct is not None:
                self._check_unshadowed(folder, direct)
                return direct
            found = self.packages_under(folder).get(name, [])
            if len(found) > 1:
                raise _duplicate_error(name, folder, found)
            if found:
                return found[0]
        for prefix in self.ament_prefixes:
            manifest = prefix / "share" / name / MANIFEST
            if _is_file(manifest) and package_name(manifest) == name:
                return Package(name, manifest.parent.resolve(), manifest)
        return None

    def _check_unshadowed(self, folder: Path, direct: Package) -> None:
        """Refuse a package found directly in ``folder`` when another of its name lies below.

        Only for a folder whose ``package.xml`` gives the name looked up (a ROS package
        in a workspace, e.g. ``src/franka_description`` next to
        ``src/franka_ros/franka_description``): ROS refuses the pair, and taking the
        one directly in ``folder`` silently may read another version of the robot.
        Best effort: a folder that cannot be searched (past the budgets, a bad
        ``package.xml`` elsewhere) keeps the package found directly, as before.

        Raises:
            InputError: Another package of that name under ``folder`` (both named).
        """
        if direct.manifest is None or folder.absolute() in self._unsearchable:
            return
        try:
            if package_name(direct.manifest) != direct.name:
                return  # a folder named otherwise than its package (example-robot-data)
            found = self.packages_under(folder).get(direct.name, [])
        except (InputError, RobotLoadError):
            self._unsearchable.add(folder.absolute())
            return
        if any(package.folder != direct.folder for package in found):
            raise _duplicate_error(direct.name, folder, found)

    def package_folder(self, name: str) -> Path | None:
        """The folder of the package ``name`` (symlinks resolved), or None; see :meth:`find`."""
        package = self.find(name)
        return None if package is None else package.folder

    def packages_under(self, folder: Path) -> dict[str, list[Package]]:
        """Every package under ``folder`` by name (searched once, then remembered).

        Raises:
            InputError: The search goes past :data:`MAX_PACKAGE_DEPTH` or
                :data:`MAX_FOLDERS_VISITED`.
            RobotLoadError: A ``package.xml`` is not strict XML or has no name.
        """
        key = folder.absolute()
        if key not in self._searched:
            if key == Path(key.anchor):
                raise InputError(
                    "package_dirs",
                    "folders holding ROS packages (a workspace's src), not the filesystem "
                    "root; a single string given as package_dirs is read as one folder per "
                    "character: pass a list, package_dirs=['ws/src']",
                    str(folder),
                )
            found: dict[str, list[Package]] = {}
            for package in _search(folder):
                found.setdefault(package.name, []).append(package)
            self._searched[key] = found
        return self._searched[key]

    def packages(self) -> Iterator[Package]:
        """Every package under the given folders (not the environment's), each once."""
        seen: set[Path] = set()
        for folder in self.folders:
            for packages in self.packages_under(folder).values():
                for package in packages:
                    if package.folder not in seen:
                        seen.add(package.folder)
                        yield package


def package_dirs_of(package_dirs: Sequence[str | Path]) -> PackageDirs:
    """``package_dirs`` as a :class:`PackageDirs`: itself if it is one (its searches kept)."""
    return package_dirs if isinstance(package_dirs, PackageDirs) else PackageDirs(package_dirs)


def _duplicate_error(name: str, folder: Path, found: Sequence[Package]) -> InputError:
    """Two packages or more named ``name`` under ``folder``: each ``package.xml`` named."""
    return InputError(
        "package_dirs",
        f"one package named {name!r} under {folder}; found {len(found)}: "
        + ", ".join(str(p.manifest) for p in found)
        + " (put a COLCON_IGNORE file in the folder of the one not to use)",
    )


def _folder_in_words(folder: Path) -> str:
    """``folder``, followed by "(no such folder)" when it is not one."""
    try:
        return str(folder) if folder.is_dir() else f"{folder} (no such folder)"
    except OSError:  # no permission to look
        return f"{folder} (not readable)"


def _path_list(value: str) -> list[Path]:
    """The folders of a colon-separated path variable, empty entries left out."""
    return [Path(part) for part in value.split(os.pathsep) if part.strip()]


def _direct_package(folder: Path, name: str) -> Package | None:
    """``<folder>/<name>``, a package by its folder's name, as Pinocchio looks it up.

    None when there is no such folder, or when it holds no ``package.xml`` but a
    folder directly inside it is the package ``name`` (a repository named after the
    package it holds, e.g. ``moveit_resources/moveit_resources``: the search finds it).
    """
    candidate = folder / name
    try:
        if not candidate.is_dir():
            return None
    except OSError:  # no permission to look: not there, as for the search
        return None
    manifest = candidate / MANIFEST
    if _is_file(manifest):  # its name may differ (example-robot-data/: example_robot_data)
        return Package(name, candidate.resolve(), manifest)
    for sub in _subfolders(candidate):
        inner = sub / MANIFEST
        if not is_skipped(sub) and _is_file(inner) and package_name(inner) == name:
            return None
    return Package(name, candidate.resolve())


def _search(top: Path) -> Iterator[Package]:
    """The packages under ``top``, in sorted folder order, within the search budgets.

    Raises:
        InputError: Deeper than :data:`MAX_PACKAGE_DEPTH`, or more than
            :data:`MAX_FOLDERS_VISITED` folders.
    """
    try:
        if not top.is_dir() or any((top / marker).exists() for marker in IGNORE_MARKERS):
            return
    except OSError:  # no permission to look into it
        return
    todo: list[tuple[Path, int]] = [(top, 0)]
    visited = 0
    while todo:
        folder, depth = todo.pop()
        visited += 1
        if visited > MAX_FOLDERS_VISITED:
            raise InputError(
                "package_dirs",
                f"a folder of at most {MAX_FOLDERS_VISITED} folders to search for packages "
                f"(MAX_FOLDERS_VISITED); {top} holds more: pass a narrower folder (e.g. a "
                "workspace's src) or put a COLCON_IGNORE file in the folders not to search",
            )
        manifest = folder / MANIFEST
        if _is_file(manifest):
            yield Package(package_name(manifest), folder.resolve(), manifest)
            continue  # a package: not entered
        below = [sub for sub in _subfolders(folder) if not is_skipped(sub)]
        if below and depth + 1 > MAX_PACKAGE_DEPTH:
            raise InputError(
                "package_dirs",
                f"packages at most {MAX_PACKAGE_DEPTH} folders below {top} "
                f"(MAX_PACKAGE_DEPTH); {below[0]} is deeper: pass a folder nearer the "
                "packages or put a COLCON_IGNORE file in the folders not to search",
            )
        todo.extend((sub, depth + 1) for sub in reversed(below))


def _is_file(path: Path) -> bool:
    """Whether ``path`` is a file; False when it cannot be looked at (no permission)."""
    try:
        return path.is_file()
    except OSError:
        return False


def _subfolders(folder: Path) -> list[Path]:
    """The folders directly inside ``folder``, sorted; symbolic links left out."""
    try:
        with os.scandir(folder) as entries:
            return sorted(
                Path(entry.path) for entry in entries if entry.is_dir(follow_symlinks=False)
            )
    except OSError:  # unreadable: skipped, as colcon does
        return []
