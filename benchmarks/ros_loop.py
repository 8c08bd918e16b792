"""A ROS 2 loop on loopback: ``clik ros``, a robot that lags, and a client (prints JSON).

Run inside a private network namespace with only ``lo`` up
(:func:`benchmarks.ros_line.run_loop` makes one, for tests/ros/test_ros_loop.py and
``clik bench``; never on the machine's own interfaces)::

    unshare -n sh -c 'ip link set lo up && exec python benchmarks/ros_loop.py SCENARIO.toml'

The robot (a node in this process) echoes the commands as joint states after ``--delay``
ticks and a first-order lag of ``--tau`` seconds, at 1 kHz. The client sends the
scenario's reference one target at a time (pose and twist, stamped), waits for the node's
``answered`` header carrying that stamp (the round trip), then sends the next. Midway it
sends a pose with a NaN (the status must name it); then, for 1 s, a target 3 m up, out
of reach (the status must say the verdict and why); at the end it stops for twice the
timeout (the status must say stale, and the commands hold). The JSON: ``sent``,
``answered``, ``rtt_ms`` (median, p99), ``max_error_m``, ``final_error_m`` (the hand on
the robot's joints against the reference), ``refused``, ``verdicts`` (while tracking),
``blocked`` (the statuses the target out of reach brought), ``stale``, ``held``.
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
from clik.scenarios.ros_table import RosSettings
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


def _twist(linear: np.ndarray, angular: np.ndarray, stamp: Any) -> TwistStamped:
    msg = TwistStamped()
    msg.header.stamp, msg.header.frame_id = stamp, "world"
    msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = map(float, linear)
    msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = map(float, angular)
    return msg


def _processes(args: argparse.Namespace) -> tuple[subprocess.Popen[str], subprocess.Popen[str]]:
    """The ``clik ros`` node and the test robot, started."""
    clik = subprocess.Popen(
        [sys.executable, "-c", "import sys; from clik.cli import main; sys.exit(main())",
         "ros", args.scenario, "--duration", "60"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    robot = subprocess.Popen(
        [sys.executable, __file__, args.scenario, "--robot", "--tau", str(args.tau),
         "--delay", str(args.delay), "--duration", "120"], text=True,
    )  # fmt: skip
    return clik, robot


class Client:
    """Targets out one at a time, answers, joint states, commands and statuses in."""

    def __init__(self, run: Any, settings: RosSettings, order: JointOrder) -> None:
        self.run, self.settings, self.order = run, settings, order
        self.node = node = rclpy.create_node("clik_test_client")
        self.q = order.angles(run.q0)[0]
        self.states = 0  # joint states received
        self.commands: list[np.ndarray] = []
        self.answered: tuple[int, int] | None = None
        self.statuses: list[dict[str, Any]] = []
        node.create_subscription(JointState, settings.joint_states, self._on_joints, 1)
        self.listening = node.create_subscription(
            _command_type(settings), settings.output_topic, self.commands.append, 1
        )
        node.create_subscription(Header, f"{settings.prefix}/answered", self._on_answer, 10)
        node.create_subscription(String, settings.status, self._on_status, 100)
        self.target = node.create_publisher(PoseStamped, settings.target_topic("task"), 10)
        self.twist = node.create_publisher(TwistStamped, settings.twist_topic("task"), 10)
        self.executor = _executor(rclpy)
        self.executor.add_node(node)

    def _on_joints(self, m: Any) -> None:
        self.q = np.array(m.position)
        self.states += 1

    def _on_answer(self, m: Any) -> None:
        self.answered = (m.stamp.sec, m.stamp.nanosec)

    def _on_status(self, m: Any) -> None:
        self.statuses.append(json.loads(m.data))

    def spin(self, seconds: float) -> None:
        """Callbacks for ``seconds``."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.005)

    def wait_for_node(self) -> None:
        """Until the node's first command and the robot's first joint state (<= 60 s)."""
        end = time.monotonic() + 60
        while not (self.commands and self.states) and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)
        self.node.destroy_subscription(self.listening)  # fewer callbacks until the hold

    def send(self, position: np.ndarray, rotation: np.ndarray, twist: Any) -> float | None:
        """One target (and its twist); the round trip [s], None without an answer in 1 s."""
        stamp = self.node.get_clock().now().to_msg()
        self.twist.publish(_twist(twist[0], twist[1], stamp))
        sent_at = time.perf_counter()
        self.target.publish(_pose(position, rotation, stamp))
        key = (stamp.sec, stamp.nanosec)
        while self.answered != key and time.perf_counter() - sent_at < 1.0:
            self.executor.spin_once(timeout_sec=0.0005)
        return time.perf_counter() - sent_at if self.answered == key else None

    def hand_error(self, frame: int, reference: np.ndarray) -> float:
        """The hand on the robot's latest joints, from the reference [m]."""
        model = self.run.robot.model
        data = model.createData()
        pin.framesForwardKinematics(model, data, self.order.configuration(self.run.q0, self.q))
        return float(np.linalg.norm(data.oMf[frame].translation - reference))

    def blocked(self, seconds: float) -> list[dict[str, Any]]:
        """A target out of reach (3 m up), sent every 5 ms: the statuses it brings."""
        start = len(self.statuses)
        far = np.array([0.0, 0.0, 3.0])
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            stamp = self.node.get_clock().now().to_msg()
            self.target.publish(_pose(far, np.eye(3), stamp))
            self.spin(0.005)
        return [s for s in self.statuses[start:] if s.get("verdict", "ok") != "ok"]

    def hold(self) -> list[np.ndarray]:
        """Stop sending: the commands after 1.5 timeouts (the node holds by then)."""
        self.listening = self.node.create_subscription(
            _command_type(self.settings), self.settings.output_topic, self.commands.append, 10
        )
        self.spin(1.5 * self.settings.timeout)
        start = len(self.commands)
        self.spin(0.5 * self.settings.timeout + 0.2)
        return [_command_values(c) for c in self.commands[start:]]


def _track(
    client: Client, run: Any, targets: int, clik: Any
) -> tuple[list[float], list[float], int]:
    """The reference sent target by target (a NaN pose midway).

    Returns:
        The round trips [s], the hand errors [m] and how many targets were sent.
    """
    t = np.arange(targets) * run.scenario.solver["dt"]
    ref = run.trajectory.sample(t)
    assert ref.position is not None and ref.rotation is not None  # a pose task's circle
    assert ref.linear_velocity is not None and ref.angular_velocity is not None
    rtt: list[float] = []
    errors: list[float] = []
    sent = 0
    for k in range(targets):
        if k == targets // 2:  # a NaN: refused by name, the node goes on
            stamp = client.node.get_clock().now().to_msg()
            client.target.publish(_pose(np.array([np.nan, 0.0, 0.0]), np.eye(3), stamp))
        took = client.send(ref.position[k], ref.rotation[k],
                           (ref.linear_velocity[k], ref.angular_velocity[k]))  # fmt: skip
        sent += 1
        if took is not None:
            rtt.append(took)
        elif clik.poll() is not None or k - len(rtt) > 5:  # the node died or does not answer
            break
        errors.append(client.hand_error(run.task.frame_id, ref.position[k]))
    return rtt, errors, sent


def _summary(rtt: list[float], errors: list[float], sent: int, held: list[np.ndarray],
             statuses: list[dict[str, Any]], out: str, err: str) -> dict[str, Any]:  # fmt: skip
    quantiles = {"median": 1e3 * float(np.median(rtt)), "p99": 1e3 * float(np.percentile(rtt, 99))}
    return {
        "sent": sent,
        "answered": len(rtt),
        "rtt_ms": quantiles if rtt else None,
        "max_error_m": max(errors[200:]) if len(errors) > 200 else None,
        "final_error_m": errors[-1] if errors else None,
        "refused": [s["refused"] for s in statuses if s.get("refused")],
        "stale": [s["stale"] for s in statuses if s.get("stale")],
        "held": bool(held) and all(np.array_equal(c, held[0]) for c in held),
        "verdicts": sorted({s.get("verdict", "") for s in statuses}),
        "node_stdout": out[-2000:],
        "node_stderr": err[-2000:],
        "rmw": os.environ.get("RMW_IMPLEMENTATION", ""),
    }


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
    clik, robot = _processes(args)
    rclpy.init()
    client = Client(run, settings, JointOrder.of(run.robot, "the test robot"))
    client.wait_for_node()
    rtt, errors, sent = _track(client, run, args.targets, clik)
    tracked = sorted({s.get("verdict", "") for s in client.statuses})
    blocked = client.blocked(1.0)  # longer than the settling time (0.5 s)
    held = client.hold()
    clik.terminate()
    robot.terminate()
    out, err = clik.communicate(timeout=30)
    robot.wait(timeout=30)
    client.node.destroy_node()
    rclpy.shutdown()
    print(
        json.dumps(
            {
                **_summary(rtt, errors, sent, held, client.statuses, out, err),
                "verdicts": tracked,
                "blocked": blocked,
            }
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
