"""A run as a ROS 2 bag: joint states, joint commands and task targets in one MCAP file.

``clik solve --export rosbag`` (and :func:`export_rosbag`) writes the folder
``DIR/trajectory_bag/``: a rosbag2 bag (``metadata.yaml`` and one
``trajectory_bag.mcap``, MCAP storage, CDR messages, rosbag2 format version 9)
written with the pure-Python ``rosbags`` library, so no ROS install is needed
(``pip install 'clik[ros]'``). Every message's bag time (its log time) is the run's
sample time ``t_k`` [s] in nanoseconds, counted from 0. Topics, for the exported samples
(every ``every``-th recorded one and the last, as :mod:`clik.outputs.export`):

- ``/joint_states``, ``sensor_msgs/msg/JointState``: one per sample, ``header.stamp =
  t_k``, ``name`` the joints in the model's velocity order, ``position`` [rad or m]
  and ``velocity`` [rad/s or m/s] as in ``trajectory.csv`` (a continuous joint as its
  unwrapped angle), ``effort`` empty.
- ``/joint_trajectory``, ``trajectory_msgs/msg/JointTrajectory``: the command of each
  sample but the last, as the ``clik ros`` node sends it: at bag time ``t_k`` one point,
  the *next* sample ``k + 1`` (positions, velocities, accelerations), with
  ``time_from_start = t_{k+1} - t_k``, and ``header.stamp`` zero (a
  ``joint_trajectory_controller`` starts a message with a zero stamp when it receives
  it, so a replay with ``ros2 bag play`` streams the run tick by tick). The whole run as
  one message is ``trajectory.json`` (``--export json``).
- ``/clik/<task name>/target``: each task's reference at each sample, for a pose task
  a ``geometry_msgs/msg/PoseStamped`` (position [m], orientation as a unit quaternion),
  for a position task (and a centre of mass task, and a pose task whose axes are all
  positions) a ``geometry_msgs/msg/PointStamped`` [m], ``header.stamp = t_k``;
  ``header.frame_id`` the robot's world frame (:func:`world_frame_name`), or frame B
  for a task relative to frame B. A one-task run names its task ``task`` (as
  ``summary.json`` does). Tasks of other kinds (orientation, posture, gaze, distance)
  have no target topic.

The targets are the tasks' trajectories sampled at the recorded times; the primary
task's position is the record's ``reference_position`` itself. A run whose reference
was re-timed (``[constraints.velocity_limits]``: the record's reference no longer
matches the trajectory at the same times) gets no target topics: the record keeps
the re-timed positions but not the re-timed orientations.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from clik.errors import ExportError, InputError
from clik.outputs.export import FORMATS, check_every, decimated, joint_trajectory
from clik.outputs.goal_check import checked_goals
from clik.outputs.io import output_errors

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.outputs.result import TrackingResult
    from clik.tasks.goal import Goal

BAG_FORMAT = "rosbag"
"""The ``--export`` name of the bag."""

EXPORT_CHOICES = (*FORMATS, BAG_FORMAT)
"""What ``clik solve --export`` accepts: the file formats, and the bag."""

BAG_NAME = "trajectory_bag"
"""The bag's folder in the output folder (its MCAP file is ``trajectory_bag.mcap``)."""

JOINT_STATES = "/joint_states"
"""The joint states' topic."""

JOINT_TRAJECTORY = "/joint_trajectory"
"""The joint commands' topic."""

ROSBAG_VERSION = 9
"""The rosbag2 metadata version written."""

REFERENCE_MATCH = 1e-9
"""Largest difference [m] between the primary task's trajectory and its recorded
reference at the same times for the run to count as not re-timed."""


class RosbagsMissing(ExportError):
    """``--export rosbag`` without the ``rosbags`` package installed.

    Attributes:
        package: The missing package (``rosbags``).
        extra: The clik extra that brings it (``ros``).
    """

    def __init__(self, package: str = "rosbags", extra: str = "ros") -> None:
        self.package = package
        self.extra = extra
        super().__init__(
            f"a rosbag needs the {package} package, which is not installed: "
            f"pip install 'clik[{extra}]' (or pip install {package})"
        )


def check_rosbags() -> None:
    """Refuse a bag export when ``rosbags`` cannot be imported (before a run).

    Raises:
        RosbagsMissing: The package is missing.
    """
    _rosbags()


def _rosbags() -> tuple[Any, Any, Any]:
    """``rosbags``' ``Writer``, ``StoragePlugin`` and the ROS 2 Jazzy type store."""
    try:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise RosbagsMissing() from None
    return Writer, StoragePlugin, get_typestore(Stores.ROS2_JAZZY)


@dataclass(frozen=True)
class TaskTarget:
    """One task's reference at the exported samples, as its target topic carries it.

    Attributes:
        name: The task's name (the topic is ``/clik/<name>/target``).
        message: ``"PoseStamped"`` or ``"PointStamped"``.
        frame_id: The frame the reference is expressed in.
        position: Reference positions (M, 3) [m].
        rotation: Reference orientations (M, 3, 3) for a pose, else None.
    """

    name: str
    message: str
    frame_id: str
    position: np.ndarray
    rotation: np.ndarray | None

    @property
    def topic(self) -> str:
        """``/clik/<name>/target``."""
        return f"/clik/{self.name}/target"


def world_frame_name(model: Any) -> str:
    """The name of the robot's world frame, for ``header.frame_id``.

    The model's root link (the first body on Pinocchio's ``universe``, e.g.
    ``panda_link0``), when it sits at the world's origin, as in a URDF; else ``"world"``.

    Args:
        model: A ``pinocchio.Model``.
    """
    for frame in model.frames:
        if frame.type == pin.FrameType.BODY and frame.parentJoint == 0:
            return str(frame.name) if frame.placement.isIdentity() else "world"
    return "world"


def task_targets(
    result: TrackingResult, goals: Sequence[Goal], model: Any, keep: np.ndarray
) -> list[TaskTarget]:
    """The tasks' targets at the kept samples (module docstring), in the run's task order.

    Args:
        result: The run.
        goals: Its tasks: ``[[tasks]]``' goals, or one goal for a one-task run (named
            ``task`` whatever its ``name``).
        model: The run's ``pinocchio.Model``.
        keep: Indices of the exported samples.

    Raises:
        InputError: Not the run's goals.
    """
    from clik.tasks.com_task import ComTask
    from clik.tasks.relative_task import RelativeTask
    from clik.tasks.task import Task

    if not goals:
        return []
    if result.info.get("tasks") is None:
        if len(goals) != 1:
            raise InputError("goals", "one goal for a one-task run", len(goals))
        named = {"task": goals[0]}
    else:
        names = checked_goals(result, goals)
        by_name = dict(zip(names, goals, strict=True))
        named = {n: by_name[n] for n in result.info["tasks"] if n in by_name}
    t = np.asarray(result.t, dtype=float)[keep]
    world = world_frame_name(model)
    targets: list[TaskTarget] = []
    for i, (name, goal) in enumerate(named.items()):
        task = goal.task
        if goal.trajectory is None or not isinstance(task, Task | RelativeTask | ComTask):
            continue
        if not getattr(task, "has_position", True):
            continue  # a pose task on orientation axes only: no point to publish
        pose = bool(getattr(task, "has_orientation", False))  # else its axes are positions
        ref = np.asarray(task.reference_arrays(goal.trajectory.sample(t))[0], dtype=float)
        position = ref[:, :3].copy()
        if i == 0 and isinstance(task, Task) and result.reference_position is not None:
            recorded = np.asarray(result.reference_position, dtype=float)[keep]
            if np.max(np.abs(recorded - position), initial=0.0) > REFERENCE_MATCH:
                return []  # re-timed: the record's reference is not the trajectory's
            position = recorded
        frame = task.relative_to if isinstance(task, RelativeTask) else world
        targets.append(
            TaskTarget(
                name,
                "PoseStamped" if pose else "PointStamped",
                frame,
                position,
                ref[:, 3:12].reshape(-1, 3, 3) if pose else None,
            )
        )
    return targets


def _recorded_targets(result: TrackingResult, model: Any, keep: np.ndarray) -> list[TaskTarget]:
    """Without goals: a one-task position run's target, from its record alone."""
    axes = result.info.get("axes") or []
    if result.info.get("tasks") is not None or not axes or not set(axes) <= set("xyz"):
        return []  # several tasks, or a task with orientation rows: not from the record
    if result.reference_position is None:
        return []
    position = np.asarray(result.reference_position, dtype=float)[keep]
    return [TaskTarget("task", "PointStamped", world_frame_name(model), position, None)]


def export_rosbag(
    result: TrackingResult,
    out: str | os.PathLike[str],
    every: int = 1,
    goals: Sequence[Goal] | None = None,
    robot: Robot | None = None,
) -> Path:
    """Write the run as a rosbag2 bag, ``out/trajectory_bag/`` (module docstring).

    The bag is written into a hidden folder beside it, then renamed into place: a
    stopped export leaves no partial bag. An existing ``trajectory_bag`` that is a bag
    (only ``metadata.yaml`` and ``.mcap`` files) is replaced, like ``trajectory.csv``;
    anything else there is refused.

    Args:
        result: The run.
        out: The output folder (created if missing).
        every: Keep every ``every``-th recorded sample and the last (>= 1).
        goals: The run's tasks, for their target topics: a ``[[tasks]]`` run's goals
            (any order), or one :class:`~clik.tasks.goal.Goal` with the task and the
            trajectory of a one-task run. None: only a one-task position run's target
            (from its recorded reference).
        robot: The run's robot, for a result without one (loaded from a file).

    Returns:
        The bag's folder.

    Raises:
        RosbagsMissing: ``rosbags`` is not installed (``pip install 'clik[ros]'``).
        InputError: ``every`` not an integer >= 1, no robot, or not the run's goals.
        ExportError: A joint that is not revolute, prismatic or continuous; non-finite
            values; a ``trajectory_bag`` there that is not a bag.
    """
    Writer, StoragePlugin, store = _rosbags()
    every = check_every(every)
    robot = robot if robot is not None else result.robot
    if robot is None:
        raise InputError("robot", "the run's robot (this result has none: pass robot=...)")
    trajectory = joint_trajectory(result.t, result.q, result.qdot, robot.model, every)
    keep = decimated(len(result.t), every)
    targets = (
        _recorded_targets(result, robot.model, keep)
        if goals is None
        else task_targets(result, goals, robot.model, keep)
    )
    folder = Path(out)
    bag = folder / BAG_NAME
    _check_replaceable(bag)
    work = folder / f".{BAG_NAME}.tmp-{os.getpid()}"  # holds the bag until it is whole
    with output_errors(bag):
        folder.mkdir(parents=True, exist_ok=True)
        shutil.rmtree(work, ignore_errors=True)
        work.mkdir()
        try:
            with Writer(
                work / BAG_NAME, version=ROSBAG_VERSION, storage_plugin=StoragePlugin.MCAP
            ) as writer:
                _write_messages(writer, store, trajectory, targets)
            if bag.exists():
                shutil.rmtree(bag)
            (work / BAG_NAME).rename(bag)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return bag


def _check_replaceable(bag: Path) -> None:
    """Refuse a ``trajectory_bag`` that is not a bag (a user's file or folder)."""
    if not bag.exists() and not bag.is_symlink():
        return
    ours = bag.is_dir() and not bag.is_symlink()
    if ours:
        ours = all(p.name == "metadata.yaml" or p.suffix == ".mcap" for p in bag.iterdir())
    if not ours:
        raise ExportError(
            f"{bag} exists and is not a rosbag2 folder (only metadata.yaml and .mcap files); "
            "move it away or export into another folder"
        )


def _time(store: Any, seconds: float) -> Any:
    """``builtin_interfaces/msg/Time`` of ``seconds`` (>= 0) [s], to the nanosecond."""
    sec, nanosec = divmod(_nanoseconds(seconds), 1_000_000_000)
    return store.types["builtin_interfaces/msg/Time"](sec=int(sec), nanosec=int(nanosec))


def _duration(store: Any, seconds: float) -> Any:
    """``builtin_interfaces/msg/Duration`` of ``seconds`` [s], to the nanosecond."""
    sec, nanosec = divmod(_nanoseconds(seconds), 1_000_000_000)
    return store.types["builtin_interfaces/msg/Duration"](sec=int(sec), nanosec=int(nanosec))


def _nanoseconds(seconds: float) -> int:
    """``seconds`` [s] as whole nanoseconds."""
    return round(seconds * 1e9)


def _write_messages(writer: Any, store: Any, trajectory: Any, targets: list[TaskTarget]) -> None:
    """Every topic's messages, in time order per topic."""
    types = store.types
    Header = types["std_msgs/msg/Header"]
    JointState = types["sensor_msgs/msg/JointState"]
    JointTrajectory = types["trajectory_msgs/msg/JointTrajectory"]
    Point = types["trajectory_msgs/msg/JointTrajectoryPoint"]
    empty = np.zeros(0)
    names = list(trajectory.joint_names)
    time = trajectory.time.tolist()

    def channel(topic: str, msgtype: str) -> Any:
        return writer.add_connection(topic, msgtype, typestore=store)

    def put(connection: Any, tk: float, message: Any) -> None:
        data = store.serialize_cdr(message, connection.msgtype)
        writer.write(connection, _nanoseconds(tk), data)

    states = channel(JOINT_STATES, JointState.__msgtype__)
    for k, tk in enumerate(time):
        put(states, tk, JointState(
            header=Header(stamp=_time(store, tk), frame_id=""),
            name=names,
            position=np.array(trajectory.positions[k], dtype=float),
            velocity=np.array(trajectory.velocities[k], dtype=float),
            effort=empty,
        ))  # fmt: skip
    commands = channel(JOINT_TRAJECTORY, JointTrajectory.__msgtype__)
    for k, tk in enumerate(time[:-1]):
        point = Point(
            positions=np.array(trajectory.positions[k + 1], dtype=float),
            velocities=np.array(trajectory.velocities[k + 1], dtype=float),
            accelerations=np.array(trajectory.accelerations[k + 1], dtype=float),
            effort=empty,
            time_from_start=_duration(store, time[k + 1] - tk),
        )
        put(commands, tk, JointTrajectory(
            header=Header(stamp=_time(store, 0.0), frame_id=""),
            joint_names=names,
            points=[point],
        ))  # fmt: skip
    for target in targets:
        _write_target(channel, put, store, target, time)


def _write_target(channel: Any, put: Any, store: Any, target: TaskTarget, time: list) -> None:
    """One task's target topic."""
    types = store.types
    Header, Point = types["std_msgs/msg/Header"], types["geometry_msgs/msg/Point"]
    kind = types[f"geometry_msgs/msg/{target.message}"]
    connection = channel(target.topic, kind.__msgtype__)
    for k, tk in enumerate(time):
        header = Header(stamp=_time(store, tk), frame_id=target.frame_id)
        x, y, z = (float(v) for v in target.position[k])
        if target.rotation is None:
            put(connection, tk, kind(header=header, point=Point(x=x, y=y, z=z)))
            continue
        qx, qy, qz, qw = (float(v) for v in pin.Quaternion(target.rotation[k]).coeffs())
        pose = types["geometry_msgs/msg/Pose"](
            position=Point(x=x, y=y, z=z),
            orientation=types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
        )
        put(connection, tk, kind(header=header, pose=pose))
