"""The per-tick lines: their keys in the quick report, their quality check, missing peers."""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from benchmarks import suite
from benchmarks.cloud_lines import CLOUD_TICK_LINES, OCTREE_LINE
from benchmarks.config import QUICK
from benchmarks.mink_backend import find_mink
from benchmarks.pink_backend import find_pink
from benchmarks.step_lines import OBSTACLE_RADIUS, OBSTACLES_ONE_ACTIVE, panda_setup
from benchmarks.tick import TICK_LINES, bench_ticks
from benchmarks.tick_clik import clik_tick_variants
from benchmarks.tick_quality import QualityCheck
from benchmarks.tick_variant import tick_reference

SHORT = dataclasses.replace(QUICK, panda_duration=0.02)
"""A 21-tick line: enough to check a line, a fraction of a second."""
FINAL_ERROR = 1e-6
"""clik's position error at its last tick [m] (the target's bound)."""
QUALITY_FIELDS = (
    "max_position_error_m",
    "max_orientation_error_rad",
    "min_clearance_m",
    "velocity_ratio",
)
PEER_LINES = {
    "pink": ("pink_panda_pose", "pink_panda_pose_obstacles", "pink_dual_arm", "pink_humanoid"),
    "mink": ("mink_panda_pose", "mink_panda_pose_obstacles", "mink_dual_arm", "mink_humanoid"),
}
WHOLE_BODY = ("dual_arm", "humanoid")
"""The several-task lines (no obstacle: no clearance), clik's and its peers'."""


def test_the_quick_run_has_every_tick_line(quick):
    out, report = quick
    assert set(report["tick_us"]) == {*TICK_LINES, *CLOUD_TICK_LINES, OCTREE_LINE}
    assert set(report["tick_quality"]) == set(TICK_LINES)
    text = (out / "bench.md").read_text()
    assert "## Tick cost" in text
    for name in TICK_LINES:
        peer = name.split("_")[0] if name.startswith(("pink_", "mink_")) else None
        ran = peer is None or report[peer]["available"]
        assert (name in report["ticks"]) == ran, name
        if not ran:
            assert report["tick_us"][name] is None and report["tick_quality"][name] is None
            continue
        line = report["ticks"][name]
        assert report["tick_us"][name] == line["median_us"] > 0.0
        assert line["p10_us"] <= line["median_us"] <= line["p90_us"], name
        assert line["ticks_per_run"] >= 1 and line["status"] == "completed", (name, line)
        assert f"| {name} |" in text and f"- `{name}`:" in text
    ticks = report["ticks"]["panda_pose"]["ticks_per_run"]
    assert ticks == round(QUICK.panda_duration / 1e-3) + 1  # one tick per sample


def test_tick_quality_is_finite_and_clik_tracks(quick):
    _, report = quick
    for name, quality in report["tick_quality"].items():
        if quality is None:
            continue
        whole_body = name.endswith(WHOLE_BODY)
        fields = [f for f in QUALITY_FIELDS if not (whole_body and f == "min_clearance_m")]
        assert all(math.isfinite(quality[f]) for f in fields), (name, quality)
        assert quality["max_position_error_m"] >= 0 and quality["velocity_ratio"] >= 0
    assert report["tick_error_m"]["panda_pose"] <= FINAL_ERROR
    assert report["tick_quality"]["panda_pose"]["max_position_error_m"] <= 1e-5
    assert report["tick_quality"]["panda_pose"]["velocity_ratio"] <= 1.0 + 1e-9
    # Several tasks per tick: the hands and feet where the references put them, every tick ok.
    dual_arm, humanoid = report["tick_quality"]["dual_arm"], report["tick_quality"]["humanoid"]
    assert dual_arm["max_position_error_m"] <= 1e-5 and humanoid["com_error_m"] <= 1e-5
    assert humanoid["max_error_m.hand"] <= 1e-4
    assert max(humanoid["max_error_m.left_foot"], humanoid["max_error_m.right_foot"]) <= 1e-5
    for name in WHOLE_BODY:
        assert report["ticks"][name]["ticks_not_ok"] == 0, name
        assert report["tick_quality"][name]["velocity_ratio"] <= 1.0 + 1e-9, name
    # The avoiding lines stay out of the spheres (the Panda starts 0.028 m from one).
    for name in ("panda_pose_obstacles", "pink_panda_pose_obstacles", "mink_panda_pose_obstacles"):
        quality = report["tick_quality"][name]
        assert quality is None or quality["min_clearance_m"] > 0.02, (name, quality)


def test_a_short_clik_tick_line_reaches_its_target():
    panda = panda_setup(SHORT)
    reference = tick_reference(panda.trajectory)
    line = clik_tick_variants(panda, reference)[0]
    ticks, wall, info = line.run()
    assert ticks == reference.ticks == 21 and wall > 0
    assert info["status"] == "completed" and info["final_error_m"] <= FINAL_ERROR
    joints = line.joints()
    assert joints.shape == (ticks + 1, panda.robot.nq)
    np.testing.assert_array_equal(joints[0], panda.q0)
    check = QualityCheck(
        panda.robot, panda.task.frame_id, reference, OBSTACLES_ONE_ACTIVE, OBSTACLE_RADIUS
    )
    quality = check(joints)
    assert all(math.isfinite(quality[f]) for f in QUALITY_FIELDS), quality
    assert quality["ticks_checked"] == ticks
    assert quality["max_position_error_m"] <= 1e-5


def test_the_quality_check_reads_the_joints_alone():
    """Joints held at q0: no speed, the clearance at q0, the reference's drift as the error."""
    panda = panda_setup(SHORT)
    reference = tick_reference(panda.trajectory)
    check = QualityCheck(
        panda.robot, panda.task.frame_id, reference, OBSTACLES_ONE_ACTIVE, OBSTACLE_RADIUS
    )
    held = np.tile(panda.q0, (reference.ticks, 1))
    quality = check(held)
    assert quality["velocity_ratio"] == 0.0
    assert quality["min_clearance_m"] == pytest.approx(check.clearance(panda.q0))
    assert 0.0 < quality["min_clearance_m"] < 0.03  # the second sphere, against link 3
    data = panda.robot.model.createData()
    pin.framesForwardKinematics(panda.robot.model, data, panda.q0)
    at_q0 = data.oMf[panda.task.frame_id].translation
    drift = max(np.linalg.norm(pose.translation - at_q0) for pose in reference.poses)
    assert quality["max_position_error_m"] == pytest.approx(drift, abs=1e-12)
    assert drift > 0.0


def test_missing_peers_are_found_missing(monkeypatch):
    monkeypatch.setitem(sys.modules, "mink", None)
    monkeypatch.setitem(sys.modules, "pink", None)
    mink, why = find_mink()
    assert mink is None and why is not None
    assert "mink or mujoco not installed" in why and "clik[bench]" in why
    pink, why = find_pink()
    assert pink is None and why is not None and "pink not installed" in why


def test_missing_peers_are_skipped_with_a_message(quick, monkeypatch, tmp_path):
    """Without pink and mink: their tick lines are left out, said in the log and bench.md."""
    _, done = quick
    monkeypatch.setitem(sys.modules, "mink", None)
    monkeypatch.setitem(sys.modules, "pink", None)

    def measure(config: Any, pink: Any, mink: Any, say: Any) -> suite.Measured:
        assert pink is None and mink is None
        return suite.Measured(  # the quick run's other figures, the tick lines run anew
            done["steps"], done["solve"], done["case_study"], done["memory"], done["sweep"],
            done["zoo"], bench_ticks(SHORT, pink, mink, say), done["controller_session"],
            done["ros"],
        )  # fmt: skip

    monkeypatch.setattr(suite, "measure", measure)
    said: list[str] = []
    report = suite.run_bench(tmp_path, quick=True, log=said.append)
    for peer, lines in PEER_LINES.items():
        assert any(line.startswith(f"{peer} skipped") for line in said), said
        assert report[peer]["available"] is False and report[peer]["reason"]
        for name in lines:
            assert name not in report["ticks"]
            assert report["tick_us"][name] is None and report["tick_quality"][name] is None
    assert set(report["ticks"]) == {"panda_pose", "panda_pose_obstacles", *WHOLE_BODY}
    text = Path(tmp_path / "bench.md").read_text()
    assert "Skipped: pink's tick lines (pink not installed" in text
    assert "Skipped: mink's tick lines (mink or mujoco not installed" in text
    targets = {t["name"]: t for t in report["targets"]}
    for name in ("tick pink / panda_pose", "tick mink / panda_pose_obstacles"):
        assert targets[name]["value"] is None and targets[name]["met"] is None
    assert targets["tick panda_pose, final position error [m]"]["met"] is True
    json.loads((tmp_path / "bench.json").read_text())  # written whole
