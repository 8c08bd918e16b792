"""The ``ros`` line of ``clik bench``: the ROS 2 loop of :mod:`benchmarks.ros_loop`, timed.

The loop (the ``clik ros`` node, a robot that lags, a client sending the Panda circle one
target at a time) runs in a private network namespace with only ``lo`` up, made here with
``unshare -n`` (root), DDS discovery limited to localhost: nothing leaves the machine.
Without rclpy (the ``ros`` extra) or without the rights to make a namespace, the line
says why it did not run.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from benchmarks.config import BenchConfig, Log

LOOP = Path(__file__).with_name("ros_loop.py")
CIRCLE = Path(__file__).resolve().parents[1] / "clik" / "scenarios" / "panda_circle.toml"
ROS_TABLE = "\n[ros]\ntimeout = 0.25\n"
"""Appended to the Panda circle: the loop's scenario."""
GAIN = 200.0
"""The loop's gain [1/s] (the circle's is 1000): a robot lagging 5 ms + 2 ticks, fed back,
is stable for gain * dt below about 0.36 (docs/method.md, (M4))."""
TARGETS = 2000
"""Targets per bench run."""


def unavailable() -> str:
    """Why the loop cannot run here ("" when it can)."""
    if importlib.util.find_spec("rclpy") is None:
        return "rclpy is not installed (pip install 'clik[ros]')"
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare or ip is missing (util-linux, iproute2)"
    probe = subprocess.run(
        ["unshare", "-n", "sh", "-c", "ip link set lo up"], capture_output=True, text=True
    )
    if probe.returncode != 0:
        return f"no private network namespace (unshare -n: {probe.stderr.strip()}; needs root)"
    return ""


def run_loop(folder: Path, targets: int, output: str = "trajectory") -> dict[str, Any]:
    """The loop on the Panda circle in a private namespace; its JSON (see ros_loop.py).

    Args:
        folder: Where to write the scenario.
        targets: How many targets the client sends.
        output: The node's ``[ros] output``.
    """
    scenario = folder / "ros_circle.toml"
    text = CIRCLE.read_text().replace("gain = 1000.0", f"gain = {GAIN}")
    scenario.write_text(text + ROS_TABLE + f'output = "{output}"\n')
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_DOMAIN_ID": "42"}  # fmt: skip
    command = f"ip link set lo up && exec {sys.executable} {LOOP} {scenario} --targets {targets}"
    done = subprocess.run(
        ["unshare", "-n", "sh", "-c", command], capture_output=True, text=True, env=env,
        timeout=600,
    )  # fmt: skip
    if done.returncode != 0:
        raise RuntimeError(f"the ROS loop failed: {done.stderr[-3000:]}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def bench_ros(config: BenchConfig, say: Log) -> dict[str, Any]:
    """The ``ros`` line: round trip [ms] (median, p99), targets answered, tracking error.

    Args:
        config: Sizes of the suite (unused: the line's size is :data:`TARGETS`).
        say: Progress callback.
    """
    del config
    why = unavailable()
    if why:
        say(f"ros: not run: {why}")
        return {"skipped": why}
    with tempfile.TemporaryDirectory(prefix="clik-ros-") as folder:
        out = run_loop(Path(folder), TARGETS)
    return {
        "skipped": None,
        "sent": out["sent"],
        "answered": out["answered"],
        "rtt_ms": out["rtt_ms"],
        "max_error_m": out["max_error_m"],
        "final_error_m": out["final_error_m"],
        "text": (
            f"clik ros on the Panda circle (gain {GAIN:g} 1/s), a robot lagging 2 ticks + 5 ms, "
            "a client sending one target at a time (pose + twist) and waiting for its answer; "
            "loopback only"
        ),
    }
