"""Points from ``sensor_msgs/PointCloud2`` messages in a rosbag2 folder (MCAP or SQLite).

Read with ``rosbags`` (the ``ros`` extra: no ROS install). A message's ``x``, ``y``,
``z`` fields (``FLOAT32`` or ``FLOAT64``, either byte order) are read at their offsets in
each point of ``point_step`` bytes, row by row (``row_step`` may pad rows). The points
are in the message's ``header.frame_id``; :func:`read_bag_cloud` returns that frame's
name with them, the caller places the cloud.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from clik.errors import InputError

FLOAT_TYPES = {7: "f4", 8: "f8"}
"""``sensor_msgs/PointField`` datatypes read (``FLOAT32``, ``FLOAT64``)."""

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"


def cloud2_points(message: Any, where: str = "PointCloud2") -> np.ndarray:
    """The ``(N, 3)`` points of a ``PointCloud2`` message (NaNs kept: the caller drops them).

    Raises:
        InputError: No float ``x``, ``y``, ``z`` fields, or data shorter than its
            ``height``, ``row_step`` say.
    """
    fields = {f.name: f for f in message.fields}
    order = ">" if message.is_bigendian else "<"
    columns = []
    for axis in "xyz":
        field = fields.get(axis)
        if field is None or field.datatype not in FLOAT_TYPES or field.count != 1:
            raise InputError(where, "float32 or float64 fields x, y, z", sorted(fields))
        columns.append((axis, order + FLOAT_TYPES[field.datatype], field.offset))
    dtype = np.dtype(
        {
            "names": [c[0] for c in columns],
            "formats": [c[1] for c in columns],
            "offsets": [c[2] for c in columns],
            "itemsize": int(message.point_step),
        }
    )
    data = np.asarray(message.data, dtype=np.uint8)
    height, width, row = int(message.height), int(message.width), int(message.row_step)
    if row < width * dtype.itemsize or data.size < height * row:
        raise InputError(where, f"{height} rows of {row} bytes of data", data.size)
    rows = data[: height * row].reshape(height, row)[:, : width * dtype.itemsize]
    records = np.ascontiguousarray(rows).view(dtype).reshape(-1)
    return np.column_stack([records[a].astype(float) for a in "xyz"])


def read_bag_cloud(
    folder: str | Path, topic: str | None = None, index: int = -1
) -> tuple[np.ndarray, str]:
    """One ``PointCloud2`` message's points from a rosbag2 folder, and their frame.

    Args:
        folder: The bag's folder (its ``metadata.yaml`` and storage files).
        topic: The topic; default the bag's only ``PointCloud2`` topic.
        index: Which message of the topic (default the last).

    Raises:
        InputError: ``rosbags`` missing, not a bag, no such topic or message.
    """
    try:
        from rosbags.rosbag2 import Reader, ReaderError
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise InputError(str(folder), "rosbags to read a bag (pip install 'clik[ros]')") from None
    store = get_typestore(Stores.ROS2_JAZZY)
    try:
        with Reader(Path(folder)) as reader:
            clouds = [c for c in reader.connections if c.msgtype == POINTCLOUD2]
            chosen = [c for c in clouds if topic is None or c.topic == topic]
            if len(chosen) != 1:
                raise InputError(str(folder), "one PointCloud2 topic (give topic=)",
                                 sorted(c.topic for c in clouds))  # fmt: skip
            raws = [raw for _, _, raw in reader.messages(connections=chosen)]
    except (OSError, ValueError, KeyError, ReaderError) as error:
        raise InputError(str(folder), "a rosbag2 folder", str(error)) from None
    if not raws or not -len(raws) <= index < len(raws):
        raise InputError("index", f"a message index among {len(raws)}", index)
    message: Any = store.deserialize_cdr(raws[index], POINTCLOUD2)
    return cloud2_points(message, f"{folder}: {chosen[0].topic}"), str(message.header.frame_id)
