"""Where a robot is read from: a URDF or xacro path, one of clik's robots, or example-robot-data.

:meth:`Robot.load <clik.model.robot.Robot.load>` tries ``source`` in that order:
an existing file (or a name that looks like a path), a robot shipped in
``robots/`` (the package data ``clik.robots``), then an example-robot-data
loader, read without being instantiated.
"""

from __future__ import annotations

import importlib.resources
from dataclasses import dataclass
from os.path import join
from pathlib import Path
from typing import Protocol

from clik.errors import RobotLoadError, UnknownRobotError
from clik.model.xacro_expand import is_xacro


@dataclass(frozen=True)
class SourceFiles:
    """Where :meth:`Robot.load` reads a robot from.

    Attributes:
        name: The robot's name.
        urdf: The URDF file.
        package_dirs: Default folders for ``package://`` meshes.
        srdf: The SRDF file, or None.
        posture: Name of the SRDF's reference posture, or None.
    """

    name: str
    urdf: Path
    package_dirs: list[Path]
    srdf: Path | None = None
    posture: str | None = None


class ErdLoader(Protocol):
    """What clik reads of an example-robot-data loader class (never instantiated)."""

    path: str
    urdf_filename: str
    urdf_subpath: str
    srdf_filename: str
    srdf_subpath: str
    ref_posture: str
    model_path: str | None


def our_robots() -> dict[str, Path]:
    """Our shipped robots: ``robots/<name>.urdf`` and the MJCF models ``robots/<name>.xml``."""
    folder = importlib.resources.files("clik.robots")
    return {
        Path(entry.name).stem: Path(str(entry))
        for entry in folder.iterdir()
        if entry.name.endswith((".urdf", ".xml"))
    }


def erd_robots() -> dict[str, ErdLoader]:
    """example-robot-data's loader classes that describe a URDF."""
    try:
        from example_robot_data.robots_loader import ROBOTS
    except ImportError:  # the loaders are a separate package
        return {}
    return {name: loader for name, loader in ROBOTS.items() if loader.urdf_filename}


def available_robots() -> dict[str, str]:
    """Names :meth:`Robot.load` accepts, with where each model comes from."""
    names = {name: f"clik: {path.name}" for name, path in our_robots().items()}
    for name, loader in erd_robots().items():
        names.setdefault(name, f"example-robot-data: {loader.path}/{loader.urdf_filename}")
    return names


def source_files(source: str | Path) -> SourceFiles:
    """Files of ``source``: a URDF path, one of our robots, or an example-robot-data name.

    Raises:
        UnknownRobotError: ``source`` is neither a file nor a known name.
    """
    source_str = str(source)
    path = Path(source)
    if path.is_file() or path.suffix in (".urdf", ".xacro", ".xml") or "/" in source_str:
        name = Path(path.name.removesuffix(".xacro")).stem if is_xacro(path) else path.stem
        return SourceFiles(name, path, parent_dirs(path))
    ours = our_robots()
    if source_str in ours:
        return SourceFiles(source_str, ours[source_str], [ours[source_str].parent])
    if source_str in erd_robots():
        return erd_files(source_str)
    raise UnknownRobotError(source_str, available_robots())


def erd_files(name: str) -> SourceFiles:
    """URDF, package dirs, SRDF and reference posture of an example-robot-data robot.

    Reads the loader class's attributes without instantiating it (that would
    build a RobotWrapper with its meshes).

    Raises:
        RobotLoadError: example-robot-data does not have the URDF file.
    """
    from example_robot_data.robots_loader import getModelPath

    loader = erd_robots()[name]
    subpath = join(loader.path, loader.urdf_subpath, loader.urdf_filename)
    try:
        model_path = loader.model_path or getModelPath(subpath)
    except OSError:
        raise RobotLoadError(name, f"example-robot-data has no file {subpath}") from None
    srdf = None
    if loader.srdf_filename:
        srdf = Path(model_path, loader.path, loader.srdf_subpath, loader.srdf_filename)
    urdf = Path(model_path, subpath).resolve()
    package_dirs = [Path(model_path, "../..").resolve()]
    return SourceFiles(name, urdf, package_dirs, srdf, loader.ref_posture)


def parent_dirs(urdf: Path) -> list[Path]:
    """The URDF's folder and its two parents, without the filesystem root.

    A ``package://pkg/...`` URI is looked up as ``<dir>/pkg/...``: with the root
    among the folders, a URDF in a shallow folder could name any system file.
    """
    folders = [urdf.parent, urdf.parent.parent, urdf.parent.parent.parent]
    absolute = [folder.absolute() for folder in folders]
    kept = [f for f, a in zip(folders, absolute, strict=True) if a.parent != a]
    return list(dict.fromkeys(kept)) or [urdf.parent]
