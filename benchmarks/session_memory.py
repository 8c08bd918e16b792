"""Memory of a long controller session: a million ticks with constraint events at each.

The planar arm holds its tip while two pins are put beside its first link and taken
away in turn (``Controller.step(target, obstacles=...)``): at every tick one obstacle row
activates and another releases. The controller keeps its last ``record_size`` ticks and
its last ``event_size`` events, so its RSS must not grow once they are full (by 10 % of
the session), and ``result()`` must cost what they hold. Runs in a fresh interpreter
(:func:`session_child`), like :mod:`benchmarks.memory`.
"""

from __future__ import annotations

import gc
import time
from typing import Any

import numpy as np

import clik
from benchmarks.config import DT, BenchConfig, Log
from benchmarks.fresh import run_fresh
from benchmarks.rss import proc_status_kb
from clik.constraints import ConstraintSet, JointLimits, Obstacle

RECORD_SIZE = 10_000
"""The session's record and event log (the controller's defaults)."""


def _rss_mb() -> float:
    """This process's resident set size [MB] (0 where ``/proc`` is missing)."""
    return (proc_status_kb("VmRSS") or 0) * 1024 / 1e6


def blinking(
    engine: str = "compiled", record_size: int = RECORD_SIZE, event_size: int = RECORD_SIZE
) -> tuple[clik.Controller, np.ndarray, tuple[dict[str, np.ndarray], ...]]:
    """The session's controller, its tip target, and the pins' moves of even and odd ticks.

    The planar arm holds its tip; two pins, 2 cm either side of its first link, are put
    there and taken away in turn: at every tick one row activates and the other releases.

    Args:
        engine: The controller's engine.
        record_size: Ticks its record keeps.
        event_size: Events it keeps.
    """
    robot = clik.Robot.load("planar4r")
    task = clik.Task(robot, "tip", "position", axes=["x", "y"])
    q0 = np.radians([180.0, -30.0, -90.0, -30.0])
    tip = np.ascontiguousarray(task.placement(q0).translation)
    left, right, away = np.array([-0.02, -0.15, 0.0]), np.array([0.02, -0.15, 0.0]), [0, 0, 1.0]
    pins = [
        Obstacle("left", "sphere", left + away, radius=0.0),
        Obstacle("right", "sphere", right + away, radius=0.0),
    ]
    cset = ConstraintSet(
        robot, obstacles=pins, obstacle_threshold=0.03, joint_limits=JointLimits(robot)
    )
    ctl = clik.Controller(
        task, gain=100.0, dt=DT, engine=engine, constraints=cset, q0=q0,
        record_size=record_size, event_size=event_size,
    )  # fmt: skip
    moves = ({"left": left, "right": right + away}, {"left": left + away, "right": right})
    return ctl, tip, moves


def session_child(ticks: int) -> dict[str, Any]:
    """Run in a fresh interpreter: RSS growth over the last 90 % of ``ticks`` and ``result()``.

    Args:
        ticks: The session's ticks.
    """
    ctl, tip, moves = blinking()
    events = quiet = 0
    rss_10 = 0.0
    start = time.perf_counter()
    for k in range(ticks):
        n = len(ctl.step(tip, obstacles=moves[k & 1]).events)
        events += n
        quiet += n == 0
        if k == ticks // 10:
            gc.collect()
            rss_10 = _rss_mb()
    wall = time.perf_counter() - start
    gc.collect()
    rss_end = _rss_mb()
    start = time.perf_counter()
    result = ctl.result()
    result_ms = (time.perf_counter() - start) * 1e3
    return {
        "ticks": ticks,
        "events": events,
        "ticks_without_event": quiet,
        "status": result.status,
        "violations": len(result.violations),
        "rss_at_10pct_mb": rss_10,
        "rss_end_mb": rss_end,
        "growth_after_10pct_mb": rss_end - rss_10,
        "result_ms": result_ms,
        "events_kept": len(result.events),
        "events_dropped": result.events_dropped,
        "ticks_kept": int(result.q.shape[0]),
        "us_per_tick": wall / ticks * 1e6,
    }


def bench_session(config: BenchConfig, log: Log) -> dict[str, Any]:
    """:func:`session_child` in a subprocess of this interpreter.

    Args:
        config: Sizes of the suite (``session_ticks``).
        log: Progress callback.

    Raises:
        RuntimeError: The subprocess failed (its stderr's end in the message).
    """
    result = run_fresh(session_child, config.session_ticks, what="session memory")
    log("  memory: a controller session done")
    return result
