"""The ``clik`` ROS 2 node: a :class:`~clik.control.controller.Controller` at ``1 / dt`` Hz.

Each tick (a timer of the node's rate) the controller steps once on the newest target
of every task (a task whose target has not come yet holds where it started), the
feed-forward twists received, the obstacles moved, and the newest joint state as the
measured joints when one came since the last tick; the next joints go out as the
configured command. A target or joint state older than ``timeout`` holds the last
command (zero velocity with ``output = "velocity"``) and says so on the status topic. A
bad message is refused, one by one: the last good value stays, and the status topic names
the topic, the field and what was expected; the node never stops on bad input.

The status topic (``std_msgs/String``) carries JSON: ``verdict``, ``reason``, ``t``,
``k``, ``events`` (this tick's), ``stale`` (topics and ages), ``refused`` (the message
refused: topic, field, message), sent whenever the verdict changes, an event happens, a
message is refused or a hold begins or ends. ``<prefix>/answered`` (``std_msgs/Header``)
carries, after each command that used a new target, that target's stamp (``frame_id``:
the task's name): a client's round trip.
"""

from __future__ import annotations

import json
import signal
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from clik.control.from_scenario import controller_of, held_target
from clik.errors import ClikError, InputError
from clik.model.joint_order import JointOrder
from clik.ros import messages
from clik.scenarios.ros_table import RosSettings
from clik.tasks.goal import Goal
from clik.tasks.posture_task import PostureTask
from clik.tasks.task import Task

NODE_NAME = "clik"


def ros_modules() -> dict[str, Any]:
    """Rclpy and the message classes the node uses.

    Raises:
        InputError: rclpy is not importable, with how to get it.
    """
    try:
        import rclpy
        from builtin_interfaces.msg import Duration
        from geometry_msgs.msg import PointStamped, PoseStamped, TwistStamped
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray, Header, String
        from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    except ImportError as exc:
        raise InputError(
            "ros",
            "rclpy and the ROS 2 messages: pip install 'clik[ros]' (the PyPI wheels), or "
            f"source a ROS 2 install ({exc})",
        ) from None
    return dict(
        rclpy=rclpy, Duration=Duration, PointStamped=PointStamped, PoseStamped=PoseStamped,
        TwistStamped=TwistStamped, JointState=JointState, Float64MultiArray=Float64MultiArray,
        Header=Header, String=String, JointTrajectory=JointTrajectory,
        JointTrajectoryPoint=JointTrajectoryPoint,
    )  # fmt: skip


@dataclass
class _Latest:
    """The newest value of a topic, when it came, and whether a tick used it yet."""

    value: Any = None
    at: float = -np.inf  # time.monotonic() of its arrival
    stamp: Any = None  # its header stamp
    new: bool = False


@dataclass
class _State:
    targets: dict[str, _Latest] = field(default_factory=dict)
    twists: dict[str, _Latest] = field(default_factory=dict)
    joints: _Latest = field(default_factory=_Latest)
    moves: dict[str, np.ndarray] = field(default_factory=dict)
    verdict: str = ""
    holding: tuple[str, ...] = ()
    last_q: np.ndarray | None = None


class ClikNode:
    """The node (see the module docstring): build, then :meth:`spin`.

    Args:
        run: The scenario's :class:`~clik.scenarios.runner.Run`.
        settings: Its ``[ros]`` table.
    """

    def __init__(self, run: Any, settings: RosSettings) -> None:
        self.ros = ros = ros_modules()
        self.settings = settings
        self.controller = ctl = controller_of(run, settings.measured_jump)
        self.robot = ctl.robot
        self.order = JointOrder.of(self.robot, "clik ros commands one value per joint")
        self.rate = settings.rate or 1.0 / ctl.dt
        goals = run.goals or [Goal(run.task, name="task")]
        self.tasks = {name: g.task for name, g in zip(ctl.names, goals, strict=True)}
        self.state = _State()
        for name, task in self.tasks.items():
            self.state.targets[name] = _Latest(held_target(task, ctl.q))
        constraints = run.tracker.constraints
        self.obstacles = [o.name for o in constraints.obstacles] if constraints else []
        full = self.robot.model
        self._index = {n: i for i, n in enumerate(self.order.names)}
        self._others = {str(full.names[j]) for j in range(1, full.njoints)} - set(self._index)
        self._others |= set(getattr(self.robot, "locked", {}) or {})
        self._data = full.createData()
        if not ros["rclpy"].ok():
            # clik's own SIGINT/SIGTERM handling (spin): rclpy's would shut the context
            # down under a running callback
            from rclpy.signals import SignalHandlerOptions

            ros["rclpy"].init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = node = ros["rclpy"].create_node(NODE_NAME)
        self._subscribe(node)
        kind = (
            ros["JointTrajectory"] if settings.output == "trajectory" else ros["Float64MultiArray"]
        )
        self._command = node.create_publisher(kind, settings.output_topic, 10)
        self._status = node.create_publisher(ros["String"], settings.status, 10)
        self._answered = node.create_publisher(ros["Header"], f"{settings.prefix}/answered", 10)
        self._timer = node.create_timer(1.0 / self.rate, self.tick)

    # -- subscriptions -------------------------------------------------------------------

    def _subscribe(self, node: Any) -> None:
        ros, s = self.ros, self.settings
        for name, task in self.tasks.items():
            pose = isinstance(task, Task) and task.has_orientation
            if isinstance(task, PostureTask):
                continue  # holds its start: no topic (docs/guides/ros.md)
            kind = ros["PoseStamped"] if pose else ros["PointStamped"]
            node.create_subscription(kind, s.target_topic(name), self._on_target(name), 10)
            node.create_subscription(
                ros["TwistStamped"], s.twist_topic(name), self._on_twist(name), 10
            )
        node.create_subscription(ros["JointState"], s.joint_states, self._on_joints, 10)
        kind = ros["PointStamped"] if s.obstacle_message == "point" else ros["PoseStamped"]
        for name in self.obstacles:
            node.create_subscription(kind, s.obstacle_topic(name), self._on_obstacle(name), 10)

    def _placement(self, frame: str) -> pin.SE3 | None:
        """A robot frame's world placement at the commanded joints (None: not a frame)."""
        model = self.robot.model
        if not model.existFrame(frame):
            return None
        pin.framesForwardKinematics(model, self._data, self.controller.q)
        return self._data.oMf[model.getFrameId(frame)]

    def _refused(self, exc: InputError) -> None:
        self._send_status(refused={"field": exc.field, "message": str(exc)})

    def _on_target(self, name: str) -> Any:
        task, topic, world = (
            self.tasks[name],
            self.settings.target_topic(name),
            self.settings.world_frame,
        )

        def read(msg: Any) -> None:
            try:
                if isinstance(task, Task) and task.has_orientation:
                    pose = messages.pose(msg, topic, world, self._placement)
                    value = pose if task.has_position else pose[:3, :3]
                else:
                    value = messages.point(msg, topic, world, self._placement)
            except InputError as exc:
                self._refused(exc)
                return
            self.state.targets[name] = _Latest(value, time.monotonic(), msg.header.stamp, True)

        return read

    def _on_twist(self, name: str) -> Any:
        task, topic, world = (
            self.tasks[name],
            self.settings.twist_topic(name),
            self.settings.world_frame,
        )

        def read(msg: Any) -> None:
            try:
                value = messages.twist(msg, topic, world, self._placement)
            except InputError as exc:
                self._refused(exc)
                return
            if isinstance(task, Task) and not (task.has_position and task.has_orientation):
                value = value[:3] if task.has_position else value[3:]
            elif not isinstance(task, Task):
                value = value[:3]
            self.state.twists[name] = _Latest(value, time.monotonic(), msg.header.stamp, True)

        return read

    def _on_joints(self, msg: Any) -> None:
        try:
            values = messages.joint_values(
                msg, self.settings.joint_states, self._index, self._others
            )
        except InputError as exc:
            self._refused(exc)
            return
        self.state.joints = _Latest(values, time.monotonic(), msg.header.stamp, True)

    def _on_obstacle(self, name: str) -> Any:
        topic, world, pose = (
            self.settings.obstacle_topic(name),
            self.settings.world_frame,
            self.settings.obstacle_message != "point",
        )

        def read(msg: Any) -> None:
            try:
                if pose:
                    value = messages.pose(msg, topic, world, self._placement)[:3, 3]
                else:
                    value = messages.point(msg, topic, world, self._placement)
            except InputError as exc:
                self._refused(exc)
                return
            self.state.moves[name] = value

        return read

    # -- the tick ------------------------------------------------------------------------

    def _stale(self, now: float) -> dict[str, float]:
        """The topics older than the timeout (of those received at least once): ages [s]."""
        s, out = self.settings, {}
        for name, latest in self.state.targets.items():
            if latest.at > -np.inf and now - latest.at > s.timeout:
                out[s.target_topic(name)] = now - latest.at
        j = self.state.joints
        if j.at > -np.inf and now - j.at > s.timeout:
            out[s.joint_states] = now - j.at
        return out

    def tick(self) -> None:
        """One tick: step the controller and publish (see the module docstring)."""
        now, st = time.monotonic(), self.state
        stale = self._stale(now)
        if stale:
            if tuple(stale) != st.holding:  # said when the set of stale topics changes
                st.holding = tuple(stale)
                ages = {topic: round(age, 4) for topic, age in stale.items()}
                self._send_status(stale=ages, timeout=self.settings.timeout)
            self._publish_hold()
            return
        if st.holding:
            st.holding = ()
            self._send_status(stale={})
        targets = {n: v.value for n, v in st.targets.items()}
        velocities = {}  # a twist feeds forward once, with the tick that reads it
        for name, twist in st.twists.items():
            if twist.new:
                velocities[name] = twist.value
                twist.new = False
        measured = None
        if st.joints.new:
            measured = self.order.configuration(self.controller.q, st.joints.value)
            st.joints.new = False
        moves, st.moves = st.moves, {}
        try:
            tick = self._step(targets, velocities, moves, measured)
        except ClikError as exc:
            self._send_status(refused={"field": "tick", "message": str(exc)})
            self._publish_hold()
            return
        self._publish(tick.q, tick.qdot)
        self._answer()
        if tick.verdict != st.verdict or tick.events:
            st.verdict = tick.verdict
            self._send_status(tick=tick)

    def _step(
        self,
        targets: dict[str, Any],
        velocities: dict[str, Any],
        moves: dict[str, Any],
        measured: np.ndarray | None,
    ) -> Any:
        ctl = self.controller
        single = len(self.tasks) == 1
        t = next(iter(targets.values())) if single else targets
        v = (next(iter(velocities.values())) if velocities else None) if single else velocities
        kwargs: dict[str, Any] = {}
        if measured is not None:
            kwargs["q_measured"] = measured
        return ctl.step(t, v if single else (v or None), obstacles=moves or None, **kwargs)

    def _answer(self) -> None:
        for name, latest in self.state.targets.items():
            if latest.new:
                latest.new = False
                self._answered.publish(self.ros["Header"](stamp=latest.stamp, frame_id=name))

    def _publish(self, q: np.ndarray, qdot: np.ndarray) -> None:
        angles = self.order.angles(q)[0]
        rates = np.asarray(qdot)[self.order.idx_v]
        self.state.last_q = angles
        self._send_command(angles, rates)

    def _publish_hold(self) -> None:
        if self.state.last_q is None:
            self.state.last_q = self.order.angles(self.controller.q)[0]
        self._send_command(self.state.last_q, np.zeros(len(self.order.names)))

    def _send_command(self, angles: np.ndarray, rates: np.ndarray) -> None:
        ros, output = self.ros, self.settings.output
        if output == "trajectory":
            msg = ros["JointTrajectory"]()
            msg.joint_names = list(self.order.names)
            point = ros["JointTrajectoryPoint"]()
            point.positions = [float(x) for x in angles]
            point.velocities = [float(x) for x in rates]
            step = 1.0 / self.rate
            point.time_from_start = ros["Duration"](
                sec=int(step), nanosec=round((step % 1.0) * 1e9)
            )
            msg.points = [point]
        else:
            msg = ros["Float64MultiArray"]()
            msg.data = [float(x) for x in (rates if output == "velocity" else angles)]
        self._command.publish(msg)

    def _send_status(self, tick: Any = None, **extra: Any) -> None:
        ctl = self.controller
        body: dict[str, Any] = {
            "t": ctl.k * ctl.dt,
            "k": ctl.k,
            "verdict": self.state.verdict or "ok",
        }
        if tick is not None:
            body.update(verdict=tick.verdict, reason=tick.reason, events=list(tick.events))
        body.update(extra)
        self._status.publish(self.ros["String"](data=json.dumps(body, default=str)))

    # -- running -------------------------------------------------------------------------

    def spin(self, duration: float | None = None) -> None:
        """Run until ``duration`` [s] has passed, Ctrl-C or SIGTERM; then shut down.

        rclpy's events executor (C++ callbacks dispatch) when this rclpy has it: the
        default executor's Python wait set costs about a millisecond per callback at
        2 kHz of timer and joint states; else the default one.
        """
        rclpy = self.ros["rclpy"]
        executor = _executor(rclpy)
        executor.add_node(self.node)
        end = None if duration is None else time.monotonic() + duration
        stop: list[int] = []
        before = None
        if threading.current_thread() is threading.main_thread():
            before = signal.signal(signal.SIGTERM, lambda number, frame: stop.append(number))
        try:
            while not stop and rclpy.ok() and (end is None or time.monotonic() < end):
                executor.spin_once(timeout_sec=0.05)
        except KeyboardInterrupt:  # Ctrl-C: stopped between callbacks, then cleaned up
            pass
        finally:
            if before is not None:
                signal.signal(signal.SIGTERM, before)
            executor.shutdown()
            self.node.destroy_node()
            rclpy.try_shutdown()


def _executor(rclpy: Any) -> Any:
    """Rclpy's events executor when it has one, else its single-threaded executor."""
    try:
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    except ImportError:
        from rclpy.executors import SingleThreadedExecutor

        return SingleThreadedExecutor()
