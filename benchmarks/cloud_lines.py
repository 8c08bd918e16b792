"""Point-cloud obstacles in ``clik bench`` (issue 45): two tick lines, an update, coal's octree.

- ``cloud_far`` and ``cloud_near`` [us per tick]: :class:`clik.Controller` (compiled
  engine) stepped once per tick on the scene of :mod:`benchmarks.cloud_scene`, timed as
  every tick line (:func:`~benchmarks.step.interleaved_rounds`: the per-tick mean of
  whole runs, median over rounds); the far cloud has no row active, the near one two.
- ``cloud_update_ms``: ``ctl.update_cloud("scan", points)`` with 50k new points (the
  engine rebuilds the voxel spheres and their grid), median over repeats [ms].
- ``coal_octree_cloud`` [us per tick]: coal's octree of the same points asked the
  distance to every link geometry at the near line's joints
  (:mod:`benchmarks.cloud_octree`), and its ratio to ``cloud_near``.

Each line is also checked, from its own record and joints: the hand's tracking error,
every verdict ``ok`` (the session's worst), the rows active per tick, clik's smallest
link-cloud distance (``min_cloud_distance``, a lower bound, >= 0) and coal's octree
distance at sampled ticks; coal's and clik's distances agree within a voxel's diagonal.
"""

from __future__ import annotations

import gc
import math
import time
from collections import Counter
from typing import Any

import numpy as np
import pinocchio as pin

from benchmarks.cloud_octree import OctreeProbe, agreement, octree_line, sampled_ticks
from benchmarks.cloud_scene import (
    CLOUD,
    PLACEMENTS,
    POINTS,
    POSTURE_GAIN,
    RADIUS,
    SEED,
    SETTLE_TICKS,
    SURFACES,
    THRESHOLD,
    VOXEL,
    CloudSetup,
    cloud_controller,
    cloud_obstacle,
    cloud_setup,
    scene_points,
)
from benchmarks.config import DT, BenchConfig, Log
from benchmarks.stats import line_timing, ratio, stats
from benchmarks.step import interleaved_rounds
from benchmarks.step_variant import RunOutcome
from benchmarks.tick_variant import TickVariant

CLOUD_TICK_LINES = ("cloud_far", "cloud_near")
"""The cloud's tick lines (``bench.json``'s ``tick_us`` keys beside the octree's)."""
OCTREE_LINE = "coal_octree_cloud"
"""The octree line's ``tick_us`` key."""
OCTREE_TICKS_PER_ROUND = 10
"""Ticks of the near run the octree line times, per round of the suite (110 in full)."""
ROWS_NEAR = 2
"""Rows the near line holds active on most ticks."""

_SCENE_WORDS = (
    f"Panda hand position task on a {RADIUS:g} m circle (x = const), law (10), posture "
    f"objective; {POINTS // 1000}k points on a table, a box and a shelf (voxel {VOXEL:g} m, "
    f"threshold {THRESHOLD:g} m)"
)
DESCRIPTIONS = {
    "cloud_far": f"clik.Controller, compiled, {_SCENE_WORDS}, the cloud 0.8 m to the left: "
    "no link within the threshold; each tick step(p_d(t_k), v_d(t_k))",
    "cloud_near": f"clik.Controller, compiled, {_SCENE_WORDS}, the arm between the box and "
    "the shelf: elbow and wrist held at the threshold, 2 rows active; each tick "
    "step(p_d(t_k), v_d(t_k))",
    OCTREE_LINE: "coal.OcTree of the same points (resolution = voxel), coal.distance to "
    "each link geometry (clik's convex hulls, placed by pin.updateGeometryPlacements) at "
    "the near line's joints; median per tick over the ticks timed",
}
"""One sentence per line, for ``bench.md``."""


def _session(ctl: Any, setup: CloudSetup, settled: np.ndarray, joints: np.ndarray) -> RunOutcome:
    """One session from the settled joints, one ``step`` per tick (as the tick lines)."""
    ctl.reset(settled)
    positions, velocities = list(setup.positions), list(setup.velocities)
    n = setup.ticks
    commanded = [settled]
    tick = None
    start = time.perf_counter()
    for k in range(n):
        tick = ctl.step(positions[k], velocities[k])
        commanded.append(tick.q)
    wall = time.perf_counter() - start
    joints[:] = commanded
    return n, wall, run_info(ctl, tick)


def run_info(ctl: Any, tick: Any) -> dict[str, Any]:
    """What a session did: its status, task error, rows active per tick, cloud distance.

    Args:
        ctl: The controller after its session.
        tick: Its last tick (None: no tick).

    Returns:
        ``status`` (the worst verdict: ``completed`` when every tick was ``ok``),
        ``violations``, ``max_task_error``, ``final_error_m``, law and engine, the
        active rows per tick (median, mean, max; the ticks with :data:`ROWS_NEAR` and
        with none), the rows activated per link (``activations``) and
        ``min_cloud_distance_m`` (clik's record: a lower bound; None when no link came
        within its search reach, the threshold plus 0.02 m).
    """
    result = ctl.result()
    summary = result.summary()
    active = np.zeros(0) if result.active_count is None else np.asarray(result.active_count)
    activations = Counter(
        e["constraint"].rpartition(":")[2] for e in result.events if e["action"] == "activate"
    )
    return {
        "status": result.status,
        "violations": len(result.violations),
        "max_task_error": float(result.max_task_error),
        "final_error_m": None if tick is None else float(tick.errors["task"][0]),
        "law": ctl.tracker.law,
        "engine": ctl.tracker.engine,
        "active_rows_median": float(np.median(active)) if active.size else 0.0,
        "active_rows_mean": float(active.mean()) if active.size else 0.0,
        "active_rows_max": int(active.max()) if active.size else 0,
        "ticks_with_2_rows": int((active == ROWS_NEAR).sum()),
        "ticks_with_no_row": int((active == 0).sum()),
        "ticks_recorded": int(active.size),
        "activations": dict(sorted(activations.items())),
        "min_cloud_distance_m": _finite(summary.get("min_cloud_distance")),
    }


def _finite(value: Any) -> float | None:
    """``value`` as a float, or None when missing or not finite (JSON has no inf)."""
    return float(value) if value is not None and math.isfinite(value) else None


def hand_quality(setup: CloudSetup, joints: np.ndarray) -> dict[str, Any]:
    """The hand's tracking error and the joint speeds, from a line's joints alone.

    Args:
        setup: The setup (the reference positions).
        joints: ``q_k`` at every tick, ``q_0`` first (n + 1, nq).

    Returns:
        ``max_position_error_m`` (Pinocchio's hand position at ``q_k`` against
        ``p_d(t_k)``) and ``velocity_ratio`` (the largest joint speed over its URDF limit).
    """
    model = setup.robot.model
    data = model.createData()
    frame = model.getFrameId("panda_hand")
    errors = []
    for k in range(setup.ticks):
        pin.framesForwardKinematics(model, data, joints[k])
        errors.append(float(np.linalg.norm(data.oMf[frame].translation - setup.positions[k])))
    speed = np.abs(np.diff(joints, axis=0)) / DT
    vmax = np.asarray(model.velocityLimit, dtype=float)
    return {
        "max_position_error_m": max(errors),
        "velocity_ratio": float((speed / vmax).max()) if len(speed) else 0.0,
    }


def cloud_tick_variant(setup: CloudSetup, placement: str) -> tuple[TickVariant, Any]:
    """The tick line of one placement, and its controller (for the update's timing).

    Args:
        setup: The setup.
        placement: ``"far"`` or ``"near"``.
    """
    name = f"cloud_{placement}"
    ctl, settled = cloud_controller(setup, placement)
    joints = np.zeros((setup.ticks + 1, setup.robot.nq))
    variant = TickVariant(
        name,
        DESCRIPTIONS[name],
        lambda: _session(ctl, setup, settled, joints),
        lambda: joints,
    )
    return variant, ctl


def update_line(ctl: Any, setup: CloudSetup, repeats: int) -> dict[str, Any]:
    """``ctl.update_cloud(CLOUD, points)`` timed, 50k new points each time [ms].

    Two samplings of the scene alternate (the other seed's, then the line's own, so
    the cloud ends as it started), every call a real replacement.

    Args:
        ctl: A controller of the cloud (compiled engine).
        setup: The setup (its points).
        repeats: Timed updates (after one untimed).
    """
    other = scene_points(len(setup.points), SEED + 1)
    clouds = [other, setup.points]
    ctl.update_cloud(CLOUD, clouds[0])  # warm-up
    times = []
    for i in range(repeats):
        gc.collect()
        points = clouds[(i + 1) % 2]
        start = time.perf_counter()
        ctl.update_cloud(CLOUD, points)
        times.append(1e3 * (time.perf_counter() - start))
    if repeats % 2 == 0:
        ctl.update_cloud(CLOUD, setup.points)
    s = stats(times)
    return {
        "median_ms": s["median"],
        "p10_ms": s["p10"],
        "p90_ms": s["p90"],
        "min_ms": s["min"],
        "repeats": s["n"],
        "points": len(setup.points),
        "engine": ctl.tracker.engine,
    }


def scene_info(setup: CloudSetup) -> dict[str, Any]:
    """The scene in words and numbers, for ``bench.json``."""
    return {
        "points": len(setup.points),
        "seed": SEED,
        "objects": list(SURFACES),
        "voxel_m": VOXEL,
        "threshold_m": THRESHOLD,
        "placements_m": {name: list(p) for name, p in PLACEMENTS.items()},
        "task": "a position task of panda_hand",
        "circle_radius_m": RADIUS,
        "ticks_per_run": setup.ticks,
        "posture_gain": POSTURE_GAIN,
        "settle_ticks": SETTLE_TICKS,
    }


def line_checks(lines: dict[str, Any], octree: dict[str, Any]) -> dict[str, bool]:
    """The structural facts of the lines (never a time).

    Args:
        lines: ``cloud_far`` and ``cloud_near`` as :func:`bench_cloud` reports them.
        octree: The octree line (its ``agreement``).
    """
    far, near = lines["cloud_far"], lines["cloud_near"]
    ticks = max(near["ticks_recorded"], 1)
    return {
        "far_no_active_row": far["active_rows_max"] == 0,
        "near_two_rows_on_most_ticks": near["ticks_with_2_rows"] > ticks / 2,
        "every_verdict_ok": far["status"] == near["status"] == "completed",
        "min_cloud_distance_nonnegative": all(
            line["min_cloud_distance_m"] is None or line["min_cloud_distance_m"] >= 0.0
            for line in (far, near)
        ),
        "octree_agrees_with_spheres": octree["agreement"]["agree"],
    }


def clearance(probe: OctreeProbe, joints: np.ndarray, samples: int) -> dict[str, Any]:
    """The octree's distance to the nearest link over sampled ticks of a line [m].

    Args:
        probe: The line's cloud as an octree.
        joints: The line's joints.
        samples: Ticks asked.

    Returns:
        ``min_octree_distance_m`` and the link it was (``min_octree_link``).
    """
    ticks = sampled_ticks(len(joints), samples)
    rows = np.array([probe.distances(joints[k]) for k in ticks])
    k, link = np.unravel_index(int(np.argmin(rows)), rows.shape)
    return {"min_octree_distance_m": float(rows[k, link]), "min_octree_link": probe.labels[link]}


def _octree_figures(
    setup: CloudSetup, joints: dict[str, np.ndarray], samples: int
) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """The octree line on the near joints, its agreement, and both lines' clearances."""
    near = OctreeProbe(setup.robot, cloud_obstacle(setup, "near"))
    line = octree_line(near, joints["cloud_near"], samples)
    rows = line.pop("distances")
    line["agreement"] = agreement(
        near, joints["cloud_near"], np.array(line["ticks"]), rows, THRESHOLD
    )
    k, link = np.unravel_index(int(np.argmin(rows)), rows.shape)
    near_clearance = {
        "min_octree_distance_m": float(rows[k, link]),
        "min_octree_link": near.labels[link],
    }
    far = OctreeProbe(setup.robot, cloud_obstacle(setup, "far"))
    far_clearance = clearance(far, joints["cloud_far"], max(2, samples // 10))
    return line, {"cloud_near": near_clearance, "cloud_far": far_clearance}


def bench_cloud(config: BenchConfig, log: Log) -> dict[str, Any]:
    """The cloud lines: far and near ticks, a 50k-point update, coal's octree per tick.

    Args:
        config: Sizes of the suite (rounds, the run's duration).
        log: Progress callback.

    Returns:
        ``tick_us`` (``cloud_far``, ``cloud_near``, ``coal_octree_cloud`` [us per tick]),
        ``update_ms`` [ms], ``octree_over_near``, and the details: ``scene``, ``lines``
        (each tick line's timing, run info and quality), ``update``, ``octree`` and
        ``checks``.
    """
    setup = cloud_setup(config)
    built = {p: cloud_tick_variant(setup, p) for p in ("far", "near")}
    variants = [variant for variant, _ in built.values()]
    samples, infos, ticks_of = interleaved_rounds(variants, config.rounds, log, "cloud tick")
    joints = {v.name: v.joints().copy() for v in variants}
    lines: dict[str, Any] = {}
    for v in variants:
        lines[v.name] = {
            **line_timing(v.description, samples[v.name], "ticks_per_run", ticks_of[v.name]),
            **infos[v.name],
            "quality": hand_quality(setup, joints[v.name]),
        }
    log("  cloud update, 50k points")
    update = update_line(built["near"][1], setup, config.rounds)
    log("  coal octree, every link per tick")
    octree, clearances = _octree_figures(setup, joints, OCTREE_TICKS_PER_ROUND * config.rounds)
    octree["description"] = DESCRIPTIONS[OCTREE_LINE]
    for name, figures in clearances.items():
        lines[name]["quality"].update(figures)
    tick_us = {name: lines[name]["median_us"] for name in CLOUD_TICK_LINES}
    tick_us[OCTREE_LINE] = octree["median_us"]
    return {
        "tick_us": tick_us,
        "update_ms": update["median_ms"],
        "octree_over_near": ratio(octree["median_us"], tick_us["cloud_near"]),
        "scene": scene_info(setup),
        "lines": lines,
        "update": update,
        "octree": octree,
        "checks": line_checks(lines, octree),
    }
