"""The ``clik`` command line: ``solve``, ``demo``, ``robots``, ``show``.

Errors are printed without a traceback (``--debug`` shows it) and the exit
code tells the kind: 0 success, 2 bad input, 3 infeasible (the run stopped
with ``deadlock`` or ``diverged``; its outputs are still written), 4 internal.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from clik.errors import EXIT_CODES, ClikError, OutputExistsError
from clik.result import TrackingResult, write_json

INFEASIBLE_STATUSES = ("deadlock", "diverged")


def prepare_out(out: Path, force: bool) -> Path:
    """Create the output folder; an existing non-empty one needs ``force``."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())) and not force:
        raise OutputExistsError(out)
    out.mkdir(parents=True, exist_ok=True)
    return out


class ProgressBar:
    """A one-line progress bar on stderr, shown only on a terminal."""

    def __init__(self, label: str, enabled: bool | None = None) -> None:
        self.label = label
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.start = time.perf_counter()

    def __call__(self, k: int, n: int) -> None:
        if not self.enabled:
            return
        width = 30
        done = int(width * k / max(n, 1))
        elapsed = time.perf_counter() - self.start
        sys.stderr.write(
            f"\r{self.label} [{'#' * done}{'.' * (width - done)}] {k}/{n} {elapsed:.1f}s"
        )
        if k >= n:
            sys.stderr.write("\n")
        sys.stderr.flush()


def write_outputs(result: TrackingResult, out: Path) -> dict:
    """Write ``summary.json`` and ``trajectory.npz`` into ``out``; returns the summary."""
    summary = result.summary()
    write_json(out / "summary.json", summary)
    result.save(out / "trajectory.npz")
    return summary


def print_summary(name: str, summary: dict) -> None:
    """A few lines for a person."""
    unit = "rad" if summary["info"].get("task") == "orientation" else "m"
    print(f"{name}: {summary['status']} ({summary['reason']})")
    print(
        f"  steps {summary['steps']}, wall time {summary['wall_time_s']:.3f} s, "
        f"max tracking error {summary['max_task_error']:.3e} {unit}, "
        f"final {summary['final_task_error']:.3e} {unit}"
    )
    if summary.get("min_obstacle_distance") is not None:
        print(f"  min link-obstacle distance {summary['min_obstacle_distance']:.4f} m")
    if summary["events"]:
        print(
            "  events: "
            + ", ".join(
                f"{e['action']} {e['constraint']} @ {e['t']:.3f}s" for e in summary["events"]
            )
        )


def cmd_solve(args: argparse.Namespace) -> int:
    from clik.runner import build

    run = build(args.scenario)
    out = prepare_out(Path(args.out), args.force)
    result = run.execute(ProgressBar(run.scenario.name, None if not args.quiet else False))
    summary = write_outputs(result, out)
    write_extras(args, result, out, run.scenario.name)
    if not args.quiet:
        print_summary(run.scenario.name, summary)
        print(f"  wrote {out / 'summary.json'} and {out / 'trajectory.npz'}")
    return EXIT_CODES["infeasible"] if result.status in INFEASIBLE_STATUSES else 0


def write_extras(args: argparse.Namespace, result: TrackingResult, out: Path, name: str) -> None:
    """``--html`` and ``--plots`` of ``clik solve``."""
    if args.html:
        from clik.viz import export_html

        export_html(result, out / "scene.html")
    if args.plots:
        from clik.plot import save_result_plots

        save_result_plots([result], out, [name])


def cmd_demo(args: argparse.Namespace) -> int:
    from clik.demo import run_demo

    return run_demo(Path(args.out), force=args.force, quiet=args.quiet)


def cmd_show(args: argparse.Namespace) -> int:
    from clik.viz import show_path

    show_path(Path(args.target), block=not args.no_block)
    return 0


def cmd_robots(args: argparse.Namespace) -> int:
    from clik.robot import Robot

    for name, where in Robot.available().items():
        print(f"{name:32s} {where}")
    return 0


def parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    p = argparse.ArgumentParser(prog="clik", description=__doc__.splitlines()[0])
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("solve", help="run a scenario file")
    s.add_argument("scenario", type=Path)
    s.add_argument("--out", required=True, help="output folder")
    s.add_argument("--force", action="store_true", help="write into an existing output folder")
    s.add_argument("--html", action="store_true", help="also write DIR/scene.html")
    s.add_argument("--plots", action="store_true", help="also write PNG plots")
    s.add_argument("--quiet", action="store_true")
    s.set_defaults(func=cmd_solve)

    d = sub.add_parser("demo", help="run the paper's case study")
    d.add_argument("--out", default="out/demo")
    d.add_argument("--force", action="store_true")
    d.add_argument("--no-html", action="store_true", help="skip the HTML scenes")
    d.add_argument("--plots", action="store_true", help="(default) the paper's figures as PNG")
    d.add_argument("--no-plots", action="store_true", help="skip the figures")
    d.add_argument("--quiet", action="store_true")
    d.set_defaults(func=cmd_demo)

    v = sub.add_parser("show", help="open the live 3-D view of a scenario or an output folder")
    v.add_argument("target")
    v.add_argument("--no-block", action="store_true", help="return once the scene is shown")
    v.set_defaults(func=cmd_show)

    r = sub.add_parser("robots", help="list the robots known by name")
    r.set_defaults(func=cmd_robots)

    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``clik`` command."""
    args = parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ClikError as exc:
        if args.debug:
            raise
        print(f"clik: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("clik: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: say so, keep the traceback behind --debug
        if args.debug:
            raise
        print(
            f"clik: internal error: {type(exc).__name__}: {exc} (run with --debug for the "
            "traceback)",
            file=sys.stderr,
        )
        return EXIT_CODES["internal"]


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
