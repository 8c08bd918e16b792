"""Sweep: runs per second of a fixed sweep on a local Dask cluster of 1 and of 2 workers."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.config import BenchConfig, Log
from clik.errors import InputError

BENCH_SWEEP = """\
base = "case_study_both"
seed = {seed}

[vary."obstacles.pin.position"]
uniform = {{ low = [0.66, -0.32, 0.0], high = [0.74, -0.24, 0.0], samples = {samples} }}
"""
"""The fixed sweep: the case study (law (9), both constraints, 3 s at 1 ms, about 0.25 s a
run on one core), the pin at uniform positions around the case study's."""


def sweep_rate(workers: int, runs: int) -> float:
    """Runs per second of a fixed sweep on a :class:`~distributed.LocalCluster` of ``workers``.

    The cluster is started and warmed up first (each worker imports clik and
    loads the robot with one run), so the rate is the steady one: ``runs``
    divided by the time from the first submission to the last row written.

    Args:
        workers: Worker processes (one thread each).
        runs: Runs of the timed sweep (a few per worker at least).

    Returns:
        Runs per second [1/s].

    Raises:
        InputError: ``workers`` or ``runs`` is not an integer >= 1.
    """
    from clik.sweep.cluster import dask_client
    from clik.sweep.execute import run_sweep

    for name, value in (("workers", workers), ("runs", runs)):
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise InputError(name, "an integer >= 1", value)
    with tempfile.TemporaryDirectory(prefix="clik_sweep_rate_") as folder:
        root = Path(folder)
        warm = root / "warm.toml"
        warm.write_text(BENCH_SWEEP.format(seed=1, samples=2 * workers))
        timed = root / "timed.toml"
        timed.write_text(BENCH_SWEEP.format(seed=0, samples=runs))
        with dask_client(workers=workers) as client:
            client.wait_for_workers(workers)
            run_sweep(warm, root / "warm", client=client, progress=False)
            report = run_sweep(timed, root / "timed", client=client, progress=False)
    return report.rate


def bench_sweep(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Runs per second of a sweep on a local Dask cluster of 1 and of 2 workers.

    The two cluster sizes alternate ``sweep_repeats`` times (medians taken), so a
    busy moment of the machine hits both.

    Args:
        config: Sizes of the suite (``sweep_runs``, ``sweep_repeats``).
        log: Progress callback.
    """
    rates: dict[int, list[float]] = {1: [], 2: []}
    for _ in range(config.sweep_repeats):
        for workers in (1, 2):
            rates[workers].append(sweep_rate(workers, config.sweep_runs))
            log(f"  sweep, {workers} worker(s): {rates[workers][-1]:.2f} runs/s")
    one, two = float(np.median(rates[1])), float(np.median(rates[2]))
    return {
        "runs": config.sweep_runs,
        "runs_per_s_1_worker": one,
        "runs_per_s_2_workers": two,
        "speedup_2_workers": two / one,
        "all_runs_per_s": {str(k): v for k, v in rates.items()},
    }
