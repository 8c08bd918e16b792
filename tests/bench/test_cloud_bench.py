"""The point-cloud lines of `clik bench` (issue 45), run short: their structure, never a time."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np
import pytest

from benchmarks import suite
from benchmarks.cloud_lines import CLOUD_TICK_LINES, OCTREE_LINE, bench_cloud
from benchmarks.cloud_octree import OctreeProbe, agreement, octree_line
from benchmarks.cloud_scene import (
    CLOUD,
    POINTS,
    THRESHOLD,
    VOXEL,
    CloudSetup,
    cloud_controller,
    cloud_obstacle,
    cloud_setup,
    scene_points,
)
from benchmarks.config import QUICK
from benchmarks.report_cloud import cloud_section
from benchmarks.targets import load_targets

SHORT = dataclasses.replace(QUICK, panda_duration=0.2)
"""201 ticks of the small circle: enough for the rows, a fraction of a second."""


@pytest.fixture(scope="module")
def setup() -> CloudSetup:
    return cloud_setup(SHORT)


def session(setup: CloudSetup, placement: str) -> tuple[list[Any], np.ndarray, Any]:
    """One session of a line's controller, tick by tick: its ticks, its joints, its result."""
    ctl, settled = cloud_controller(setup, placement)
    ticks, joints = [], [settled]
    for k in range(setup.ticks):
        tick = ctl.step(setup.positions[k], setup.velocities[k])
        ticks.append(tick)
        joints.append(tick.q)
    return ticks, np.array(joints), ctl.result()


def cloud_rows(tick: Any) -> list[str]:
    return [name for name in tick.active if name.startswith(f"cloud:{CLOUD}:")]


def test_the_scene_is_50k_points_on_three_objects():
    points = scene_points()
    assert points.shape == (POINTS, 3) and np.isfinite(points).all()
    assert np.array_equal(points, scene_points())  # fixed seed
    assert not np.array_equal(points, scene_points(seed=1))
    on_table = np.isclose(points[:, 2], 0.30)
    on_shelf = np.isclose(points[:, 0], -0.265)
    assert 0 < on_table.sum() < POINTS and 0 < on_shelf.sum() < POINTS
    assert (~on_table & ~on_shelf).sum() > 0  # the box


def test_far_has_no_active_row_and_every_tick_ok(setup):
    ticks, _, result = session(setup, "far")
    assert len(ticks) == setup.ticks
    assert all(cloud_rows(t) == [] for t in ticks)
    assert all(t.verdict == "ok" for t in ticks)
    assert result.status == "completed" and result.max_task_error < 1e-5
    nearest = result.summary()["min_cloud_distance"]
    assert nearest >= THRESHOLD  # nothing within reach: no distance below it recorded


def test_near_holds_two_rows_on_most_ticks_every_tick_ok(setup):
    ticks, joints, result = session(setup, "near")
    counts = np.array([len(cloud_rows(t)) for t in ticks])
    assert (counts == 2).sum() > len(ticks) / 2, np.bincount(counts)
    assert np.median(counts) == 2
    assert all(t.verdict == "ok" for t in ticks), {t.verdict for t in ticks}
    links = {name.rpartition(":")[2] for t in ticks for name in cloud_rows(t)}
    assert "panda_link6" in links and links & {"panda_link3", "panda_link4"}
    summary = result.summary()
    assert 0.0 <= summary["min_cloud_distance"] <= THRESHOLD
    assert result.status == "completed" and result.max_task_error < 1e-3
    assert np.isfinite(joints).all()


def test_the_octree_agrees_with_the_spheres_within_a_voxel_diagonal(setup):
    _, joints, _ = session(setup, "near")
    probe = OctreeProbe(setup.robot, cloud_obstacle(setup, "near"))
    line = octree_line(probe, joints, samples=4)
    rows = line.pop("distances")
    assert rows.shape == (line["ticks_timed"], len(probe.labels)) == (4, 17)
    assert np.isfinite(rows).all() and line["median_us"] > 0
    assert line["resolution_m"] == VOXEL
    checked = agreement(probe, joints, np.array(line["ticks"]), rows, THRESHOLD)
    assert checked["pairs"] > 0 and checked["agree"], checked
    assert checked["max_abs_difference_m"] <= math.sqrt(3.0) * VOXEL
    # the links held at the threshold are near the octree's cells too
    spheres = probe.nearest_spheres(joints[-1], THRESHOLD, 2 * THRESHOLD)
    held = [probe.labels.index("panda_link6")]
    assert np.all(spheres[held] <= THRESHOLD + 1e-3)
    assert np.all(np.abs(rows[-1][held] - spheres[held]) <= math.sqrt(3.0) * VOXEL)


def test_bench_cloud_reports_its_figures_and_checks():
    cloud = bench_cloud(SHORT, lambda _line: None)
    json.dumps(cloud, allow_nan=False)  # bench.json's content
    assert set(cloud["tick_us"]) == {*CLOUD_TICK_LINES, OCTREE_LINE}
    assert all(v > 0 and math.isfinite(v) for v in cloud["tick_us"].values())
    assert cloud["update_ms"] > 0 and cloud["update"]["points"] == POINTS
    assert cloud["octree_over_near"] == pytest.approx(
        cloud["tick_us"][OCTREE_LINE] / cloud["tick_us"]["cloud_near"]
    )
    assert all(cloud["checks"].values()), cloud["checks"]
    far, near = cloud["lines"]["cloud_far"], cloud["lines"]["cloud_near"]
    assert far["active_rows_max"] == 0 and far["min_cloud_distance_m"] is None
    assert near["active_rows_median"] == 2 and near["status"] == "completed"
    for line in (far, near):
        assert line["quality"]["max_position_error_m"] < 1e-3
        assert line["quality"]["min_octree_distance_m"] > 0
        assert line["engine"] == "compiled"
    text = "\n".join(cloud_section({"cloud": cloud}))
    assert "## Point-cloud obstacles" in text
    for name in (*CLOUD_TICK_LINES, OCTREE_LINE):
        assert f"- `{name}`:" in text


def test_the_suite_carries_the_cloud_keys_and_targets():
    assert {"tick_us.cloud_far", "tick_us.cloud_near", "tick_us.coal_octree_cloud"} <= set(
        suite.REQUIRED_KEYS
    )
    assert "cloud_update_ms" in suite.REQUIRED_KEYS
    unmeasured = suite.Measured({}, {}, {}, {}, {}, {}, {}, {}, {})
    assert suite.cloud_tick_us(unmeasured) == dict.fromkeys((*CLOUD_TICK_LINES, OCTREE_LINE))
    assert cloud_section({"cloud": {}})[-1] == "Not measured."
    by_measure = {(t.measure, t.over): t for t in load_targets()}
    wanted = {
        ("tick_us.cloud_far", None): ("<=", 10.0),
        ("tick_us.cloud_near", None): ("<=", 30.0),
        ("cloud_update_ms", None): ("<=", 20.0),
        ("tick_us.coal_octree_cloud", "tick_us.cloud_near"): (">=", 20.0),
    }
    for key, (op, bound) in wanted.items():
        assert (by_measure[key].op, by_measure[key].bound) == (op, bound), key
