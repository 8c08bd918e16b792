"""clik.ros.messages: each ROS message read and checked (no ROS needed: duck-typed)."""

from __future__ import annotations

from types import SimpleNamespace as NS

import numpy as np
import pinocchio as pin
import pytest

from clik.errors import InputError
from clik.ros import messages
from clik.scenarios.ros_table import RosSettings, ros_table
from clik.schema import Table

WORLD = "world"


def _header(frame: str = WORLD) -> NS:
    return NS(frame_id=frame, stamp=NS(sec=1, nanosec=2))


def _pose(p: list[float], q: list[float], frame: str = WORLD) -> NS:
    position = NS(x=p[0], y=p[1], z=p[2])
    orientation = NS(x=q[0], y=q[1], z=q[2], w=q[3])
    return NS(header=_header(frame), pose=NS(position=position, orientation=orientation))


def _placements(name: str) -> pin.SE3 | None:
    return (
        pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, np.pi / 2), np.array([1.0, 0.0, 0.0]))
        if name == "tool"
        else None
    )


def test_a_pose_in_the_world_and_in_a_robot_frame() -> None:
    half = [0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)]
    m = messages.pose(_pose([0.1, 0.2, 0.3], half), "/t", WORLD, _placements)
    assert np.allclose(m[:3, 3], [0.1, 0.2, 0.3])
    assert np.allclose(m[:3, :3], pin.rpy.rpyToMatrix(0.0, 0.0, np.pi / 2))
    local = messages.pose(_pose([0.1, 0.0, 0.0], [0, 0, 0, 1], "tool"), "/t", WORLD, _placements)
    assert np.allclose(local[:3, 3], [1.0, 0.1, 0.0])  # the tool's x is the world's y


def test_bad_poses_are_refused_by_field() -> None:
    with pytest.raises(InputError, match=r"/t: pose\.orientation.*unit quaternion"):
        messages.pose(_pose([0, 0, 0], [0, 0, 0, 0.5]), "/t", WORLD, _placements)
    with pytest.raises(InputError, match=r"/t: pose\.position.*finite"):
        messages.pose(_pose([np.nan, 0, 0], [0, 0, 0, 1]), "/t", WORLD, _placements)
    with pytest.raises(InputError, match=r"/t: header\.frame_id.*'elbow'"):
        messages.pose(_pose([0, 0, 0], [0, 0, 0, 1], "elbow"), "/t", WORLD, _placements)


def test_points_and_twists() -> None:
    point = NS(header=_header("tool"), point=NS(x=0.0, y=0.5, z=0.0))
    assert np.allclose(messages.point(point, "/p", WORLD, _placements), [0.5, 0.0, 0.0])
    twist = NS(
        header=_header("tool"),
        twist=NS(linear=NS(x=1.0, y=0.0, z=0.0), angular=NS(x=0.0, y=0.0, z=2.0)),
    )
    assert np.allclose(messages.twist(twist, "/w", WORLD, _placements), [0, 1, 0, 0, 0, 2])
    twist.twist.linear.x = float("inf")
    with pytest.raises(InputError, match=r"/w: twist\.linear"):
        messages.twist(twist, "/w", WORLD, _placements)


def test_joint_states_by_name() -> None:
    joints = {"a": 0, "b": 1}
    msg = NS(name=["b", "finger", "a"], position=[2.0, 9.0, 1.0])
    assert np.allclose(messages.joint_values(msg, "/js", joints, {"finger"}), [1.0, 2.0])
    with pytest.raises(InputError, match=r"/js: name.*joints of the robot.*'x'"):
        messages.joint_values(NS(name=["a", "b", "x"], position=[1, 2, 3]), "/js", joints, set())
    with pytest.raises(InputError, match=r"/js: name.*missing b"):
        messages.joint_values(NS(name=["a"], position=[1.0]), "/js", joints, set())
    with pytest.raises(InputError, match=r"/js: position.*one value per name"):
        messages.joint_values(NS(name=["a", "b"], position=[1.0]), "/js", joints, set())
    with pytest.raises(InputError, match=r"/js: position.*finite"):
        messages.joint_values(NS(name=["a", "b"], position=[1.0, np.nan]), "/js", joints, set())


def test_the_ros_table() -> None:
    values = ros_table(Table({"output": "velocity", "timeout": 0.1}, "s.toml", "ros"))
    s = RosSettings(**values)
    assert s.output_topic == "/forward_velocity_controller/commands"
    assert s.target_topic("hand") == "/clik/hand/target" and s.timeout == 0.1
    for bad, key in (({"output": "torque"}, "output"), ({"prefix": "clik"}, "prefix"),
                     ({"timeout": 0}, "timeout"), ({"rate": -1}, "rate"),
                     ({"topics": 1}, "topics")):  # fmt: skip
        with pytest.raises(Exception, match=key):
            ros_table(Table(bad, "s.toml", "ros"))
