"""``clik ros`` in a ROS 2 loop on loopback only (tests/ros/loop.py, docs/guides/ros.md).

The node, a test robot that lags (first-order, 5 ms, plus 2 ticks of delay) and a client
run in a private network namespace with only ``lo`` up, made here with ``unshare -n``
(root, as in CI), with DDS discovery limited to localhost. Nothing is sent to any other
address. Skipped, saying why, without rclpy (the ``ros`` extra) or without the rights to
make a namespace.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from clik.scenarios import runner

pytest.importorskip("rclpy", reason="rclpy is not installed: pip install 'clik[ros]'")

LOOP = Path(__file__).with_name("loop.py")
SCENARIOS = Path(runner.__file__).parent


def _namespace_ok() -> str:
    """Why a private network namespace cannot be made here ("" when it can)."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare or ip is missing"
    probe = subprocess.run(
        ["unshare", "-n", "sh", "-c", "ip link set lo up"], capture_output=True, text=True
    )
    return "" if probe.returncode == 0 else f"unshare -n failed: {probe.stderr.strip()}"


def _loop(tmp_path: Path, targets: int) -> dict:  # type: ignore[type-arg]
    why = _namespace_ok()
    if why:
        pytest.skip(f"no private network namespace ({why}): the ROS test runs only there")
    scenario = tmp_path / "circle.toml"
    scenario.write_text((SCENARIOS / "panda_circle.toml").read_text() + "\n[ros]\ntimeout = 0.25\n")
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_DOMAIN_ID": "42"}  # fmt: skip
    command = f"ip link set lo up && exec {sys.executable} {LOOP} {scenario} --targets {targets}"
    done = subprocess.run(
        ["unshare", "-n", "sh", "-c", command], capture_output=True, text=True, env=env,
        timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def test_the_loop_answers_tracks_refuses_and_holds(tmp_path: Path) -> None:
    out = _loop(tmp_path, 3000)
    print(json.dumps({k: out[k] for k in ("sent", "answered", "rtt_ms", "max_error_m")}))
    assert out["node_stderr"] == ""
    assert out["answered"] == out["sent"] == 3000  # every target answered
    assert out["rtt_ms"]["median"] < 50.0
    # the hand on the lagging robot's joints, against the circle
    assert out["max_error_m"] < 2e-3
    assert out["final_error_m"] < 2e-3
    refused = out["refused"]
    assert refused and refused[0]["field"] == "/clik/task/target: pose.position"
    assert "finite" in refused[0]["message"]
    assert any("/clik/task/target" in s for s in out["stale"])  # said when the targets stop
    assert out["held"]  # and the command held
    assert out["verdicts"] == ["ok"]
