"""Step cost [us per sample]: every line's whole runs, interleaved round by round.

Every variant runs once as a warm-up, then once per round; the order rotates
every round, so a busy moment of the machine hits every line alike.
"""

from __future__ import annotations

import gc
from collections.abc import Sequence
from typing import Any

from benchmarks.config import BenchConfig, Log
from benchmarks.pink_backend import Pink
from benchmarks.stats import line_timing
from benchmarks.step_lines import step_variants
from benchmarks.step_variant import Variant


def interleaved_rounds(
    variants: Sequence[Variant], rounds: int, log: Log, label: str = "step"
) -> tuple[dict[str, list[float]], dict[str, dict[str, Any]], dict[str, int]]:
    """Warm up every variant, then run each once per round in a rotating order.

    Args:
        variants: The lines.
        rounds: Rounds after the warm-up.
        log: Called once per round.
        label: What the round's log line calls the lines (``step``, ``tick``).

    Returns:
        Per line: the cost of every round [us per step], the last run's info and its steps.
    """
    for v in variants:  # warm-up: caches, lazy imports, first allocations
        v.run()
    samples: dict[str, list[float]] = {v.name: [] for v in variants}
    infos: dict[str, dict[str, Any]] = {}
    steps_of: dict[str, int] = {}
    for r in range(rounds):
        shift = r % len(variants)
        for v in [*variants[shift:], *variants[:shift]]:
            gc.collect()
            steps, wall, info = v.run()
            samples[v.name].append(1e6 * wall / max(steps, 1))
            infos[v.name], steps_of[v.name] = info, steps
        log(f"  {label} round {r + 1}/{rounds}")
    return samples, infos, steps_of


def bench_steps(config: BenchConfig, pink: Pink | None, log: Log) -> dict[str, Any]:
    """Interleaved rounds of every step variant; per-variant statistics [us per step].

    Args:
        config: Sizes of the suite.
        pink: The installed pink, or None to leave its lines out.
        log: Progress callback.

    Returns:
        Per line (in the order of :func:`~benchmarks.step_lines.step_variants`): its
        description, median, p10, p90 and min [us], runs, steps per run, real-time
        factor and the info of its last run.
    """
    variants = step_variants(config, pink)
    samples, infos, steps_of = interleaved_rounds(variants, config.rounds, log)
    out: dict[str, Any] = {}
    for v in variants:
        out[v.name] = {
            **line_timing(v.description, samples[v.name], "steps_per_run", steps_of[v.name]),
            **infos[v.name],
        }
    return out
