"""Step cost [us per sample]: every line's whole runs, interleaved round by round.

Every variant runs once as a warm-up, then once per round; the order rotates
every round, so a busy moment of the machine hits every line alike.
"""

from __future__ import annotations

import gc
from typing import Any

from clik.bench.config import DT, BenchConfig, Log
from clik.bench.pink_backend import Pink
from clik.bench.stats import stats
from clik.bench.step_lines import step_variants
from clik.bench.step_variant import Variant


def interleaved_rounds(
    variants: list[Variant], rounds: int, log: Log
) -> tuple[dict[str, list[float]], dict[str, dict[str, Any]], dict[str, int]]:
    """Warm up every variant, then run each once per round in a rotating order.

    Args:
        variants: The lines.
        rounds: Rounds after the warm-up.
        log: Called once per round.

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
        for v in variants[shift:] + variants[:shift]:
            gc.collect()
            steps, wall, info = v.run()
            samples[v.name].append(1e6 * wall / max(steps, 1))
            infos[v.name], steps_of[v.name] = info, steps
        log(f"  step round {r + 1}/{rounds}")
    return samples, infos, steps_of


def bench_steps(config: BenchConfig, pink: Pink | None, log: Log) -> dict[str, Any]:
    """Interleaved rounds of every step variant; per-variant statistics [us per step].

    Args:
        config: Sizes of the suite.
        pink: The installed pink, or None to leave its lines out.
        log: Progress callback.

    Returns:
        Per line (in the order of :func:`~clik.bench.step_lines.step_variants`): its
        description, median, p10, p90 and min [us], runs, steps per run, real-time
        factor and the info of its last run.
    """
    variants = step_variants(config, pink)
    samples, infos, steps_of = interleaved_rounds(variants, config.rounds, log)
    out: dict[str, Any] = {}
    for v in variants:
        s = stats(samples[v.name])
        out[v.name] = {
            "description": v.description,
            "median_us": s["median"],
            "p10_us": s["p10"],
            "p90_us": s["p90"],
            "min_us": s["min"],
            "runs": s["n"],
            "steps_per_run": steps_of[v.name],
            "realtime_factor": DT / (1e-6 * s["median"]),
            **infos[v.name],
        }
    return out
