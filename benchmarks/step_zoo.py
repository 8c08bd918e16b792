"""Step cost of the zoo's obstacle run (:mod:`benchmarks.zoo`), robot by robot.

Each robot is loaded and its run built (not timed), run once as a warm-up, then
``zoo_rounds`` times with the compiled engine; its cost is the median of
``wall_time_s / steps`` over those runs. A robot refused before its run (a
:class:`~clik.errors.ClikError` while loading, building or in the warm-up) is
skipped and named. One robot is held in memory at a time.
"""

from __future__ import annotations

import gc
import warnings
from typing import Any

import numpy as np

import clik
from benchmarks.config import BenchConfig, Log
from benchmarks.stats import stats
from benchmarks.zoo import zoo_setup


def zoo_robot_cost(name: str, rounds: int) -> dict[str, Any]:
    """Per-sample cost [us] of one robot's obstacle run, or why it was refused.

    Args:
        name: The robot.
        rounds: Timed runs after the warm-up.

    Returns:
        ``{"median_us", "steps", "status"}``, or ``{"refused", "reason"}``.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            setup = zoo_setup(name)
            tracker = setup.tracker("compiled")
            result = tracker.run(setup.line, setup.q0)
        except clik.ClikError as exc:
            return {"refused": type(exc).__name__, "reason": str(exc).splitlines()[0][:200]}
        costs = []
        for _ in range(rounds):
            gc.collect()
            result = tracker.run(setup.line, setup.q0)
            costs.append(1e6 * result.wall_time_s / max(result.steps, 1))
    return {
        "median_us": float(np.median(costs)),
        "steps": int(result.steps),
        "status": result.status,
    }


def bench_zoo(config: BenchConfig, log: Log) -> dict[str, Any]:
    """The zoo's obstacle run on every robot (``config.zoo_robots``; None: all of them).

    Args:
        config: Sizes of the suite (``zoo_robots``, ``zoo_rounds``).
        log: Progress callback.

    Returns:
        The median over robots of their per-sample cost [us] (with p10, p90, min and
        max), how many robots were timed, each timed robot's cost, steps and status,
        and the refused robots with the error's name.
    """
    names = sorted(clik.Robot.available()) if config.zoo_robots is None else config.zoo_robots
    timed: dict[str, dict[str, Any]] = {}
    skipped: dict[str, dict[str, Any]] = {}
    for i, name in enumerate(names):
        outcome = zoo_robot_cost(name, config.zoo_rounds)
        (skipped if "refused" in outcome else timed)[name] = outcome
        if (i + 1) % max(1, len(names) // 4) == 0:
            log(f"  zoo {i + 1}/{len(names)} robots")
    if not timed:
        raise RuntimeError(f"zoo: every robot was refused: {sorted(skipped)}")
    s = stats([x["median_us"] for x in timed.values()])
    return {
        "median_us": s["median"],
        "p10_us": s["p10"],
        "p90_us": s["p90"],
        "min_us": s["min"],
        "max_us": max(x["median_us"] for x in timed.values()),
        "robots_timed": len(timed),
        "robots_skipped": len(skipped),
        "rounds": config.zoo_rounds,
        "per_robot": timed,
        "skipped": skipped,
    }
