"""``clik sweep``: run a sweep file (many scenarios) on Dask, and count its runs per status.

Exit code 1 (:data:`SWEEP_FAILED`) when a run in the output folder raised, or
ended with a status of :data:`clik.sweep.report.FAILED_STATUSES`; every row is
still written (:func:`failed_text` says so in ``--help``). ``clik sweep --table
DIR`` prints a finished sweep's results table as CSV, without pandas.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

SWEEP_FAILED = 1
"""Exit code of ``clik sweep`` when a run in its folder raised or ended with a failed status."""


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep; 1 (:data:`SWEEP_FAILED`) when a run in the folder failed, else 0.

    The last line printed (unless ``--quiet``) counts every run in the folder
    per status, e.g. ``completed 118, deadlock 1, violated 1, raised 0``. A
    failed sweep also says so on stderr, ``--quiet`` or not.
    """
    from clik.errors import InputError
    from clik.sweep.execute import run_sweep
    from clik.sweep.report import status_line
    from clik.sweep.spec import load_sweep

    if args.table is not None:
        from clik.sweep.table import results_csv

        sys.stdout.write(results_csv(args.table))
        return 0
    if args.sweep is None:
        raise InputError("sweep", "a sweep file (or --table DIR to print a results table)")
    if args.out is None:
        raise InputError("--out", "an output folder (rerun to resume)")
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
        print(f"  wrote {report.results} (clik sweep --table {args.out} prints it as CSV)")
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


def failed_text() -> str:
    """The exit-1 sentence of ``clik sweep --help``, from the statuses' table in code.

    The statuses are :data:`clik.sweep.report.FAILED_STATUSES`, so help and code agree.
    """
    from clik.sweep.report import FAILED_STATUSES, RAISED, STATUS_ORDER

    listed = [s for s in STATUS_ORDER if s in FAILED_STATUSES]
    listed += sorted(FAILED_STATUSES - set(listed))
    return (
        f"Exit code {SWEEP_FAILED} when a run in the output folder raised (status {RAISED}) "
        f"or ended {', '.join(listed[:-1])} or {listed[-1]} (every row is still written)."
    )


def add_sweep(sub: Any) -> None:
    """The ``clik sweep`` subcommand."""
    w = sub.add_parser(
        "sweep",
        help="run a sweep file (many scenarios) on Dask",
        description="Run a sweep file (many scenarios) on Dask. " + failed_text() + " The "
        "last line counts the runs per status. clik sweep --table DIR prints the results "
        "table of a sweep's output folder as CSV (no pandas needed).",
    )
    w.add_argument("sweep", type=Path, nargs="?", help="the sweep file (TOML)")
    w.add_argument("--out", help="output folder (rerun to resume); required to run a sweep")
    w.add_argument(
        "--table",
        metavar="DIR",
        help="print the results table of the sweep output folder DIR as CSV, run nothing",
    )
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
