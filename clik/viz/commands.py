"""Meshcat's viewer protocol: commands and three.js objects as plain dicts.

The viewer (``meshcat/viewer/dist/main.min.js``) decodes one msgpack map per
command and hands it to ``Viewer.handle_command``. The maps built here are the
ones ``meshcat.commands`` would lower to, written directly so that clik can use
typed arrays (``Float32Array``, ``Uint16Array``) for meshes and animation
tracks, column-major matrices everywhere, and materials with options that
``meshcat.geometry`` does not expose (transparency without depth writes, flat
shading). A path names a node of the viewer's scene tree, e.g.
``/meshcat/robot/joint1``; a node's object sits in its ``<object>`` child.
"""

from __future__ import annotations

import uuid as _uuid
from collections.abc import Sequence
from typing import Any

import numpy as np
import umsgpack  # type: ignore[import-untyped]  # u-msgpack-python ships no type hints

Command = dict[str, Any]
"""One viewer command: a map with ``type`` and ``path`` keys."""

_TYPED_ARRAYS = {
    np.dtype(np.float32): ("Float32Array", 0x17),
    np.dtype(np.uint16): ("Uint16Array", 0x14),
    np.dtype(np.uint32): ("Uint32Array", 0x16),
}
"""numpy dtype -> (JavaScript typed array, msgpack-lite extension code)."""

INTERPOLATE_DISCRETE = 2300
"""three.js ``InterpolateDiscrete``: a track holds each key's value until the next key."""


def typed_array(array: np.ndarray, dtype: type[np.generic] = np.float32) -> umsgpack.Ext:
    """A numpy array as a msgpack extension the viewer decodes into a JavaScript typed array.

    Args:
        array: Values, any shape (flattened in C order).
        dtype: ``np.float32``, ``np.uint16`` or ``np.uint32``.

    Returns:
        The extension object.
    """
    data: np.ndarray = np.ascontiguousarray(array, dtype=dtype).reshape(-1)
    _, code = _TYPED_ARRAYS[np.dtype(dtype)]
    return umsgpack.Ext(code, data.astype(data.dtype.newbyteorder("<")).tobytes())


def buffer_attribute(array: np.ndarray, dtype: type[np.generic] = np.float32) -> dict[str, Any]:
    """A three.js ``BufferAttribute``: ``array`` is (count, item_size) or (count,)."""
    array = np.asarray(array)
    name, _ = _TYPED_ARRAYS[np.dtype(dtype)]
    item_size = 1 if array.ndim == 1 else array.shape[1]
    return {
        "itemSize": item_size,
        "type": name,
        "array": typed_array(array, dtype),
        "normalized": False,
    }


def new_uuid() -> str:
    """A fresh identifier for a three.js geometry, material or object."""
    return str(_uuid.uuid4())


def color_int(rgb: Sequence[float]) -> int:
    """An RGB triple in [0, 1] as the 0xRRGGBB integer three.js uses."""
    r, g, b = (round(255 * min(max(float(c), 0.0), 1.0)) for c in rgb[:3])
    return (r << 16) | (g << 8) | b


def column_major(matrix: np.ndarray) -> list[float]:
    """A 4x4 homogeneous matrix in three.js's (column-major) order."""
    return [float(v) for v in np.asarray(matrix, dtype=float).reshape(4, 4).T.reshape(-1)]


def phong_material(
    rgb: Sequence[float], opacity: float = 1.0, flat: bool = False, double_sided: bool = False
) -> dict[str, Any]:
    """A lit material; translucent (and not hiding what is behind it) when ``opacity < 1``."""
    material: dict[str, Any] = {
        "uuid": new_uuid(),
        "type": "MeshPhongMaterial",
        "color": color_int(rgb),
        "shininess": 30,
        "flatShading": flat,
        "side": 2 if double_sided else 0,
    }
    if opacity < 1.0:
        material.update(transparent=True, opacity=float(opacity), depthWrite=False)
    return material


def line_material(rgb: Sequence[float]) -> dict[str, Any]:
    """An unlit line material (WebGL draws lines one pixel wide)."""
    return {"uuid": new_uuid(), "type": "LineBasicMaterial", "color": color_int(rgb)}


def scene_object(
    kind: str,
    geometry: dict[str, Any],
    material: dict[str, Any],
    matrix: np.ndarray | None = None,
    name: str = "",
) -> dict[str, Any]:
    """A three.js JSON object (``Mesh``, ``Line``, ``LineSegments``) with its geometry.

    Args:
        kind: three.js object type.
        geometry: Geometry JSON (with a ``uuid``).
        material: Material JSON (with a ``uuid``).
        matrix: The object's transform in its node, 4x4 (default identity).
        name: Object name (shown nowhere; kept for debugging).
    """
    obj: dict[str, Any] = {
        "uuid": new_uuid(),
        "type": kind,
        "name": name,
        "geometry": geometry["uuid"],
        "material": material["uuid"],
        "matrix": column_major(np.eye(4) if matrix is None else matrix),
    }
    return {
        "metadata": {"version": 4.5, "type": "Object"},
        "geometries": [geometry],
        "materials": [material],
        "object": obj,
    }


def set_object(path: str, obj: dict[str, Any]) -> Command:
    """Put ``obj`` (see :func:`scene_object`) at ``path``, replacing what was there."""
    return {"type": "set_object", "path": path, "object": obj}


def set_transform(path: str, matrix: np.ndarray) -> Command:
    """Place the node ``path`` in its parent (4x4 homogeneous matrix)."""
    return {"type": "set_transform", "path": path, "matrix": column_major(matrix)}


def set_property(path: str, key: str, value: Any) -> Command:
    """Set a property of the node's object (``visible``, ``position``, ``top_color``...)."""
    return {"type": "set_property", "path": path, "property": key, "value": value}


def delete(path: str) -> Command:
    """Remove the node ``path`` and its children."""
    return {"type": "delete", "path": path}


def track(
    name: str,
    kind: str,
    times: np.ndarray,
    values: np.ndarray | list[Any],
    discrete: bool = False,
) -> dict[str, Any]:
    """One three.js keyframe track.

    Args:
        name: Property binding, relative to the animated node: ``.position``,
            ``.quaternion`` (x, y, z, w), ``.scale``, ``.visible``, ``.material.color``.
        kind: ``vector3``, ``quaternion``, ``color`` or ``bool``.
        times: Key times (K,) [s].
        values: Key values, (K, item) numbers or a list of K booleans.
        discrete: Hold each value until the next key instead of interpolating.
    """
    packed: Any
    if kind == "bool":
        packed = [bool(v) for v in values]
    else:
        packed = typed_array(np.asarray(values, dtype=float))
    out: dict[str, Any] = {
        "name": name,
        "type": kind,
        "times": typed_array(times),
        "values": packed,
    }
    if discrete:
        out["interpolation"] = INTERPOLATE_DISCRETE
    return out


def set_animation(
    clips: dict[str, list[dict[str, Any]]], play: bool = True, repetitions: int = 1_000_000
) -> Command:
    """Load an animation: for each node path, the tracks that drive it.

    Key times are in seconds (the clips' ``fps`` is 1). ``repetitions=0`` is not
    used: with meshcat 0.3.2 it plays once and then shows a broken pose, so the
    animation loops a large number of times instead.
    """
    animations = [
        {"path": path, "clip": {"fps": 1, "name": "default", "tracks": tracks}}
        for path, tracks in clips.items()
        if tracks
    ]
    return {
        "type": "set_animation",
        "path": "",
        "animations": animations,
        "options": {"play": play, "repetitions": int(repetitions)},
    }


def pack(command: Command) -> bytes:
    """The bytes the viewer's ``handle_command_bytearray`` expects."""
    return umsgpack.packb(command)
