"""The live example (clik.viz.live_demo) runs headless: a 1 kHz controller, a 30 Hz view.

The meshcat server listens on 127.0.0.1 and is stopped at the end; the ball's rows
switch on and off as it passes, and the joints stay within their limits.
"""

from __future__ import annotations

import numpy as np

from clik.viz import live_demo
from clik.viz.live import live_server, stop_server
from tests.limits_check import assert_within_limits


def test_the_circle_with_a_live_view() -> None:
    try:
        result, frames = live_demo.run(seconds=2.0, target="circle", view=True, say=False)
        server = live_server()
        assert server.alive and "127.0.0.1" in server.web_url
    finally:
        stop_server()
    assert frames == len(range(0, 2000, live_demo.VIEW_EVERY))  # 30 Hz of 1 kHz ticks
    actions = [(e["action"], e["constraint"]) for e in result.events]
    assert ("activate", "obstacle:ball:panda_hand") in actions
    assert ("release", "obstacle:ball:panda_hand") in actions
    robot = result.robot
    assert robot is not None
    assert_within_limits(result, robot)
    assert result.q.shape == (2000, robot.nq)
    assert np.all(np.isfinite(result.q))


def test_a_random_walk_without_a_view() -> None:
    result, frames = live_demo.run(seconds=1.0, target="walk", view=False, say=False)
    assert frames == 0
    assert result.status == "completed", result.reason  # the ball is not reached in 1 s
    assert result.max_task_error < 5e-3  # positions only: the lag |v| / K, a few mm at most
    assert_within_limits(result, result.robot)


def test_a_box_seen_as_points_slides_toward_the_arm() -> None:
    try:
        result, frames = live_demo.run(seconds=6.0, view=True, say=False, obstacle="cloud")
    finally:
        stop_server()
    assert frames == len(range(0, 6000, live_demo.VIEW_EVERY))  # the cloud redrawn each frame
    assert result.status == "completed", result.reason
    pushed = {e["constraint"] for e in result.events if e["action"] == "activate"}
    assert "cloud:scan:panda_link5" in pushed  # the box reaches the forearm first
    summary = result.summary()
    assert summary["min_cloud_distance"] >= 0.04 - 0.01  # threshold minus the voxel
    assert result.max_task_error < 0.02
    assert_within_limits(result, result.robot)
