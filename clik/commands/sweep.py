"""``clik sweep``: run a sweep file (many scenarios) on Dask, and count its runs per status.

Exit code 1 (:data:`SWEEP_FAILED`) when a run in the output folder raised, or
ended ``violated``, ``velocity_limit`` or ``diverged``; every row is still written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

SWEEP_FAILED = 1
"""Exit code of ``clik sweep`` when a run in its folder raised or ended violated or diverged."""


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep; 1 (:data:`SWEEP_FAILED`) when a run in the folder failed, else 0.

    The last line printed (unless ``--quiet``) counts every run in the folder
    per status, e.g. ``completed 118, deadlock 1, violated 1, raised 0``. A
    failed sweep also says so on stderr, ``--quiet`` or not.
    """
    from clik.sweep.execute import run_sweep
    from clik.sweep.report import status_line
    from clik.sweep.spec import load_sweep

    sweep = load_sweep(args.sweep)
    try:
        report = run_sweep(
            sweep,
            Path(args.out),
            workers=args.workers,
            scheduler=args.scheduler,
            keep_trajectories=args.keep_trajectories,
            force=args.force,
            fmt=args.format,
            progress=False if args.quiet else None,
        )
    except KeyboardInterrupt:
        print(
            f"clik sweep: stopped; the finished runs are in {args.out}: run the same command "
            "again to compute the others",
            file=sys.stderr,
        )
        raise
    if not args.quiet:
        counts = ", ".join(f"{n} {s}" for s, n in sorted(report.statuses.items())) or "nothing"
        print(
            f"{sweep.name}: {report.total} runs, {report.skipped} already in {args.out}, "
            f"{report.computed} computed ({counts}) in {report.wall_time_s:.1f} s "
            f"({report.rate:.2f} runs/s)"
        )
        if report.lost:
            print(f"  {report.lost} runs were cancelled by the cluster: rerun to compute them")
        print(f"  wrote {report.results}")
        print(status_line(report.all_statuses))
    if report.failed:
        print(
            f"clik sweep: {report.failed} of {sum(report.all_statuses.values())} runs failed "
            f"({status_line(report.all_statuses)}); their status, reason and error are in "
            f"{report.results}",
            file=sys.stderr,
        )
        return SWEEP_FAILED
    return 0


def add_sweep(sub: Any) -> None:
    """The ``clik sweep`` subcommand."""
    w = sub.add_parser(
        "sweep",
        help="run a sweep file (many scenarios) on Dask",
        description="Run a sweep file (many scenarios) on Dask. Exit code 1 when a run in the "
        "output folder raised or ended violated or diverged (every row is still written); the "
        "last line counts the runs per status.",
    )
    w.add_argument("sweep", type=Path, help="the sweep file (TOML)")
    w.add_argument("--out", required=True, help="output folder (rerun to resume)")
    where = w.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="local worker processes (default: one per CPU)")
    where.add_argument("--scheduler", help="an existing Dask scheduler, tcp://HOST:PORT")
    w.add_argument(
        "--keep-trajectories", action="store_true", help="also write DIR/runs/<id>/ per run"
    )
    w.add_argument("--force", action="store_true", help="start over in a folder holding others")
    w.add_argument(
        "--format", choices=("auto", "parquet", "csv"), default="auto", help="results table"
    )
    w.add_argument("--quiet", action="store_true")
    w.set_defaults(func=cmd_sweep)
