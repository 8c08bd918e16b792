"""``clik solve --export rosbag``: a ROS 2 bag, read back with rosbags and checked.

Joint states and commands are compared with ``trajectory.npz``; the primary task's
target with the recorded ``reference_position``; every task's target with the
configurations read back from the bag itself (forward kinematics: the run tracked its
targets within its recorded task errors).
"""

from __future__ import annotations

import builtins
import json
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

pytest.importorskip(
    "rosbags", reason="rosbags is not installed (pip install 'clik[ros]'): no bag to read back"
)

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

import clik
from clik.cli import main
from clik.errors import ClikError, ExportError
from clik.outputs.result import TrackingResult
from clik.outputs.rosbag_export import (
    BAG_NAME,
    JOINT_STATES,
    JOINT_TRAJECTORY,
    RosbagsMissing,
    export_rosbag,
)

EXACT = 1e-12
"""Tolerance on positions, velocities and references read back (doubles in CDR) [SI]."""
STAMP = 1e-9
"""Tolerance on a time read back (integer nanoseconds) [s]."""
TRACKED = 1e-9
"""Added to a task's recorded max error when comparing its target with its frame [m, rad]."""

STORE = get_typestore(Stores.ROS2_JAZZY)


def solve(out: Path, scenario: str, *options: str) -> int:
    return main(["solve", scenario, "--out", str(out), "--quiet", *options])


def read_bag(bag: Path) -> dict[str, list[tuple[int, Any]]]:
    """Each topic's (bag time [ns], message), in bag order; checks one ``.mcap`` file."""
    assert sorted(p.suffix for p in bag.iterdir()) == [".mcap", ".yaml"]
    topics: dict[str, list[tuple[int, Any]]] = {}
    with Reader(bag) as reader:
        assert "storage_identifier: mcap" in (bag / "metadata.yaml").read_text()
        for connection, timestamp, raw in reader.messages():
            message = STORE.deserialize_cdr(raw, connection.msgtype)
            topics.setdefault(connection.topic, []).append((timestamp, message))
    return topics


def seconds(stamp: Any) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def record(out: Path) -> dict[str, Any]:
    with np.load(out / "trajectory.npz") as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays["meta"] = json.loads(str(arrays.pop("meta_json")))
    return arrays


def robot_of(rec: dict[str, Any]) -> clik.Robot:
    info = rec["meta"]["info"]
    with warnings.catch_warnings():  # the solve said them already (baxter's SRDF)
        warnings.simplefilter("ignore", clik.ClikWarning)
        return clik.Robot.load(info["robot_source"], lock=info["robot_lock"] or None)


def frames_of(description: str) -> list[str]:
    """The frames a task's description names (``pose of frame 'a' in frame 'b'``)."""
    return re.findall(r"frame '([^']+)'", description)


def rotation(q: Any) -> np.ndarray:
    return pin.Quaternion(q.w, q.x, q.y, q.z).toRotationMatrix()


def check_joint_topics(topics: dict, rec: dict[str, Any], keep: np.ndarray) -> None:
    """Joint states and commands against the record, at the kept samples."""
    t, q, qdot = rec["t"][keep], rec["q"][keep], rec["qdot"][keep]
    names = [str(n) for n in rec["velocity_names"]]
    states = topics[JOINT_STATES]
    assert len(states) == len(t)
    for k, (stamp, msg) in enumerate(states):
        assert msg.name == names
        assert stamp == round(t[k] * 1e9)
        assert abs(seconds(msg.header.stamp) - t[k]) <= STAMP
        np.testing.assert_allclose(msg.position, q[k], rtol=0, atol=EXACT)
        np.testing.assert_allclose(msg.velocity, qdot[k], rtol=0, atol=EXACT)
        assert len(msg.effort) == 0
    commands = topics[JOINT_TRAJECTORY]
    assert len(commands) == len(t) - 1
    for k, (stamp, msg) in enumerate(commands):
        assert stamp == round(t[k] * 1e9)
        assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)
        assert msg.joint_names == names and len(msg.points) == 1
        point = msg.points[0]
        np.testing.assert_allclose(point.positions, q[k + 1], rtol=0, atol=EXACT)
        np.testing.assert_allclose(point.velocities, qdot[k + 1], rtol=0, atol=EXACT)
        assert abs(seconds(point.time_from_start) - (t[k + 1] - t[k])) <= STAMP


@pytest.fixture(scope="module")
def panda_bag(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("panda") / "out"
    assert solve(out, "panda_circle", "--export", "rosbag") == 0
    return out


def test_panda_bag_holds_the_run(panda_bag):
    rec = record(panda_bag)
    topics = read_bag(panda_bag / BAG_NAME)
    assert sorted(topics) == sorted([JOINT_STATES, JOINT_TRAJECTORY, "/clik/task/target"])
    n = len(rec["t"])
    assert n > 100 and len(rec["velocity_names"]) == 7
    check_joint_topics(topics, rec, np.arange(n))

    robot = robot_of(rec)
    model, data = robot.model, robot.model.createData()
    hand = model.getFrameId(rec["meta"]["info"]["frame"])
    errors = rec["meta"]["task_errors"]["task"]
    targets = topics["/clik/task/target"]
    assert len(targets) == n
    for k, (stamp, msg) in enumerate(targets):
        assert type(msg).__msgtype__ == "geometry_msgs/msg/PoseStamped"
        assert msg.header.frame_id == "panda_link0"
        assert stamp == round(rec["t"][k] * 1e9)
        p = msg.pose.position
        np.testing.assert_allclose([p.x, p.y, p.z], rec["reference_position"][k], atol=EXACT)
        o = msg.pose.orientation
        assert abs(np.linalg.norm([o.x, o.y, o.z, o.w]) - 1) <= EXACT
        pin.framesForwardKinematics(model, data, rec["q"][k])
        placement = data.oMf[hand]
        angle = np.linalg.norm(pin.log3(rotation(o) @ placement.rotation.T))
        assert angle <= errors["max_orientation"] + TRACKED


def test_export_every_thins_every_topic(tmp_path):
    out = tmp_path / "out"
    assert solve(out, "panda_circle", "--export", "rosbag", "csv", "--export-every", "700") == 0
    rec = record(out)
    n = len(rec["t"])
    keep = np.append(np.arange(0, n, 700), n - 1) if (n - 1) % 700 else np.arange(0, n, 700)
    topics = read_bag(out / BAG_NAME)
    check_joint_topics(topics, rec, keep)
    assert len(topics["/clik/task/target"]) == len(keep)
    csv_rows = (out / "trajectory.csv").read_text().splitlines()
    assert len(csv_rows) - 1 == len(keep)


def test_several_tasks_each_get_a_target(tmp_path):
    out = tmp_path / "out"
    assert solve(out, "baxter_two_hands", "--export", "rosbag") == 0
    rec = record(out)
    topics = read_bag(out / BAG_NAME)
    tasks = rec["meta"]["task_errors"]
    with_target = [n for n, e in tasks.items() if e["kind"] in ("pose", "position")]
    assert len(with_target) == 3 and "posture" in tasks
    assert sorted(topics) == sorted(
        [JOINT_STATES, JOINT_TRAJECTORY, *(f"/clik/{n}/target" for n in with_target)]
    )
    n = len(rec["t"])
    check_joint_topics(topics, rec, np.arange(n))

    robot = robot_of(rec)
    model, data = robot.model, robot.model.createData()
    primary = rec["meta"]["info"]["tasks"][0]
    for name in with_target:
        frames = frames_of(tasks[name]["task"])
        ids = [model.getFrameId(f) for f in frames]
        messages = topics[f"/clik/{name}/target"]
        assert len(messages) == n
        for k, (stamp, msg) in enumerate(messages):
            assert stamp == round(rec["t"][k] * 1e9)
            pin.framesForwardKinematics(model, data, rec["q"][k])
            placement = data.oMf[ids[0]]
            if len(frames) == 2:  # relative: A's placement in B, B its frame id
                assert msg.header.frame_id == frames[1]
                placement = data.oMf[ids[1]].actInv(placement)
            else:
                assert msg.header.frame_id == "base"
            if tasks[name]["kind"] == "pose":
                p, o = msg.pose.position, msg.pose.orientation
                angle = np.linalg.norm(pin.log3(rotation(o) @ placement.rotation.T))
                assert angle <= tasks[name]["max_orientation"] + TRACKED
            else:
                p = msg.point
            xyz = np.array([p.x, p.y, p.z])
            assert np.linalg.norm(xyz - placement.translation) <= tasks[name]["max"] + TRACKED
            if name == primary:
                np.testing.assert_allclose(xyz, rec["reference_position"][k], atol=EXACT)


def test_without_rosbags_solve_says_how_to_get_it(tmp_path, monkeypatch, capsys):
    real_import = builtins.__import__

    def no_rosbags(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "rosbags" or name.startswith("rosbags."):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_rosbags)
    out = tmp_path / "out"
    assert solve(out, "panda_circle", "--export", "csv", "rosbag") == 2
    err = capsys.readouterr().err
    assert "rosbags" in err and "pip install 'clik[ros]'" in err
    assert not out.exists()  # refused before the run and before the folder
    result = TrackingResult.load(_any_record(tmp_path))
    with pytest.raises(RosbagsMissing, match=r"pip install 'clik\[ros\]'") as info:
        export_rosbag(result, tmp_path / "api", robot=clik.Robot.load("planar4r"))
    assert isinstance(info.value, ClikError) and info.value.exit_code == 2
    assert not (tmp_path / "api").exists()


def _any_record(tmp_path: Path) -> Path:
    """A small run's trajectory.npz (no bag), written without rosbags."""
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180, -30, -90, -30])
    from clik.trajectory import Hold

    result = clik.track(
        task, Hold(position=task.placement(q0).translation, duration=0.01), q0=q0,
        law="pseudoinverse", gain=100.0,
    )  # fmt: skip
    return result.save(tmp_path / "small.npz")


def test_python_api_replaces_its_bag_and_keeps_a_users_folder(tmp_path):
    robot = clik.Robot.load("planar4r")
    result = TrackingResult.load(_any_record(tmp_path))
    n = len(result.t)
    bag = export_rosbag(result, tmp_path / "a", robot=robot)
    assert bag == tmp_path / "a" / BAG_NAME
    topics = read_bag(bag)
    # a one-task position run without goals: its target from the recorded reference
    assert sorted(topics) == sorted([JOINT_STATES, JOINT_TRAJECTORY, "/clik/task/target"])
    assert len(topics["/clik/task/target"]) == n
    for k, (_, msg) in enumerate(topics["/clik/task/target"]):
        assert msg.header.frame_id == "base"
        p = msg.point
        np.testing.assert_allclose([p.x, p.y, p.z], result.reference_position[k], atol=EXACT)
    again = export_rosbag(result, tmp_path / "a", every=2, robot=robot)  # replaced whole
    assert len(read_bag(again)[JOINT_STATES]) == len(range(0, n, 2)) + (n - 1) % 2
    assert [p.name for p in (tmp_path / "a").iterdir()] == [BAG_NAME]  # no leftovers

    mine = tmp_path / "b" / BAG_NAME
    mine.mkdir(parents=True)
    (mine / "notes.txt").write_text("mine")
    with pytest.raises(ExportError, match="is not a rosbag2 folder"):
        export_rosbag(result, tmp_path / "b", robot=robot)
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    assert (mine / "notes.txt").read_text() == "mine"


def test_targets_follow_the_goals_and_are_left_out_when_they_do_not_match_the_record(tmp_path):
    from clik.trajectory import Hold

    robot = clik.Robot.load("planar4r")
    result = TrackingResult.load(_any_record(tmp_path))
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    start = result.reference_position[0]
    same = clik.Goal(task, Hold(position=start, duration=0.01))
    topics = read_bag(export_rosbag(result, tmp_path / "a", goals=[same], robot=robot))
    assert len(topics["/clik/task/target"]) == len(result.t)
    # another reference than the recorded one (a re-timed run's): no target topic
    moved = clik.Goal(task, Hold(position=start + [0.01, 0.0, 0.0], duration=0.01))
    topics = read_bag(export_rosbag(result, tmp_path / "b", goals=[moved], robot=robot))
    assert sorted(topics) == sorted([JOINT_STATES, JOINT_TRAJECTORY])
