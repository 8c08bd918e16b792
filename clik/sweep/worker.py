"""What runs on a Dask worker: a batch of sweep runs in, one result row per run out.

Robots are loaded once per worker process (and thread), not once per run:
:func:`cached_robot` keeps the last few robots, keyed by what
:meth:`clik.Robot.load` is given (source, package folders, locked joints, xacro
arguments).
Each run then parses its own scenario (substituted base dict, cheap) and
builds its task, trajectory and constraints on the cached robot.

A run that raises becomes a row with ``status = "error"`` and the error
message; it never fails the Dask task, so one bad run does not stop a sweep.
A Dask task computes a batch of runs (:func:`run_batch`, one :func:`run_one`
each, in order, until a time budget is spent): a run takes milliseconds, and a
task per run would cost more in Dask's overhead than the run itself.

For tests and debugging, when the environment variable ``CLIK_SWEEP_TRACE``
names a folder, every run computed appends its id to
``<folder>/<pid>.log`` (one line per computation, written when the run ends).
"""

from __future__ import annotations

import os
import socket
import tempfile
import threading
import time
import traceback
import warnings
from collections import OrderedDict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clik.scenarios.scenario import parse_scenario
from clik.sweep.keypath import substitute

if TYPE_CHECKING:
    from clik.model.robot import Robot
    from clik.scenarios.runner import Run
    from clik.scenarios.scenario import Scenario

TRACE_ENV = "CLIK_SWEEP_TRACE"
"""Environment variable: a folder where each computed run's id is logged (tests, debugging)."""

ROBOTS_PER_WORKER = 4
"""Robots kept per worker thread (least recently used dropped first)."""

_local = threading.local()
_count_lock = threading.Lock()
_loads = [0]


def _robots() -> OrderedDict[tuple[Any, ...], Robot]:
    cache = getattr(_local, "robots", None)
    if cache is None:
        cache = _local.robots = OrderedDict()
    return cache


def robot_key(spec: dict[str, Any]) -> tuple[Any, ...]:
    """Cache key of a scenario's ``robot`` table (as validated by ``parse_scenario``)."""
    return (
        spec["source"],
        tuple(spec["package_dirs"]),
        tuple(sorted((k, float(v)) for k, v in spec["lock"].items())),
        tuple(sorted(spec.get("xacro_args", {}).items())),
        spec.get("srdf"),
    )


def cached_robot(spec: dict[str, Any]) -> Robot:
    """The robot of a scenario's ``robot`` table, loaded once per worker thread.

    A thread has its own robots: a :class:`~clik.model.robot.Robot` holds Pinocchio
    data that a run writes into.
    """
    from clik.model.robot import Robot

    cache = _robots()
    key = robot_key(spec)
    robot = cache.get(key)
    if robot is None:
        robot = Robot.load(
            spec["source"],
            package_dirs=spec["package_dirs"] or None,
            lock=spec["lock"] or None,
            xacro_args=spec.get("xacro_args") or None,
            srdf=spec.get("srdf"),
        )
        cache[key] = robot
        with _count_lock:
            _loads[0] += 1
        while len(cache) > ROBOTS_PER_WORKER:
            cache.popitem(last=False)
    cache.move_to_end(key)
    return robot


def robot_loads() -> int:
    """How many robots this process has loaded for runs (a test of the cache)."""
    return _loads[0]


def build_run(scenario: Scenario, robot: Robot) -> Run:
    """:func:`clik.scenarios.runner.build` on a robot loaded earlier (same errors, same objects)."""
    from clik.scenarios import runner

    return runner.build(scenario, robot=robot)


def worker_name() -> str:
    """The Dask worker's address, or ``host:pid`` outside a worker."""
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def _trace(run_id: str) -> None:
    folder = os.environ.get(TRACE_ENV)
    if not folder:
        return
    Path(folder).mkdir(parents=True, exist_ok=True)
    fd = os.open(Path(folder) / f"{os.getpid()}.log", os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    try:
        os.write(fd, f"{run_id}\n".encode())
    finally:
        os.close(fd)


def summary_columns(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary numbers that become columns of the results table."""
    import json

    return {
        "reason": summary["reason"],
        "steps": int(summary["steps"]),
        "wall_time_s": float(summary["wall_time_s"]),
        "max_task_error": float(summary["max_task_error"]),
        "final_task_error": float(summary["final_task_error"]),
        "max_orientation_error": summary.get("max_orientation_error"),
        "min_obstacle_distance": summary.get("min_obstacle_distance"),
        "min_obstacle_distance_by_obstacle": json.dumps(
            summary.get("min_obstacle_distance_by_obstacle") or {}
        ),
        "event_count": len(summary["events"]),
        "events": json.dumps(summary["events"]),
        "joint_min": list(summary["joint_min"]),
        "joint_max": list(summary["joint_max"]),
    }


def run_one(
    base_data: dict[str, Any],
    base_file: str,
    run_id: str,
    params: dict[str, Any],
    keep_trajectory: bool = False,
) -> dict[str, Any]:
    """Compute one run of a sweep; never raises for a run's own failure.

    Args:
        base_data: The base scenario as read from TOML.
        base_file: Its path (relative paths resolve against its folder).
        run_id: The run's id.
        params: Key path -> value to substitute.
        keep_trajectory: Also return ``_summary`` (dict) and ``_trajectory_npz`` (``.npz`` bytes).

    Returns:
        A row: ``run_id``, ``status`` (the run's, or ``"error"``), ``error``, the
        summary numbers (:func:`summary_columns`), ``run_wall_time_s`` (build and
        run), ``warnings``, ``worker``, ``finished_at`` (Unix time [s]).
    """
    start = time.perf_counter()
    row: dict[str, Any] = {"run_id": run_id, "error": None}
    extra: dict[str, Any] = {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scenario = parse_scenario(substitute(base_data, params), base_file)
            run = build_run(scenario, cached_robot(scenario.robot))
            result = run.execute()
            summary = result.summary()
            row["status"] = result.status
            row.update(summary_columns(summary))
            if keep_trajectory:
                extra = {"_summary": summary, "_trajectory_npz": _npz_bytes(result)}
        except Exception as exc:  # a run's failure is data; the sweep goes on
            row["status"] = "error"
            row["reason"] = f"{type(exc).__name__}: {exc}"
            row["error"] = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    row["warnings"] = "; ".join(dict.fromkeys(str(w.message) for w in caught)) or None
    row["run_wall_time_s"] = time.perf_counter() - start
    row["worker"] = worker_name()
    row["finished_at"] = time.time()
    row.update(extra)
    _trace(run_id)
    return row


def run_batch(
    base_data: dict[str, Any],
    base_file: str,
    runs: list[tuple[str, dict[str, Any]]],
    keep_trajectory: bool = False,
    budget_s: float | None = None,
) -> list[dict[str, Any]]:
    """Compute runs one after the other (:func:`run_one`); their rows, in the same order.

    Args:
        base_data: The base scenario as read from TOML.
        base_file: Its path (relative paths resolve against its folder).
        runs: ``(run_id, params)`` of each run.
        keep_trajectory: See :func:`run_one`.
        budget_s: Start no run once this long has passed [s] (None: no limit): the
            rows are then those of the first runs only (at least one), and the
            caller submits the others again.
    """
    start = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for rid, params in runs:
        if rows and budget_s is not None and time.perf_counter() - start >= budget_s:
            break
        rows.append(run_one(base_data, base_file, rid, params, keep_trajectory))
    return rows


def _npz_bytes(result: Any) -> bytes:
    """A result's ``.npz`` file as bytes (it travels to the client, which writes it)."""
    with tempfile.TemporaryDirectory(prefix="clik_sweep_") as folder:
        path = Path(folder) / "trajectory.npz"
        result.save(path)
        return path.read_bytes()
