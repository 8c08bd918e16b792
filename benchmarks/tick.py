"""Tick cost [us per tick]: clik's controller, pink and mink stepped once per 1 ms tick.

Every tick line (:mod:`benchmarks.tick_clik`, :mod:`benchmarks.tick_pink`,
:mod:`benchmarks.tick_mink`) runs the Panda's pose task on the shipped circle, and the
whole-body lines (:mod:`benchmarks.tick_whole_body`) several tasks on Baxter and Talos, one
Python call per tick, timed over the whole per-tick loop; its figure is the median
over interleaved rounds of the per-tick mean (:func:`~benchmarks.step.interleaved_rounds`,
as the step lines). Its joints then go through the same quality check
(:class:`~benchmarks.tick_quality.QualityCheck`). A library that is not installed
leaves its lines out.
"""

from __future__ import annotations

from typing import Any

from benchmarks.config import BenchConfig, Log
from benchmarks.mink_backend import Mink
from benchmarks.pink_backend import Pink
from benchmarks.stats import line_timing
from benchmarks.step import interleaved_rounds
from benchmarks.step_lines import OBSTACLE_RADIUS, OBSTACLES_ONE_ACTIVE, panda_setup
from benchmarks.tick_clik import clik_tick_variants
from benchmarks.tick_mink import mink_tick_variants
from benchmarks.tick_pink import pink_tick_variants
from benchmarks.tick_quality import QualityCheck
from benchmarks.tick_variant import TickVariant, tick_reference
from benchmarks.tick_whole_body import whole_body_variants

TICK_LINES = (
    "panda_pose",
    "panda_pose_obstacles",
    "dual_arm",
    "humanoid",
    "pink_panda_pose",
    "pink_panda_pose_obstacles",
    "pink_dual_arm",
    "pink_humanoid",
    "mink_panda_pose",
    "mink_panda_pose_obstacles",
    "mink_dual_arm",
    "mink_humanoid",
)
"""The tick lines, in report order: clik's, pink's, mink's (``bench.json``'s ``tick_us``
keys; a missing library's are null)."""


def bench_ticks(
    config: BenchConfig, pink: Pink | None, mink: Mink | None, log: Log
) -> dict[str, Any]:
    """Interleaved rounds of every tick line; per-line statistics [us per tick] and quality.

    Args:
        config: Sizes of the suite (its rounds and the Panda's duration).
        pink: The installed pink, or None to leave its lines out.
        mink: The installed mink, or None to leave its lines out.
        log: Progress callback.

    Returns:
        Per line that ran (in :data:`TICK_LINES` order): its description, median, p10,
        p90 and min [us per tick], runs, ticks per run, real-time factor, its last
        run's info and ``quality`` (:class:`~benchmarks.tick_quality.QualityCheck`).
    """
    panda = panda_setup(config)
    reference = tick_reference(panda.trajectory)
    variants: list[TickVariant] = clik_tick_variants(panda, reference)
    if pink is not None:
        variants += pink_tick_variants(pink, panda)
    if mink is not None:
        variants += mink_tick_variants(mink, panda, reference)
    variants += whole_body_variants(pink, mink)
    samples, infos, ticks_of = interleaved_rounds(variants, config.rounds, log, "tick")
    check = QualityCheck(
        panda.robot, panda.task.frame_id, reference, OBSTACLES_ONE_ACTIVE, OBSTACLE_RADIUS
    )
    out: dict[str, Any] = {}
    for v in variants:
        out[v.name] = {
            **line_timing(v.description, samples[v.name], "ticks_per_run", ticks_of[v.name]),
            **infos[v.name],
            "quality": (v.check or check)(v.joints()),
        }
    return out
