"""The ``[ros]`` table of a scenario: topics, rate, output and timeout of ``clik ros``.

Every key is optional (docs/guides/ros.md):

- ``rate`` [Hz]: the node's tick rate; default ``1 / solver.dt``.
- ``output``: ``"trajectory"`` (a ``trajectory_msgs/JointTrajectory`` of one point, the
  next tick's joints), ``"position"`` or ``"velocity"`` (``std_msgs/Float64MultiArray``,
  joints in the scenario's order).
- ``output_topic``: default ``/joint_trajectory_controller/joint_trajectory``,
  ``/forward_position_controller/commands`` or ``/forward_velocity_controller/commands``.
- ``joint_states``: the feedback topic (``sensor_msgs/JointState``), ``/joint_states``.
- ``status``: the status topic (``std_msgs/String`` of JSON), ``/clik/status``.
- ``prefix``: the targets' topics are ``<prefix>/<task name>/target`` and
  ``<prefix>/<task name>/twist``, the moving obstacles' ``<prefix>/obstacles/<name>``;
  default ``/clik``.
- ``obstacle_message``: ``"point"`` (``geometry_msgs/PointStamped``, default) or
  ``"pose"`` (``PoseStamped``, its position read).
- ``timeout`` [s]: a target or a joint state older than this holds the last command and
  says so on the status topic; default 0.25 s.
- ``world_frame``: the ``frame_id`` meaning the robot's world frame (also accepted:
  ``""``), default ``"world"``; any frame of the robot is accepted too.
- ``measured_jump``: ``c`` of eq. (M3) for the node's controller, default 10 (the
  ``Controller``'s is 3): a node on a non-real-time system runs a tick a few
  milliseconds late now and then, and the joint state it reads then holds several
  ticks of motion (measured: 3.1 ticks' worth at the speed limit in a CI run).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from clik.schema import Table

OUTPUTS = ("trajectory", "position", "velocity")
OUTPUT_TOPICS = {
    "trajectory": "/joint_trajectory_controller/joint_trajectory",
    "position": "/forward_position_controller/commands",
    "velocity": "/forward_velocity_controller/commands",
}
TIMEOUT = 0.25
"""Default age [s] past which a target or a joint state is stale."""

MEASURED_JUMP = 10.0
"""The node's default ``measured_jump`` (eq. (M3)): ticks of motion at the speed limits
a joint state may hold since the last accepted one, per tick."""


@dataclass(frozen=True)
class RosSettings:
    """The ``[ros]`` table, checked (see the module docstring)."""

    rate: float | None = None
    output: str = "trajectory"
    output_topic: str = OUTPUT_TOPICS["trajectory"]
    joint_states: str = "/joint_states"
    status: str = "/clik/status"
    prefix: str = "/clik"
    obstacle_message: str = "point"
    timeout: float = TIMEOUT
    world_frame: str = "world"
    measured_jump: float = MEASURED_JUMP

    def target_topic(self, task: str) -> str:
        """The target topic of task ``task``."""
        return f"{self.prefix}/{task}/target"

    def twist_topic(self, task: str) -> str:
        """The feed-forward topic of task ``task``."""
        return f"{self.prefix}/{task}/twist"

    def obstacle_topic(self, name: str) -> str:
        """The topic of the moving obstacle ``name``."""
        return f"{self.prefix}/obstacles/{name}"


def _topic(table: Table, name: str, default: str) -> str:
    value = str(table.string(name, default))
    if not value.startswith("/") or any(c.isspace() for c in value) or value.endswith("/"):
        raise table.error(name, "an absolute ROS topic name ('/a/b', no spaces)", value)
    return value


def ros_table(table: Table) -> dict[str, Any]:
    """The ``[ros]`` table's values (the keys of :class:`RosSettings`), checked."""
    output = table.string("output", "trajectory", OUTPUTS)
    rate = table.number("rate", None, minimum=0.0, strict=True, unit="[Hz]")
    values = {
        "rate": None if rate is None else float(rate),
        "output": output,
        "output_topic": _topic(table, "output_topic", OUTPUT_TOPICS[output]),
        "joint_states": _topic(table, "joint_states", "/joint_states"),
        "status": _topic(table, "status", "/clik/status"),
        "prefix": _topic(table, "prefix", "/clik"),
        "obstacle_message": table.string("obstacle_message", "point", ("point", "pose")),
        "timeout": float(table.number("timeout", TIMEOUT, minimum=0.0, strict=True, unit="[s]")),
        "world_frame": table.string("world_frame", "world"),
        "measured_jump": float(
            table.number("measured_jump", MEASURED_JUMP, minimum=0.0, strict=True)
        ),
    }
    table.done()
    return values
