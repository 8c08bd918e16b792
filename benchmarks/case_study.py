"""Case study: wall time of the eight shipped runs, with and without building them."""

from __future__ import annotations

import gc
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from benchmarks.config import BenchConfig, Log
from benchmarks.stats import stats
from clik.scenarios import CASE_STUDY, scenario_path
from clik.scenarios.runner import build


@dataclass
class _Round:
    """One round of the eight runs: totals [s], each run's ``execute()`` [s], statuses."""

    with_build: float = 0.0
    execute: float = 0.0
    loop: float = 0.0
    per_run: dict[str, float] = field(default_factory=dict)
    statuses: dict[str, str] = field(default_factory=dict)


def case_study_round() -> _Round:
    """Build and execute each case-study run once, timing both stages."""
    out = _Round()
    for name in CASE_STUDY:
        gc.collect()
        t0 = time.perf_counter()
        run = build(scenario_path(name))
        t1 = time.perf_counter()
        result = run.execute()
        t2 = time.perf_counter()
        out.with_build += t2 - t0
        out.execute += t2 - t1
        out.loop += result.wall_time_s
        out.statuses[name] = result.status
        out.per_run[name] = t2 - t1
    return out


def bench_case_study(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Wall time of the eight case-study runs, per round; medians over rounds.

    Args:
        config: Sizes of the suite (``case_study_rounds``, after one warm-up round).
        log: Progress callback.

    Returns:
        Medians over rounds of the eight runs' total [s] (``execute()``, build +
        execute, loop only), each run's median, statuses and the real-time factor.
    """
    statuses = case_study_round().statuses  # round 0 is a warm-up
    rounds: list[_Round] = []
    for r in range(1, config.case_study_rounds + 1):
        rounds.append(case_study_round())
        statuses = rounds[-1].statuses
        log(f"  case study round {r}/{config.case_study_rounds}")
    s = stats([x.execute for x in rounds])
    return {
        "all_runs_s": s["median"],
        "all_runs_p10_s": s["p10"],
        "all_runs_p90_s": s["p90"],
        "all_runs_with_build_s": stats([x.with_build for x in rounds])["median"],
        "all_runs_loop_only_s": stats([x.loop for x in rounds])["median"],
        "per_run_s": {
            name: float(np.median([x.per_run[name] for x in rounds])) for name in CASE_STUDY
        },
        "status": statuses,
        "realtime_factor_per_run": 3.0 * len(CASE_STUDY) / s["median"],
        "rounds": config.case_study_rounds,
    }
