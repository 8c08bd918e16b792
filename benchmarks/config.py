"""Sizes of the benchmark suite (full and ``--quick``) and its sample time."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class BenchConfig:
    """Sizes of the suite.

    Attributes:
        rounds: Rounds of the step benchmark (every variant runs once per round).
        panda_duration: Length of the Panda runs [s] (the shipped circle lasts 3 s).
        solve_targets: Random reachable poses for the single-pose solve.
        pink_max_iterations: Iteration cap of pink's solve to convergence.
        case_study_rounds: Repeats of the eight case-study runs.
        memory_samples: Samples of the planar run whose peak RSS is measured.
        memory_record_every: Decimation of the memory run's decimated variant.
        session_ticks: Ticks of the controller session whose memory is measured.
        sweep_runs: Runs of the timed sweep (enough that the sweep's fixed costs, submission
            and the final write, weigh little against the steady rate).
        sweep_repeats: Alternations of the 1- and 2-worker sweeps (median taken).
        seed: Seed of the random solve targets.
        zoo_robots: Robots of the zoo line (None: every robot ``clik.Robot.available()``
            lists).
        zoo_rounds: Timed runs of each zoo robot (after one warm-up run).
    """

    rounds: int = 11
    panda_duration: float = 3.0
    solve_targets: int = 1000
    pink_max_iterations: int = 100
    case_study_rounds: int = 5
    memory_samples: int = 1_000_000
    memory_record_every: int = 1000
    session_ticks: int = 1_000_000
    sweep_runs: int = 360
    sweep_repeats: int = 3
    seed: int = 6
    zoo_robots: tuple[str, ...] | None = None
    zoo_rounds: int = 5


FULL = BenchConfig()
"""The settings of a real measurement (``clik bench``)."""
QUICK = BenchConfig(
    rounds=1,
    panda_duration=0.1,
    solve_targets=4,
    pink_max_iterations=30,
    case_study_rounds=1,
    memory_samples=5_000,
    memory_record_every=100,
    session_ticks=3_000,
    sweep_runs=4,
    sweep_repeats=1,
    zoo_robots=("planar4r", "double_pendulum_simple", "finger_edu", "ur5", "panda"),
    zoo_rounds=1,
)
"""Smoke settings (``--quick``): every line runs, with tiny counts, in a few seconds."""

DT = 1e-3
"""Sample time of every run [s]."""

Log = Callable[[str], None]
"""Progress callback: called with one line per stage (e.g. ``print``)."""
