"""Memory: peak RSS growth of a long planar run, full and decimated recording.

Each measurement runs in a fresh interpreter (:func:`memory_child`), so
neither the suite's other lines nor the other measurement leave memory behind.
"""

from __future__ import annotations

import gc
from typing import Any

import numpy as np

import clik
from benchmarks.config import DT, BenchConfig, Log
from benchmarks.fresh import run_fresh
from benchmarks.rss import peak_rss_bytes, rss_baseline
from clik.trajectory import Line


def memory_child(samples: int, record_every: int) -> dict[str, Any]:
    """Run in a fresh interpreter: peak-RSS growth of one planar run of ``samples`` samples.

    The baseline is the RSS after loading the robot, building the tracker and a
    10-sample warm-up run (the peak is reset there, see
    :func:`~benchmarks.rss.rss_baseline`); the growth is the peak RSS during the big
    run (trajectory sampling, recording, the result) minus that baseline
    [MB = 1e6 bytes].

    Args:
        samples: Samples of the run.
        record_every: Recording decimation (1: every sample).
    """
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    start = task.placement(q0).translation
    tracker = clik.Tracker(task, law="transpose", gain=1000.0, dt=DT)
    tracker.run(Line(start, [0.8, -0.2, 0.0], duration=10 * DT), q0)
    duration = (samples - 1) * DT
    line = Line(start, [0.8, -0.2, 0.0], duration=duration)
    gc.collect()
    base, method = rss_baseline()
    result = tracker.run(line, q0, record_every=record_every)
    peak = peak_rss_bytes(method)
    return {
        "samples": int(result.steps),
        "record_every": record_every,
        "status": result.status,
        "violations": len(result.violations),
        "method": method,
        "baseline_mb": base / 1e6,
        "peak_mb": peak / 1e6,
        "growth_mb": max(peak - base, 0) / 1e6,
        "recorded_samples": int(result.q.shape[0]),
        "wall_time_s": float(result.wall_time_s),
    }


def memory_run(samples: int, record_every: int) -> dict[str, Any]:
    """:func:`memory_child` in a subprocess of this interpreter.

    Args:
        samples: Samples of the run.
        record_every: Recording decimation.

    Raises:
        RuntimeError: The subprocess failed (its stderr's end in the message).
    """
    return run_fresh(memory_child, samples, record_every, what="memory")


def bench_memory(config: BenchConfig, log: Log) -> dict[str, Any]:
    """Peak RSS growth with full and with decimated recording, each in a fresh process.

    Args:
        config: Sizes of the suite (``memory_samples``, ``memory_record_every``).
        log: Progress callback.
    """
    full = memory_run(config.memory_samples, 1)
    log("  memory: full recording done")
    decimated = memory_run(config.memory_samples, config.memory_record_every)
    log("  memory: decimated recording done")
    return {"full": full, "decimated": decimated}
