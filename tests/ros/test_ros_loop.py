"""``clik ros`` in a ROS 2 loop on loopback only (benchmarks/ros_loop.py, docs/guides/ros.md).

The node, a test robot that lags (first-order, 5 ms, plus 2 ticks of delay) and a client
run in a private network namespace with only ``lo`` up, made here with ``unshare -n``
(root, as in CI), with DDS discovery limited to localhost. Nothing is sent to any other
address. Skipped, saying why, without rclpy (the ``ros`` extra) or without the rights to
make a namespace.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.ros_line import run_loop, unavailable

pytest.importorskip("rclpy", reason="rclpy is not installed: pip install 'clik[ros]'")


def test_the_loop_answers_tracks_refuses_and_holds(tmp_path: Path) -> None:
    why = unavailable()
    if why:
        pytest.skip(f"the ROS loop runs only in a private network namespace: {why}")
    out = run_loop(tmp_path, 3000)
    print(json.dumps({k: out[k] for k in ("sent", "answered", "rtt_ms", "max_error_m")}))
    assert out["node_stderr"] == ""
    assert out["answered"] == out["sent"] == 3000  # every target answered
    assert out["rtt_ms"]["median"] < 50.0
    # the hand on the lagging robot's joints, against the circle (gain 200 1/s, the stable
    # range of (M4) for this robot): the acceptance bound of the offline lag test
    assert out["max_error_m"] < 2e-3
    assert out["final_error_m"] < 2e-3
    refused = out["refused"]
    assert refused and refused[0]["field"] == "/clik/task/target: pose.position"
    assert "finite" in refused[0]["message"]
    assert any("/clik/task/target" in s for s in out["stale"])  # said when the targets stop
    assert out["held"]  # and the command held
    assert out["verdicts"] == ["ok"]  # while tracking
    blocked = out["blocked"]  # a target out of reach: said, with its reason
    assert blocked and blocked[0]["verdict"] in ("deadlock", "off_track")
    assert blocked[0]["reason"]


@pytest.mark.parametrize("output", ["position", "velocity"])
def test_the_other_outputs_drive_the_robot(tmp_path: Path, output: str) -> None:
    why = unavailable()
    if why:
        pytest.skip(f"the ROS loop runs only in a private network namespace: {why}")
    out = run_loop(tmp_path, 1000, output)
    print(json.dumps({k: out[k] for k in ("sent", "answered", "rtt_ms", "max_error_m")}))
    assert out["node_stderr"] == ""
    assert out["answered"] == out["sent"] == 1000
    assert out["max_error_m"] < 5e-3  # the robot integrates velocities, or takes positions
    assert out["held"]  # held: the same positions, or zero velocities
