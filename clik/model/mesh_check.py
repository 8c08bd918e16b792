"""Cheap checks on a mesh file before any mesh loader reads it.

Mesh files (a URDF's link meshes, a scenario's obstacle meshes) are read by
assimp through coal. assimp follows side files a mesh names (an OBJ's
``mtllib``, a glTF's buffers), blocks on a FIFO and takes minutes and gigabytes
on a 100 MB mesh. :func:`check_mesh_file` looks at the file before that: it must be
a regular file (``os.stat``, never opened when it is not), of a format clik
reads (:data:`MESH_FORMATS`), within :data:`MAX_MESH_BYTES`, with vertex and
face counts read cheaply from the file (binary STL header, OBJ ``v``/``f``
lines, PLY header) within :data:`MAX_MESH_ELEMENTS`, and with its vertices
(binary STL: read from the file; else after loading, see
:func:`vertex_problem`) within :data:`MAX_COORDINATE` once scaled.

Side files: an OBJ's ``mtllib`` names are returned (:attr:`MeshFacts.side_files`)
so the caller either checks they stay inside its folder (URDF meshes) or hands
the loader a copy without them (:func:`sanitized_obj`, obstacle meshes).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clik.bounds import MAX_COORDINATE, SCALE_RANGE

MESH_FORMATS = (".stl", ".obj", ".dae", ".ply")
"""Mesh file suffixes clik reads (any case); others (glTF, FBX, ...) may name side files."""

MAX_MESH_BYTES = 64 * 2**20
"""Largest mesh file read [bytes] (64 MiB; example-robot-data's largest is 28 MB)."""

MAX_MESH_ELEMENTS = 2_000_000
"""Most vertices, and most faces, a mesh file may declare."""

_MTLLIB = re.compile(rb"^[ \t]*mtllib[ \t]+(.*?)[ \t]*\r?$", re.MULTILINE)
_SIDE_LINE = re.compile(rb"^[ \t]*(mtllib|usemtl)\b.*$", re.MULTILINE)
_PLY_ELEMENT = re.compile(rb"^element[ \t]+(vertex|face)[ \t]+(\d+)", re.MULTILINE)
_STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


@dataclass(frozen=True)
class MeshFacts:
    """What the cheap checks learned about a mesh file.

    Attributes:
        path: The mesh file, symlinks resolved.
        kind: Its format suffix, lower case (``".stl"``, ``".obj"``, ...).
        side_files: Names an OBJ's ``mtllib`` lines give (empty for other formats).
    """

    path: Path
    kind: str
    side_files: tuple[str, ...] = ()


class MeshRefused(ValueError):
    """A mesh file fails a cheap check; the message is the problem in words."""


def regular_file_problem(path: Path) -> str | None:
    """Why ``path`` cannot be read as a file (``os.stat`` only, never opened), or None."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "no such file"
    except OSError as error:
        return f"cannot be examined ({error.strerror})"
    if stat.S_ISDIR(mode):
        return "is a folder, not a regular file"
    if not stat.S_ISREG(mode):
        return "is not a regular file (a FIFO, socket or device)"
    return None


def check_mesh_file(
    path: Path,
    scale: Sequence[float] | np.ndarray,
    root: Path | None = None,
    what: str = "mesh file",
) -> MeshFacts:
    """Check a mesh file cheaply, before anything loads it.

    Args:
        path: The mesh file.
        scale: Its scale factors (3,) (check them with :func:`check_scale` first).
        root: A folder the file must stay inside once symlinks are resolved
            (None: no such folder).
        what: How messages name the file before its path, e.g. ``"mesh file"``.

    Returns:
        What the checks learned.

    Raises:
        MeshRefused: The first problem, in words naming the file.
    """
    problem = regular_file_problem(path)
    if problem is not None:
        raise MeshRefused(f"{what} {path} {problem}")
    resolved = path.resolve()
    if root is not None and not resolved.is_relative_to(root.resolve()):
        raise MeshRefused(f"{what} {path} resolves to {resolved}, which leaves its folder {root}")
    kind = path.suffix.lower()
    if kind not in MESH_FORMATS:
        raise MeshRefused(
            f"{what} {path} has format {kind or '(no suffix)'!r}; clik reads "
            f"{', '.join(MESH_FORMATS)} (other formats may name side files)"
        )
    size = os.stat(resolved).st_size
    if size > MAX_MESH_BYTES:
        raise MeshRefused(
            f"{what} {path} has {size} bytes, above the budget of {MAX_MESH_BYTES} "
            "bytes (MAX_MESH_BYTES); decimate it"
        )
    with open(resolved, "rb") as file:  # a regular file of bounded size
        data = file.read()
    side = _count_elements(data, kind, scale, f"{what} {path}")
    return MeshFacts(resolved, kind, side)


def check_scale(scale: Sequence[float] | np.ndarray, what: str = "mesh file") -> None:
    """Refuse a scale factor that is not finite or whose magnitude leaves :data:`SCALE_RANGE`."""
    low, high = SCALE_RANGE
    values = [float(s) for s in scale]
    if len(values) != 3 or not all(low <= abs(s) <= high for s in values):
        raise MeshRefused(
            f"{what} scale {values} is out of range: each factor's magnitude must be "
            f"within [{low:g}, {high:g}]"
        )


def _count_elements(
    data: bytes, kind: str, scale: Sequence[float] | np.ndarray, what: str
) -> tuple[str, ...]:
    """Check the vertex and face counts a file declares; return an OBJ's side files."""
    counts: dict[str, int] = {}
    side: tuple[str, ...] = ()
    if kind == ".stl":
        faces = int.from_bytes(data[80:84], "little") if len(data) >= 84 else 0
        if len(data) == 84 + 50 * faces:  # binary STL; else ASCII ("solid ...")
            counts["faces"] = faces
            records = np.frombuffer(data, _STL_RECORD, count=faces, offset=84)
            _check_extent(records["vertices"].reshape(-1, 3), scale, what)
        else:
            counts["faces"] = data.count(b"facet")
    elif kind == ".obj":
        counts["vertices"] = data.count(b"\nv ") + data.startswith(b"v ")
        counts["faces"] = data.count(b"\nf ") + data.startswith(b"f ")
        side = tuple(m.decode("utf-8", "replace") for m in _MTLLIB.findall(data))
    elif kind == ".ply":
        header = data[: data.find(b"end_header")]
        counts.update({k.decode(): int(n) for k, n in _PLY_ELEMENT.findall(header)})
    for name, count in counts.items():
        if count > MAX_MESH_ELEMENTS:
            raise MeshRefused(
                f"{what} declares {count} {name}, above the budget of {MAX_MESH_ELEMENTS} "
                "(MAX_MESH_ELEMENTS); decimate it"
            )
    return side


def _check_extent(vertices: np.ndarray, scale: Sequence[float] | np.ndarray, what: str) -> None:
    problem = vertex_problem(vertices, scale)
    if problem is not None:
        raise MeshRefused(f"{what}: {problem}")


def vertex_problem(
    vertices: np.ndarray, scale: Sequence[float] | np.ndarray = (1.0, 1.0, 1.0)
) -> str | None:
    """Why these mesh vertices (n, 3), times ``scale``, are refused, or None.

    They must be finite and within :data:`MAX_COORDINATE` of the mesh origin.
    """
    if len(vertices) == 0:
        return None
    scaled = np.asarray(vertices, dtype=float) * np.abs(np.asarray(scale, dtype=float))
    with np.errstate(over="ignore", invalid="ignore"):
        extent = float(np.max(np.abs(scaled)))
    if not np.isfinite(extent):
        return "the mesh has non-finite vertices"
    if extent > MAX_COORDINATE:
        return (
            f"the scaled mesh reaches {extent:.6g} m from its origin, beyond "
            f"{MAX_COORDINATE:g} m (MAX_COORDINATE)"
        )
    return None


def sanitized_obj(data: bytes) -> bytes:
    """An OBJ file's bytes without its ``mtllib`` and ``usemtl`` lines (no side file named)."""
    return _SIDE_LINE.sub(b"", data)
