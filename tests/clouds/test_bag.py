"""PointCloud2 in a rosbag2 (MCAP) folder, written with rosbags, read back as points."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from clik.errors import InputError

rosbags = pytest.importorskip(
    "rosbags", reason="rosbags is not installed (pip install 'clik[ros]')"
)

from clik.clouds.bag import read_bag_cloud  # noqa: E402


def write_bag(folder: Path, clouds: list[np.ndarray], padding: int = 4) -> Path:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    msgs = store.types
    PointCloud2, PointField = (
        msgs["sensor_msgs/msg/PointCloud2"],
        msgs["sensor_msgs/msg/PointField"],
    )
    Header, Time = msgs["std_msgs/msg/Header"], msgs["builtin_interfaces/msg/Time"]
    bag = folder / "scan_bag"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection(
            "/camera/points", PointCloud2.__msgtype__, typestore=store
        )
        for k, points in enumerate(clouds):
            step = 12 + padding  # x, y, z float32 then an unread field's bytes
            rows = np.zeros((len(points), step), dtype=np.uint8)
            rows[:, :12] = points.astype("<f4").view(np.uint8).reshape(len(points), 12)
            fields = [
                PointField(name=a, offset=4 * i, datatype=7, count=1) for i, a in enumerate("xyz")
            ]
            message = PointCloud2(
                header=Header(stamp=Time(sec=k, nanosec=0), frame_id="camera_optical"),
                height=1, width=len(points), fields=fields, is_bigendian=False,
                point_step=step, row_step=step * len(points), data=rows.reshape(-1),
                is_dense=False,
            )  # fmt: skip
            writer.write(
                connection, k * 1_000_000_000, store.serialize_cdr(message, PointCloud2.__msgtype__)
            )
    return bag


def test_the_last_cloud_of_the_topic_comes_back(tmp_path: Path) -> None:
    first = np.array([[0.0, 0.0, 1.0]])
    last = np.array([[0.5, -0.25, 2.0], [np.nan, 0.0, 0.0], [1.0, 1.0, 1.0]])
    bag = write_bag(tmp_path, [first, last])
    points, frame = read_bag_cloud(bag)
    assert frame == "camera_optical"
    np.testing.assert_allclose(points, last.astype(np.float32), equal_nan=True)
    np.testing.assert_allclose(read_bag_cloud(bag, "/camera/points", index=0)[0], first)


def test_a_wrong_topic_or_folder_is_named(tmp_path: Path) -> None:
    bag = write_bag(tmp_path, [np.zeros((2, 3))])
    with pytest.raises(InputError, match="one PointCloud2 topic"):
        read_bag_cloud(bag, "/other")
    with pytest.raises(InputError, match="index"):
        read_bag_cloud(bag, index=3)
    with pytest.raises(InputError, match="a rosbag2 folder"):
        read_bag_cloud(tmp_path / "nothing")


def test_a_bag_cloud_is_a_cloud_obstacle_placed_by_its_frame(tmp_path: Path) -> None:
    from clik.clouds import CloudObstacle

    last = np.array([[0.5, -0.25, 2.0], [np.nan, 0.0, 0.0], [1.0, 1.0, 1.0]])
    bag = write_bag(tmp_path, [last])
    cloud = CloudObstacle.from_bag("scan", str(bag), voxel=0.0, position=(1.0, 0.0, 0.0))
    assert cloud.dropped == 1 and "camera_optical" in cloud.source
    np.testing.assert_allclose(cloud.world, [[1.5, -0.25, 2.0], [2.0, 1.0, 1.0]], atol=1e-6)
