"""``clik ros SCENARIO.toml``: the scenario's controller as a ROS 2 node (docs/guides/ros.md).

Without rclpy (the ``ros`` extra, or a sourced ROS 2 install) it says how to get it, exit
code 2. ``--duration S`` stops after S seconds (else Ctrl-C).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from clik.errors import InputError


def cmd_ros(args: argparse.Namespace) -> int:
    """Run ``clik ros`` (see the module docstring)."""
    from clik.ros.node import ClikNode, ros_modules
    from clik.scenarios.ros_table import RosSettings
    from clik.scenarios.runner import build

    ros_modules()  # before the robot loads: a missing rclpy is said first
    if args.duration is not None and not args.duration > 0:
        raise InputError("--duration", "a positive number of seconds", args.duration)
    run = build(Path(args.scenario))
    node = ClikNode(run, RosSettings(**run.scenario.ros))
    s = node.settings
    print(
        f"clik: node '{node.node.get_name()}' at {node.rate:g} Hz: targets on "
        f"{s.prefix}/<task>/target ({', '.join(node.tasks)}), joint states on "
        f"{s.joint_states}, {s.output} commands on {s.output_topic}, status on {s.status}",
        flush=True,
    )
    node.spin(args.duration)
    return 0


def add_ros(sub: Any) -> None:
    """The ``clik ros`` subcommand."""
    r = sub.add_parser("ros", help="run a scenario's controller as a ROS 2 node")
    r.add_argument("scenario", metavar="SCENARIO.toml", help="the scenario (its [ros] table)")
    r.add_argument("--duration", type=float, help="stop after this many seconds")
    r.set_defaults(func=cmd_ros)
