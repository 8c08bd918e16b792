"""A ROS 2 loop on loopback: ``clik ros``, a robot that lags, and a client (prints JSON).

Run inside a private network namespace with only ``lo`` up
(:func:`benchmarks.ros_line.run_loop` makes one, for tests/ros/test_ros_loop.py and
``clik bench``; never on the machine's own interfaces)::

    unshare -n sh -c 'ip link set lo up && exec python benchmarks/ros_loop.py SCENARIO.toml'

The robot (a node in this process) echoes the commands as joint states after ``--delay``
ticks and a first-order lag of ``--tau`` seconds, at 1 kHz. The client sends the
scenario's reference one target at a time (pose and twist, stamped), waits for the node's
``answered`` header carrying that stamp (the round trip), then sends the next. Midway it
sends a pose with a NaN (the status must name it) and at the end it stops for twice the
timeout (the status must say stale, and the commands hold). The JSON: ``sent``,
``answered``, ``rtt_ms`` (median, p99), ``max_error_m``, ``final_error_m`` (the hand on
the robot's joints against the reference), ``refused``, ``stale``, ``held``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections import deque
from typing import Any

import numpy as np
import pinocchio as pin
import rclpy
from geometry_msgs.msg import PoseStamped, TwistStamped
from rclpy.executors import ExternalShutdownException
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header, String
from trajectory_msgs.msg import JointTrajectory

from clik.model.joint_order import JointOrder
from clik.ros.node import _executor
from clik.ros.settings import RosSettings
from clik.scenarios.runner import build


def _command_type(settings: RosSettings) -> Any:
    """The command topic's message type for the node's ``output``."""
    return JointTrajectory if settings.output == "trajectory" else Float64MultiArray


def _command_values(msg: Any) -> np.ndarray:
    """A command's joint values: a trajectory's point, or the array's data."""
    if isinstance(msg, JointTrajectory):
        return np.array(msg.points[0].positions)
    return np.array(msg.data)


class Robot:
    """Commands in, joint states out: ``delay`` ticks late, then a first-order lag."""

    def __init__(self, node: Any, order: JointOrder, q0: np.ndarray, tau: float, delay: int,
                 settings: RosSettings) -> None:  # fmt: skip
        self.order, self.tau, self.dt = order, tau, 1e-3
        self.q = order.angles(q0)[0]
        self.queue: deque[np.ndarray] = deque([self.q.copy()] * (delay + 1), maxlen=delay + 1)
        self.command = self.q.copy()
        self.commands = 0
        self.velocity = settings.output == "velocity"
        node.create_subscription(
            _command_type(settings), settings.output_topic, self.on_command, 10
        )
        self.pub = node.create_publisher(JointState, settings.joint_states, 10)
        node.create_timer(self.dt, self.step)

    def on_command(self, msg: Any) -> None:
        """A command: its point's positions become the robot's input."""
        values = _command_values(msg)
        self.command = self.command + values * self.dt if self.velocity else values
        self.commands += 1

    def step(self) -> None:
        """One millisecond: the delayed command, through the lag; the joint state out."""
        self.queue.append(self.command)
        target = self.queue[0]
        self.q = self.q + (target - self.q) * (self.dt / (self.tau + self.dt))
        msg = JointState(name=list(self.order.names), position=[float(x) for x in self.q])
        self.pub.publish(msg)


def robot_main(scenario: str, tau: float, delay: int, duration: float) -> int:
    """The test robot alone (its own process: its 1 kHz timer does not slow the client)."""
    run = build(scenario)
    settings = RosSettings(**run.scenario.ros)
    rclpy.init()
    node = rclpy.create_node("clik_test_robot")
    Robot(node, JointOrder.of(run.robot, "the test robot"), run.q0, tau, delay, settings)
    executor = _executor(rclpy)
    executor.add_node(node)
    end = time.monotonic() + duration
    try:
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.01)
    except ExternalShutdownException:  # SIGTERM from the client: done
        return 0
    node.destroy_node()
    rclpy.shutdown()
    return 0


def _pose(position: np.ndarray, rotation: np.ndarray, stamp: Any) -> PoseStamped:
    msg = PoseStamped()
    msg.header.stamp, msg.header.frame_id = stamp, "world"
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, position)
    q = pin.Quaternion(rotation)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = float(q.x), float(q.y), float(q.z), float(q.w)
    return msg


def main() -> int:
    """The client (or, with ``--robot``, the robot); prints the loop's JSON."""
    a = argparse.ArgumentParser()
    a.add_argument("scenario")
    a.add_argument("--targets", type=int, default=2000)
    a.add_argument("--tau", type=float, default=0.005)
    a.add_argument("--delay", type=int, default=2)
    a.add_argument("--robot", action="store_true", help="be the test robot")
    a.add_argument("--duration", type=float, default=120.0)
    args = a.parse_args()
    if args.robot:
        return robot_main(args.scenario, args.tau, args.delay, args.duration)
    run = build(args.scenario)
    settings = RosSettings(**run.scenario.ros)
    robot_model = run.robot
    order = JointOrder.of(robot_model, "the test robot")
    frame = run.task.frame_id
    clik = subprocess.Popen(
        [sys.executable, "-c", "import sys; from clik.cli import main; sys.exit(main())",
         "ros", args.scenario, "--duration", str(60.0)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    robot_proc = subprocess.Popen(
        [sys.executable, __file__, args.scenario, "--robot", "--tau", str(args.tau),
         "--delay", str(args.delay), "--duration", "120"],
    )  # fmt: skip
    rclpy.init()
    node = rclpy.create_node("clik_test_client")
    latest: dict[str, Any] = {"q": order.angles(run.q0)[0], "commands": []}

    def on_joints(m: Any) -> None:
        latest["q"] = np.array(m.position)

    node.create_subscription(JointState, settings.joint_states, on_joints, 1)

    def on_command(m: Any) -> None:
        latest["commands"].append(_command_values(m))

    commands = node.create_subscription(
        _command_type(settings), settings.output_topic, on_command, 1
    )
    answered: dict[str, Any] = {}
    statuses: list[dict[str, Any]] = []
    node.create_subscription(
        Header, f"{settings.prefix}/answered",
        lambda m: answered.__setitem__("last", (m.stamp.sec, m.stamp.nanosec)), 10,
    )  # fmt: skip
    node.create_subscription(
        String, settings.status, lambda m: statuses.append(json.loads(m.data)), 100
    )
    executor = _executor(rclpy)
    executor.add_node(node)

    def spin(timeout_sec: float) -> None:
        executor.spin_once(timeout_sec=timeout_sec)

    target = node.create_publisher(PoseStamped, settings.target_topic("task"), 10)
    twist = node.create_publisher(TwistStamped, settings.twist_topic("task"), 10)
    start = time.monotonic()
    while not latest["commands"] and time.monotonic() - start < 30:  # the node is up
        spin(timeout_sec=0.01)
    node.destroy_subscription(commands)  # until the hold: fewer callbacks, a faster client
    dt = run.scenario.solver["dt"]
    t = np.arange(args.targets) * dt
    ref = run.trajectory.sample(t)
    assert ref.position is not None and ref.rotation is not None  # a pose task's circle
    assert ref.linear_velocity is not None and ref.angular_velocity is not None
    data = robot_model.model.createData()
    rtt, errors, refused_at = [], [], args.targets // 2
    sent = 0
    for k in range(args.targets):
        if k == refused_at:  # a NaN: refused by name, the node goes on
            bad = _pose(np.array([np.nan, 0.0, 0.0]), np.eye(3), node.get_clock().now().to_msg())
            target.publish(bad)
        stamp = node.get_clock().now().to_msg()
        tw = TwistStamped()
        tw.header.stamp, tw.header.frame_id = stamp, "world"
        v, w = ref.linear_velocity[k], ref.angular_velocity[k]
        tw.twist.linear.x, tw.twist.linear.y, tw.twist.linear.z = map(float, v)
        tw.twist.angular.x, tw.twist.angular.y, tw.twist.angular.z = map(float, w)
        twist.publish(tw)
        sent_at = time.perf_counter()
        target.publish(_pose(ref.position[k], ref.rotation[k], stamp))
        sent += 1
        key = (stamp.sec, stamp.nanosec)
        while answered.get("last") != key and time.perf_counter() - sent_at < 1.0:
            spin(timeout_sec=0.0005)
        if answered.get("last") == key:
            rtt.append(time.perf_counter() - sent_at)
        elif clik.poll() is not None or k - len(rtt) > 5:  # the node died or does not answer
            break
        q = order.configuration(run.q0, latest["q"])
        pin.framesForwardKinematics(robot_model.model, data, q)
        errors.append(float(np.linalg.norm(data.oMf[frame].translation - ref.position[k])))
    # stop sending: the node must hold and say stale
    pause = time.monotonic()
    node.create_subscription(_command_type(settings), settings.output_topic, on_command, 10)
    while time.monotonic() - pause < 1.5 * settings.timeout:
        spin(timeout_sec=0.005)
    held_from = len(latest["commands"])
    while time.monotonic() - pause < 2 * settings.timeout + 0.2:
        spin(timeout_sec=0.005)
    held = latest["commands"][held_from:]
    clik.terminate()
    robot_proc.terminate()
    out, err = clik.communicate(timeout=30)
    robot_proc.wait(timeout=30)
    node.destroy_node()
    rclpy.shutdown()
    refused = [s["refused"] for s in statuses if s.get("refused")]
    stale = [s["stale"] for s in statuses if s.get("stale")]
    del start
    result = {
        "sent": sent,
        "answered": len(rtt),
        "rtt_ms": {
            "median": 1e3 * float(np.median(rtt)),
            "p99": 1e3 * float(np.percentile(rtt, 99)),
        }
        if rtt
        else None,
        "max_error_m": max(errors[200:]) if len(errors) > 200 else None,
        "final_error_m": errors[-1],
        "refused": refused,
        "stale": stale,
        "held": bool(held) and all(np.array_equal(c, held[0]) for c in held),
        "verdicts": sorted({s.get("verdict", "") for s in statuses}),
        "node_stdout": out[-2000:],
        "node_stderr": err[-2000:],
        "rmw": os.environ.get("RMW_IMPLEMENTATION", ""),
    }
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
