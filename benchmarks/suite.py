"""The whole suite: run every measurement, write ``bench.json`` and ``bench.md``.

:func:`run_bench` is what ``clik bench`` calls; :func:`main` is
``python -m benchmarks``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.case_study import bench_case_study
from benchmarks.cloud_lines import CLOUD_TICK_LINES, OCTREE_LINE, bench_cloud
from benchmarks.config import FULL, QUICK, BenchConfig, Log
from benchmarks.machine import cpu_seconds, machine_info, versions
from benchmarks.memory import bench_memory
from benchmarks.mink_backend import Mink, find_mink
from benchmarks.pink_backend import Pink, find_pink
from benchmarks.report import markdown
from benchmarks.ros_line import bench_ros
from benchmarks.session_memory import bench_session
from benchmarks.solve import bench_solve
from benchmarks.stats import ratio
from benchmarks.step import bench_steps
from benchmarks.step_lines import line_name
from benchmarks.step_zoo import bench_zoo
from benchmarks.sweep_rate import bench_sweep
from benchmarks.targets import evaluate_targets, load_targets
from benchmarks.tick import TICK_LINES, bench_ticks
from clik.outputs.io import atomic_write, check_out_path, output_errors, write_json

REQUIRED_KEYS = (
    "step_us.planar4r",
    "step_us.panda_pose",
    "step_us.panda_pose_obstacles",
    "step_us.python_panda_pose",
    "step_us.pink_panda_pose",
    "step_us.pink_panda_pose_obstacles",
    "step_us.zoo_obstacle_median",
    "zoo.robots_timed",
    "ratios.pink_over_panda_pose",
    "ratios.pink_over_panda_pose_obstacles",
    "ratios.python_over_panda_pose",
    "ratios.pink_over_solve",
    "solve.success_rate",
    "solve.median_us",
    "solve.python_median_us",
    "solve.pink_median_us",
    "case_study_all_runs_s",
    "memory_growth_mb.decimated",
    "memory_growth_mb.full",
    "memory_growth_mb.controller_session",
    "controller_session.result_ms",
    "sweep_runs_per_s.1_worker",
    "sweep_runs_per_s.2_workers",
    *(f"tick_us.{line}" for line in TICK_LINES),
    *(f"tick_quality.{line}" for line in TICK_LINES),
    "tick_error_m.panda_pose",
    *(f"tick_us.{line}" for line in (*CLOUD_TICK_LINES, OCTREE_LINE)),
    "cloud_update_ms",
)
"""Dotted key paths ``bench.json`` always holds (pink's and mink's are ``null`` without
them)."""

CLIK_STEP_US = {
    "planar4r": "planar4r",
    "planar4r_case_study_both": "planar4r_case_study_both",
    "panda_pose": "panda_pose",
    "panda_pose_transpose": "panda_pose_transpose",
    "panda_pose_obstacles": "panda_pose_obstacles_1_active",
    "panda_pose_obstacles_0_active": "panda_pose_obstacles_0_active",
    "panda_pose_obstacles_1_active": "panda_pose_obstacles_1_active",
    "panda_pose_obstacles_transpose": "panda_pose_obstacles_transpose",
    "dual_arm": "dual_arm",
    "humanoid": "humanoid",
}
"""``bench.json``'s ``step_us`` keys of clik's compiled engine and the line each is the
median of; ``panda_pose_obstacles`` is the line with one obstacle row active."""

STEP_US = {
    **CLIK_STEP_US,
    **{line_name(key, "python"): line_name(line, "python") for key, line in CLIK_STEP_US.items()},
    "pink_panda_pose": "pink_panda_pose",
    "pink_panda_pose_default_limits": "pink_panda_pose_default_limits",
    "pink_panda_pose_obstacles": "pink_panda_pose_obstacles",
    "pink_dual_arm": "pink_dual_arm",
}
"""``bench.json``'s ``step_us`` keys and the step line whose median each is: clik's
compiled engine, its Python engine's twins (``python_`` keys) and pink. The key
``zoo_obstacle_median`` is added beside them (:func:`~benchmarks.step_zoo.bench_zoo`)."""


@dataclass(frozen=True)
class Measured:
    """What each measurement returned.

    Attributes:
        steps: Per step line (:func:`~benchmarks.step.bench_steps`).
        solve: Single-pose solve (:func:`~benchmarks.solve.bench_solve`).
        case: Case study (:func:`~benchmarks.case_study.bench_case_study`).
        memory: Memory (:func:`~benchmarks.memory.bench_memory`).
        sweep: Sweep (:func:`~benchmarks.sweep_rate.bench_sweep`).
        zoo: The zoo's obstacle run (:func:`~benchmarks.step_zoo.bench_zoo`).
        ticks: Per tick line (:func:`~benchmarks.tick.bench_ticks`).
        session: A long controller session's memory
            (:func:`~benchmarks.session_memory.bench_session`).
        ros: The ROS 2 loop (:func:`~benchmarks.ros_line.bench_ros`).
        cloud: Point-cloud obstacles (:func:`~benchmarks.cloud_lines.bench_cloud`); empty
            when not measured.
    """

    steps: dict[str, Any]
    solve: dict[str, Any]
    case: dict[str, Any]
    memory: dict[str, Any]
    sweep: dict[str, Any]
    zoo: dict[str, Any]
    ticks: dict[str, Any]
    session: dict[str, Any]
    ros: dict[str, Any]
    cloud: dict[str, Any] = field(default_factory=dict)


def measure(config: BenchConfig, pink: Pink | None, mink: Mink | None, say: Log) -> Measured:
    """Run every measurement of the suite, in order.

    Args:
        config: Sizes of the suite.
        pink: The installed pink, or None to leave its lines out.
        mink: The installed mink, or None to leave its lines out.
        say: Progress callback.
    """
    say("step cost (interleaved rounds)")
    steps = bench_steps(config, pink, say)
    say("tick cost: one Python call per 1 ms tick (interleaved rounds)")
    ticks = bench_ticks(config, pink, mink, say)
    say("point-cloud obstacles: far and near ticks, a 50k-point update, coal's octree")
    cloud = bench_cloud(config, say)
    say("step cost of the zoo's obstacle run, robot by robot")
    zoo = bench_zoo(config, say)
    say("single-pose solve")
    solve = bench_solve(config, pink, say)
    say("case study")
    case = bench_case_study(config, say)
    say("memory (two subprocesses)")
    memory = bench_memory(config, say)
    say("memory of a controller session with events at every tick (a subprocess)")
    session = bench_session(config, say)
    say("sweep on a local Dask cluster, 1 and 2 workers")
    sweep = bench_sweep(config, say)
    say("ROS 2 loop on loopback (a private network namespace)")
    ros = bench_ros(config, say)
    return Measured(steps, solve, case, memory, sweep, zoo, ticks, session, ros, cloud)


def step_ratios(m: Measured) -> dict[str, Any]:
    """Ratios of medians: pink over clik's compiled engine, clik's Python engine over it.

    Args:
        m: What the measurements returned.

    Returns:
        Ratios of step medians (Panda pose, Panda pose with one obstacle row active)
        and of solve medians; ``python_over_compiled_steps`` holds every clik line's.
        A ratio is None when a figure is missing (pink not installed).
    """

    def median(name: str) -> float | None:
        return m.steps[name]["median_us"] if name in m.steps else None

    return {
        "pink_over_panda_pose": ratio(median("pink_panda_pose"), median("panda_pose")),
        "pink_over_panda_pose_obstacles": ratio(
            median("pink_panda_pose_obstacles"), median("panda_pose_obstacles_1_active")
        ),
        "python_over_panda_pose": ratio(median("python_panda_pose"), median("panda_pose")),
        "pink_over_solve": m.solve.get("speedup_vs_pink"),
        "python_over_solve": m.solve.get("python_over_compiled"),
        "python_over_compiled_steps": {
            line: ratio(median(line_name(line, "python")), median(line))
            for line in dict.fromkeys(CLIK_STEP_US.values())
        },
    }


def cloud_tick_us(m: Measured) -> dict[str, float | None]:
    """The cloud lines' ``tick_us``: ``cloud_far``, ``cloud_near``, ``coal_octree_cloud``.

    Args:
        m: What the measurements returned (None per line when the cloud was not measured).
    """
    measured = m.cloud.get("tick_us", {})
    return {line: measured.get(line) for line in (*CLOUD_TICK_LINES, OCTREE_LINE)}


def tick_figures(m: Measured) -> dict[str, Any]:
    """The tick lines: medians, quality, clik's final error and the peers' ratios.

    Args:
        m: What the measurements returned.

    Returns:
        ``tick_us`` and ``tick_quality`` (every line of
        :data:`~benchmarks.tick.TICK_LINES`, None when its library is missing; ``tick_us``
        also the cloud lines', :func:`cloud_tick_us`),
        ``tick_error_m.panda_pose`` (clik's position error at its last tick [m]),
        ``ticks`` (each line's statistics and info) and ``tick_ratios`` (pink's and
        mink's medians over clik's).
    """

    def median(line: str) -> float | None:
        return m.ticks[line]["median_us"] if line in m.ticks else None

    return {
        "tick_us": {**{line: median(line) for line in TICK_LINES}, **cloud_tick_us(m)},
        "tick_quality": {line: m.ticks.get(line, {}).get("quality") for line in TICK_LINES},
        "tick_error_m": {"panda_pose": m.ticks["panda_pose"]["final_error_m"]},
        "ticks": {
            line: {key: value for key, value in figures.items() if key != "quality"}
            for line, figures in m.ticks.items()
        },
        "tick_ratios": {
            f"{peer}_over_{line}": ratio(median(f"{peer}_{line}"), median(line))
            for peer in ("pink", "mink")
            for line in ("panda_pose", "panda_pose_obstacles", "dual_arm", "humanoid")
        },
    }


def figures(config: BenchConfig, m: Measured) -> dict[str, Any]:
    """The report's measured sections, from the step medians to the sweep.

    Args:
        config: Sizes of the suite.
        m: What the measurements returned.
    """
    step_us = {
        key: m.steps[line]["median_us"] if line in m.steps else None
        for key, line in STEP_US.items()
    }
    step_us["zoo_obstacle_median"] = m.zoo["median_us"]
    obstacles = m.steps["panda_pose_obstacles_1_active"]
    return {
        "step_us": step_us,
        "steps": m.steps,
        "zoo": m.zoo,
        "ratios": step_ratios(m),
        "solve": m.solve,
        "case_study_all_runs_s": m.case["all_runs_s"],
        "case_study": m.case,
        "panda_obstacles_run": {
            "duration_s": config.panda_duration,
            "wall_s": obstacles["median_us"] * 1e-6 * obstacles["steps_per_run"],
            "realtime_factor": obstacles["realtime_factor"],
        },
        "memory_growth_mb": {
            "full": m.memory["full"]["growth_mb"],
            "decimated": m.memory["decimated"]["growth_mb"],
            "controller_session": m.session["growth_after_10pct_mb"],
        },
        "memory": m.memory,
        "controller_session": m.session,
        "sweep_runs_per_s": {
            "1_worker": m.sweep["runs_per_s_1_worker"],
            "2_workers": m.sweep["runs_per_s_2_workers"],
        },
        "sweep": m.sweep,
        "ros": m.ros,
        **tick_figures(m),
        "cloud_update_ms": m.cloud.get("update_ms"),
        "cloud": m.cloud,
    }


def run_bench(
    out: Path, quick: bool = False, log: Log | None = None, targets: Path | None = None
) -> dict[str, Any]:
    """Run the suite and write ``out/bench.json`` and ``out/bench.md``.

    Args:
        out: Output folder (created if missing).
        quick: Smoke settings (:data:`~benchmarks.config.QUICK`): the same report
            structure in a few seconds.
        log: Called with one line per stage (e.g. ``print``); default silent.
        targets: Targets file; default the shipped ``targets.toml``.

    Returns:
        The report written to ``bench.json``.

    Raises:
        InputError: ``out`` is an existing file.
        OutputError: ``out`` cannot be created or written (named, with the OS reason).
    """
    say: Log = log if log is not None else (lambda _line: None)
    config = QUICK if quick else FULL
    target_list = load_targets(targets)
    out = Path(out)
    check_out_path(out)  # a file, a dangling link or a file as a parent: said before the bench
    with output_errors(out):
        out.mkdir(parents=True, exist_ok=True)
    pink, why_not = find_pink()
    mink, why_not_mink = find_mink()
    for peer, reason in (("pink", why_not), ("mink", why_not_mink)):
        if reason is not None:
            say(f"{peer} skipped, its lines left out: {reason}")
    report: dict[str, Any] = {
        "quick": quick,
        "config": asdict(config),
        "machine": machine_info(),
        "versions": versions(),
        "pink": {
            "solver": None if pink is None else pink.solver,
            "available": pink is not None,
            "reason": why_not,
        },
        "mink": {
            "solver": None if mink is None else mink.solver,
            "available": mink is not None,
            "reason": why_not_mink,
        },
    }
    started = time.perf_counter()
    cpu_started = cpu_seconds()
    report.update(figures(config, measure(config, pink, mink, say)))
    report["targets"] = evaluate_targets(report, target_list)
    report["bench_wall_time_s"] = time.perf_counter() - started
    # Below 1, other processes took the CPU during the bench: figures are inflated.
    report["machine"]["cpu_share"] = round(
        (cpu_seconds() - cpu_started) / report["bench_wall_time_s"], 3
    )
    if hasattr(os, "getloadavg"):
        report["machine"]["load_average_1min_end"] = round(os.getloadavg()[0], 2)
    text = markdown(report)
    with output_errors(out):  # each file whole or not at all
        write_json(out / "bench.json", report)
        atomic_write(out / "bench.md", lambda f: f.write(text), mode="w")
    return report


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m benchmarks --out DIR [--quick] [--quiet]``: run the suite, print ``bench.md``.

    The same as ``clik bench``, run from the checkout's root.

    Args:
        argv: Command-line arguments; default ``sys.argv[1:]``.
    """
    parser = argparse.ArgumentParser(prog="python -m benchmarks")
    parser.add_argument("--out", type=Path, default=Path("out/bench"), help="output folder")
    parser.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    args = parser.parse_args(argv)
    run_bench(args.out, quick=args.quick, log=None if args.quiet else print)
    print((args.out / "bench.md").read_text())
