"""Single-pose solve: :func:`clik.solve` against pink on the same random reachable poses.

The targets are the hand's poses at seeded random configurations inside the
joint limits; every solver starts from the reference configuration and is
checked independently of any (:mod:`benchmarks.pose_error`). clik's compiled
engine, its Python engine and pink take turns block by block (:data:`BLOCK`
targets each; which goes first rotates too): drift in the machine's load
reaches all three alike, and each solver runs a block with its own code and data
in the caches, as a caller solving many poses (a reach map) runs it, rather than
after the other two evicted them at every target.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pinocchio as pin

import clik
from benchmarks.config import BenchConfig, Log
from benchmarks.pink_backend import Pink
from benchmarks.pose_error import (
    ORIENTATION_TOLERANCE,
    POSITION_TOLERANCE,
    pose_errors,
    within_tolerance,
)
from benchmarks.solve_pink import PinkSolve, pink_setup_text, pink_solver
from benchmarks.stats import ratio, stats
from clik.model.robot import PANDA_FINGERS

Engine = Literal["compiled", "python"]
"""An engine of :func:`clik.solve`."""


@dataclass
class _Record:
    """Per-target outcomes of one solver, in target order."""

    times: list[float] = field(default_factory=list)
    ok: list[bool] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)
    reported: list[bool] = field(default_factory=list)
    attempts: list[int] = field(default_factory=list)
    failures: list[int] = field(default_factory=list)


@dataclass
class _Solvers:
    """What both solvers need: the task, a scratch data for the check, pink's solve."""

    task: clik.Task
    model: pin.Model
    check: pin.Data
    pink_solve: PinkSolve | None


def solve_targets(robot: clik.Robot, task: clik.Task, count: int, seed: int) -> list[pin.SE3]:
    """Poses of the task frame at seeded random configurations inside the joint limits.

    Args:
        robot: The robot.
        task: The pose task whose frame is placed.
        count: Number of targets.
        seed: Seed of the random configurations.
    """
    rng = np.random.default_rng(seed)
    data = robot.model.createData()
    targets = []
    for _ in range(count):
        q = robot.random_configuration(rng)
        pin.framesForwardKinematics(robot.model, data, q)
        targets.append(data.oMf[task.frame_id].copy())
    return targets


def _time_clik(s: _Solvers, target: pin.SE3, index: int, rec: _Record, engine: Engine) -> None:
    start = time.perf_counter()
    res = clik.solve(s.task, target, engine=engine)
    rec.times.append(time.perf_counter() - start)
    good = within_tolerance(pose_errors(s.model, s.check, s.task.frame_id, res.q, target))
    rec.ok.append(good)
    rec.reported.append(res.success)
    rec.iterations.append(res.iterations)
    rec.attempts.append(res.attempts)
    if not good:
        rec.failures.append(index)


def _time_pink(s: _Solvers, pink_solve: PinkSolve, target: pin.SE3, rec: _Record) -> None:
    start = time.perf_counter()
    q, it = pink_solve(target)
    rec.times.append(time.perf_counter() - start)
    rec.ok.append(within_tolerance(pose_errors(s.model, s.check, s.task.frame_id, q, target)))
    rec.iterations.append(it)


SOLVERS = ("compiled", "python", "pink")
"""The solvers of the benchmark: clik.solve in each engine, and pink."""

BLOCK = 25
"""Targets a solver runs in a row before the next solver takes its turn."""


def _alternate(s: _Solvers, targets: list[pin.SE3], log: Log) -> tuple[_Record, _Record, _Record]:
    """Every solver on every target, in turns of :data:`BLOCK` targets, the first rotating.

    Returns:
        The records of clik's compiled engine, of its Python engine and of pink.
    """
    clik.solve(s.task, targets[0], engine="compiled")  # warm-up
    clik.solve(s.task, targets[0], engine="python")
    if s.pink_solve is not None:
        s.pink_solve(targets[0])
    records = {who: _Record() for who in SOLVERS}
    blocks = range(0, len(targets), BLOCK)
    for b, first in enumerate(blocks):
        shift = b % len(SOLVERS)
        for who in SOLVERS[shift:] + SOLVERS[:shift]:
            for i in range(first, min(first + BLOCK, len(targets))):
                if who == "pink":
                    if s.pink_solve is not None:
                        _time_pink(s, s.pink_solve, targets[i], records[who])
                else:
                    engine: Engine = "python" if who == "python" else "compiled"
                    _time_clik(s, targets[i], i, records[who], engine)
        if (b + 1) % max(1, len(blocks) // 4) == 0:
            log(f"  solve {min(first + BLOCK, len(targets))}/{len(targets)}")
    return records["compiled"], records["python"], records["pink"]


def _median_us_of_successes(rec: _Record) -> float | None:
    ok = np.asarray(rec.ok)
    return float(np.median(1e6 * np.asarray(rec.times)[ok])) if ok.any() else None


def _clik_summary(rec: _Record, config: BenchConfig, count: int) -> dict[str, Any]:
    t_us = stats(1e6 * np.asarray(rec.times))
    return {
        "targets": count,
        "seed": config.seed,
        "tolerance_m": POSITION_TOLERANCE,
        "tolerance_rad": ORIENTATION_TOLERANCE,
        "success_rate": float(np.asarray(rec.ok).mean()),
        "reported_success_rate": float(np.mean(rec.reported)),
        "median_us": t_us["median"],
        "p10_us": t_us["p10"],
        "p90_us": t_us["p90"],
        "mean_us": t_us["mean"],
        "median_us_successes": _median_us_of_successes(rec),
        "iterations_median": float(np.median(rec.iterations)),
        "iterations_mean": float(np.mean(rec.iterations)),
        "restarts_used_fraction": float(np.mean(np.asarray(rec.attempts) > 1)),
        "failed_targets": rec.failures[:20],
        "pink_success_rate": None,
        "pink_median_us": None,
    }


def _python_summary(rec: _Record, clik_median_us: float) -> dict[str, Any]:
    t_us = stats(1e6 * np.asarray(rec.times))
    return {
        "python_success_rate": float(np.asarray(rec.ok).mean()),
        "python_median_us": t_us["median"],
        "python_p10_us": t_us["p10"],
        "python_p90_us": t_us["p90"],
        "python_mean_us": t_us["mean"],
        "python_iterations_median": float(np.median(rec.iterations)),
        "python_over_compiled": ratio(t_us["median"], clik_median_us),
    }


def _pink_summary(
    rec: _Record, config: BenchConfig, pink: Pink, clik_median_us: float
) -> dict[str, Any]:
    p_us = stats(1e6 * np.asarray(rec.times))
    return {
        "pink_success_rate": float(np.asarray(rec.ok).mean()),
        "pink_median_us": p_us["median"],
        "pink_p10_us": p_us["p10"],
        "pink_p90_us": p_us["p90"],
        "pink_mean_us": p_us["mean"],
        "pink_median_us_successes": _median_us_of_successes(rec),
        "pink_iterations_median": float(np.median(rec.iterations)),
        "pink_max_iterations": config.pink_max_iterations,
        "pink_setup": pink_setup_text(pink),
        "speedup_vs_pink": ratio(p_us["median"], clik_median_us),
    }


def bench_solve(config: BenchConfig, pink: Pink | None, log: Log) -> dict[str, Any]:
    """clik.solve (both engines) and pink to convergence on the same random poses, in turns.

    Args:
        config: Sizes of the suite.
        pink: The installed pink, or None to time clik alone (pink's figures ``None``).
        log: Progress callback.

    Returns:
        Success rates (checked here, and as reported by clik), timing statistics
        [us] and iterations of the compiled engine (unprefixed keys), of the Python
        engine (``python_`` keys) and of pink (``pink_`` keys, with the speed-up,
        when pink ran).
    """
    robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
    task = clik.Task(robot, "panda_hand", "pose")
    model = robot.model
    targets = solve_targets(robot, task, config.solve_targets, config.seed)
    check = model.createData()
    pink_solve = None
    if pink is not None:
        pink_solve = pink_solver(pink, model, task, robot.q_reference, config.pink_max_iterations)
    mine, python, theirs = _alternate(_Solvers(task, model, check, pink_solve), targets, log)
    out = _clik_summary(mine, config, len(targets))
    out.update(_python_summary(python, out["median_us"]))
    if pink is not None and theirs.times:
        out.update(_pink_summary(theirs, config, pink, out["median_us"]))
    return out
