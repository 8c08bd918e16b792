"""Point clouds from files: an ``(N, 3)`` ``.npy``, a PLY file or a PCD file, within budgets.

Every reader returns a :class:`CloudPoints`: the finite points [m] in the file's frame, and
how many points were dropped for a NaN or an infinite coordinate (depth cameras write
NaN where they saw nothing). A file above :data:`MAX_CLOUD_BYTES` or holding more than
:data:`MAX_CLOUD_POINTS` points, a malformed header, or points without ``x``, ``y``,
``z`` is an :class:`~clik.errors.InputError` naming the file and, for a header, the line.

- ``.npy``: a float array of shape ``(N, 3)`` (no pickles).
- ``.ply``: the ``vertex`` element's ``x``, ``y``, ``z`` (ASCII or binary), read with
  ``plyfile``.
- ``.pcd`` (Point Cloud Library): the header (``FIELDS``, ``SIZE``, ``TYPE``,
  ``COUNT``, ``WIDTH``, ``HEIGHT``, ``POINTS``, ``DATA``), then ``ascii`` or ``binary``
  data; ``binary_compressed`` is refused (save it as ``binary``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from clik.errors import InputError

MAX_CLOUD_BYTES = 512 * 1024 * 1024
"""Largest cloud file read [bytes]."""

MAX_CLOUD_POINTS = 10_000_000
"""Most points a cloud file may hold."""

PCD_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT")
PCD_TYPES = {
    (kind, size): f"{kind.lower() if kind != 'U' else 'u'}{size}"
    for kind, sizes in (("F", (4, 8)), ("I", (1, 2, 4, 8)), ("U", (1, 2, 4, 8)))
    for size in sizes
}
"""PCD ``TYPE`` and ``SIZE`` to numpy's little-endian type codes."""


@dataclass(frozen=True)
class CloudPoints:
    """Points read from a file.

    Attributes:
        points: ``(N, 3)`` finite points [m], in the file's frame.
        dropped: Points left out for a NaN or an infinite coordinate.
        source: The file.
    """

    points: np.ndarray
    dropped: int
    source: str


def read_cloud(path: str | Path) -> CloudPoints:
    """The finite points of a ``.npy``, ``.ply`` or ``.pcd`` file.

    Raises:
        InputError: Not such a file, above the budgets, a malformed header (naming its
            line), no ``x``, ``y``, ``z``.
    """
    path = Path(path)
    readers = {".npy": _read_npy, ".ply": _read_ply, ".pcd": _read_pcd}
    suffix = path.suffix.lower()
    if suffix not in readers:
        raise InputError(str(path), "a point cloud file ending .npy, .ply or .pcd", path.name)
    if not path.is_file():
        raise InputError(str(path), "an existing point cloud file", "no such file")
    size = os.stat(path).st_size
    if size > MAX_CLOUD_BYTES:
        raise InputError(str(path), f"a file of at most {MAX_CLOUD_BYTES} bytes", size)
    return finite_points(readers[suffix](path), str(path))


def finite_points(xyz: np.ndarray, source: str) -> CloudPoints:
    """The rows without a NaN or an infinity, and how many were dropped."""
    if len(xyz) > MAX_CLOUD_POINTS:
        raise InputError(source, f"at most {MAX_CLOUD_POINTS} points", len(xyz))
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    keep = np.all(np.isfinite(xyz), axis=1)
    points = np.ascontiguousarray(xyz[keep])
    points.flags.writeable = False
    return CloudPoints(points, int(len(xyz) - int(keep.sum())), source)


def _read_npy(path: Path) -> np.ndarray:
    try:
        array = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as error:
        raise InputError(
            str(path), "a .npy array of shape (N, 3) (no pickles)", str(error)
        ) from None
    if array.ndim != 2 or array.shape[1] != 3 or not np.issubdtype(array.dtype, np.number):
        raise InputError(str(path), "a numeric .npy array of shape (N, 3)", array.shape)
    return array


def _read_ply(path: Path) -> np.ndarray:
    try:
        from plyfile import PlyData, PlyHeaderParseError
    except ImportError:
        raise InputError(
            str(path), "the plyfile package to read PLY (pip install plyfile)"
        ) from None
    try:
        data = PlyData.read(str(path))
    except PlyHeaderParseError as error:
        where = f"{path}, line {error.line}" if getattr(error, "line", None) else str(path)
        raise InputError(where, "a PLY header", error.message) from None
    except (ValueError, OSError, EOFError) as error:
        raise InputError(str(path), "a PLY file", str(error)) from None
    names = [e.name for e in data.elements]
    if "vertex" not in names:
        raise InputError(str(path), "a PLY 'vertex' element", names)
    vertex = data["vertex"].data
    missing = [a for a in "xyz" if a not in (vertex.dtype.names or ())]
    if missing:
        raise InputError(str(path), "vertex properties x, y, z", vertex.dtype.names)
    return np.stack([vertex[a] for a in "xyz"], axis=1)


def _read_pcd(path: Path) -> np.ndarray:
    with open(path, "rb") as file:
        header, line = _pcd_header(file, path)
        dtype, count = _pcd_dtype(header, path, line)
        kind = header["DATA"][0].lower()
        if kind == "ascii":
            width = sum(int(np.prod(dtype[n].shape)) or 1 for n in dtype.names or ())
            text = file.read().decode("ascii", errors="replace").split()
            try:
                values = np.array(text[: count * width], dtype=float)
            except ValueError:
                raise InputError(str(path), "numbers in the ascii data") from None
            if values.size != count * width:
                raise InputError(str(path), f"{count} points of ascii data", values.size)
            return values.reshape(count, width)[:, _xyz_columns(dtype)]
        if kind != "binary":
            raise InputError(
                f"{path}, line {line}", "DATA ascii or binary (save it as binary)", kind
            )
        raw = file.read(count * dtype.itemsize)
    if len(raw) != count * dtype.itemsize:
        raise InputError(str(path), f"{count} points of binary data", f"{len(raw)} bytes")
    records = np.frombuffer(raw, dtype=dtype, count=count)
    return np.stack([records[a].astype(float) for a in "xyz"], axis=1)


def _xyz_columns(dtype: np.dtype) -> list[int]:
    """The columns of ``x``, ``y``, ``z`` in a row of ascii values."""
    offsets, at = {}, 0
    for name in dtype.names or ():
        offsets[name] = at
        at += int(np.prod(dtype[name].shape)) or 1
    return [offsets[a] for a in "xyz"]


def _pcd_header(file: object, path: Path) -> tuple[dict[str, list[str]], int]:
    """The header's keys and the line of its ``DATA`` key (1-based)."""
    header: dict[str, list[str]] = {}
    for number in range(1, 100):
        raw = file.readline()  # type: ignore[attr-defined]
        if not raw:
            break
        text = raw.decode("ascii", errors="replace").strip()
        if not text or text.startswith("#"):
            continue
        key, *values = text.split()
        if key not in (*PCD_KEYS, "POINTS", "DATA"):
            raise InputError(f"{path}, line {number}", "a PCD header key", key[:40])
        header[key] = values
        if key == "DATA":
            return header, number
    raise InputError(str(path), "a PCD header ending with DATA", "none in 100 lines")


def _pcd_dtype(header: dict[str, list[str]], path: Path, line: int) -> tuple[np.dtype, int]:
    """The record type of the header's fields, and the number of points."""
    fields = header.get("FIELDS", [])
    sizes, types = header.get("SIZE", []), header.get("TYPE", [])
    counts = header.get("COUNT", ["1"] * len(fields))
    if not fields or not len(fields) == len(sizes) == len(types) == len(counts):
        raise InputError(str(path), "FIELDS, SIZE, TYPE (and COUNT) of one length each")
    missing = [a for a in "xyz" if a not in fields]
    if missing:
        raise InputError(str(path), "FIELDS with x, y, z", fields)
    columns = []
    for name, size, kind, n in zip(fields, sizes, types, counts, strict=True):
        code = PCD_TYPES.get((kind, int(size)) if size.isdigit() else (kind, 0))
        if code is None or not n.isdigit():
            raise InputError(str(path), "a PCD TYPE/SIZE/COUNT", (name, kind, size, n))
        shape = (int(n),) if n != "1" else ()
        columns.append((name, "<" + code, shape))
    points = header.get("POINTS", [""])[0]
    if not points.isdigit():
        raise InputError(f"{path}, line {line}", "POINTS with a count before DATA", points)
    if int(points) > MAX_CLOUD_POINTS:
        raise InputError(str(path), f"at most {MAX_CLOUD_POINTS} points", int(points))
    return np.dtype([(n, t, s) if s else (n, t) for n, t, s in columns]), int(points)
