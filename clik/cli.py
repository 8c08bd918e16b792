"""The ``clik`` command line: solve, demo, show, robots, sweep, reach and bench.

Errors are printed without a traceback (``--debug`` shows it) and the exit
code tells the kind: 0 success, 1 a sweep with failed runs (``clik sweep``:
a run raised, or ended ``violated``, ``velocity_limit`` or ``diverged``; every
row is still written), 2 bad input, 3 infeasible (the run ended ``violated``,
``velocity_limit``, ``deadlock`` or ``diverged``; its outputs are still
written), 4 internal; 130 after Ctrl-C, 143 after SIGTERM (the output folder is
then left as it was: :mod:`clik.outputs.out_folder`), 141 when stdout is closed early
(``clik robots | head -1``: quietly, like a process stopped by SIGPIPE).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tqdm import tqdm

from clik.errors import EXIT_CODES, ClikError, InputError
from clik.outputs.export import FORMATS, check_exportable
from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_folder
from clik.outputs.result import FAILED_STATUSES, TrackingResult, write_outputs

if TYPE_CHECKING:
    from clik.scenarios.scenario import Scenario
    from clik.sweep.reach_data import ReachSpec

SWEEP_FAILED = 1
"""Exit code of ``clik sweep`` when a run in its folder raised or ended violated or diverged."""

BROKEN_PIPE = 141
"""Exit code when stdout was closed by its reader (``| head``): 128 + SIGPIPE, as a shell says."""


class ProgressBar:
    """A run's progress on stderr (tqdm), shown only on a terminal unless ``enabled``.

    Args:
        label: Shown before the bar (the scenario's name).
        enabled: ``None``: only when stderr is a terminal.
    """

    def __init__(self, label: str, enabled: bool | None = None) -> None:
        self.label = label
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.bar: tqdm | None = None

    def __call__(self, k: int, n: int) -> None:
        """Sample ``k`` of ``n`` is done (the tracker's progress callback)."""
        if not self.enabled:
            return
        if self.bar is None:
            self.bar = tqdm(total=n, desc=self.label, unit="sample", file=sys.stderr)
        self.bar.update(k - self.bar.n)
        if k >= n:
            self.bar.close()


def _number(value: float | None, spec: str) -> str:
    """``value`` formatted with ``spec``; ``null`` for a value not finite in the summary."""
    return "null" if value is None else format(value, spec)


def print_summary(name: str, summary: dict) -> None:
    """A few lines for a person."""
    unit = "rad" if summary["info"].get("task") == "orientation" else "m"
    print(f"{name}: {summary['status']} ({summary['reason']})")
    print(
        f"  steps {summary['steps']}, wall time {_number(summary['wall_time_s'], '.3f')} s, "
        f"max tracking error {_number(summary['max_task_error'], '.3e')} {unit}, "
        f"final {_number(summary['final_task_error'], '.3e')} {unit}"
    )
    if summary.get("min_obstacle_distance") is not None:
        print(f"  min link-obstacle distance {summary['min_obstacle_distance']:.4f} m")
    ratio = summary.get("max_velocity_ratio")
    if ratio is not None:
        over = ", ".join(
            f"{v['joint']} x{v['max_ratio']:.2f} from t = {v['t_first']:.3f} s"
            for v in summary.get("velocity", [])
        )
        line = f"  joint speed: max |qdot| / URDF limit {ratio:.2f}"
        print(line + (f" (over the limit: {over})" if over else ""))
    if summary["events"]:
        print(
            "  events: "
            + ", ".join(
                f"{e['action']} {e['constraint']} @ {e['t']:.3f}s" for e in summary["events"]
            )
        )


def cmd_solve(args: argparse.Namespace) -> int:
    """``clik solve``: run a scenario file, write its outputs; 3 when the run failed.

    Export options are checked before the run and before the output folder is touched.
    """
    from clik.scenarios.runner import build

    if args.export_every is not None and not args.export:
        raise InputError("--export-every", "to be given with --export", args.export_every)
    run = build(args.scenario)
    if args.engine is not None:
        run.tracker.engine = args.engine
    if args.export:
        check_exportable(run.robot.model)
    out = Path(args.out)
    with output_folder(out, args.force) as work:
        result = run.execute(ProgressBar(run.scenario.name, None if not args.quiet else False))
        with output_errors(out):
            summary = write_outputs(result, work)
            written = write_extras(args, result, work, run.scenario.name)
    extras = [out / p.relative_to(work) for p in written]
    if not args.quiet:
        print_summary(run.scenario.name, summary)
        print(f"  wrote {out / 'summary.json'} and {out / 'trajectory.npz'}")
        if extras:
            print("  and " + ", ".join(str(p) for p in extras))
    return EXIT_CODES["infeasible"] if result.status in FAILED_STATUSES else 0


def write_extras(
    args: argparse.Namespace, result: TrackingResult, out: Path, name: str
) -> list[Path]:
    """``--export``, ``--html`` and ``--plots`` of ``clik solve``; the exported files."""
    written: list[Path] = []
    if args.export:
        every = 1 if args.export_every is None else args.export_every
        written += result.export(out, args.export, every).values()
    if args.html:
        from clik.viz import export_html

        export_html(result, out / "scene.html")
    if args.plots:
        from clik.plot import save_result_plots

        save_result_plots([result], out, [name])
    return written


def _export_every(text: str) -> int:
    """The ``K`` of ``clik solve --export-every K``: an integer >= 1."""
    try:
        every = int(text)
    except ValueError:
        every = 0
    if every < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return every


def cmd_demo(args: argparse.Namespace) -> int:
    """``clik demo``: the paper's case study, with its table and figures."""
    from clik.demo import run_demo

    return run_demo(
        Path(args.out),
        force=args.force,
        html=not args.no_html,
        plots=not args.no_plots,
        quiet=args.quiet,
    )


def cmd_show(args: argparse.Namespace) -> int:
    """``clik show``: the live 3-D view of a scenario or an output folder."""
    from clik.viz import show_path

    show_path(Path(args.target), block=not args.no_block)
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """``clik bench``: the benchmark suite (``bench.json``, ``bench.md``)."""
    from clik.bench.suite import run_bench

    run_bench(Path(args.out), quick=args.quick, log=None if args.quiet else print)
    return 0


def cmd_robots(args: argparse.Namespace) -> int:
    """``clik robots``: the robots known by name, and where each is found."""
    from clik.model.robot import Robot

    for name, where in Robot.available().items():
        print(f"{name:32s} {where}")
    return 0


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


def _lock_item(text: str) -> tuple[str, float]:
    """``JOINT=VALUE`` of ``clik reach --lock``."""
    name, sep, value = text.partition("=")
    try:
        if not sep or not name:
            raise ValueError
        return name, float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected JOINT=VALUE, got {text!r}") from None


def _radians3(degrees: Sequence[float]) -> tuple[float, float, float]:
    """Three angles from degrees to radians."""
    roll, pitch, yaw = (math.radians(v) for v in degrees)
    return roll, pitch, yaw


def cmd_reach(args: argparse.Namespace) -> int:
    """``clik reach``: a reachability map over a grid of target points.

    With ``--scenario``, the robot, its obstacles and its constraints come from the
    scenario file, and the frame too unless ``--frame`` is given; the grid, the task
    kind (``--orientation``) and its axes still come from the flags. Points solved
    without the constraints but not with them are counted as blocked.
    """
    from clik.sweep.reach import check_spec, reach_map
    from clik.sweep.reach_output import write_reach

    spec = _reach_spec(args)
    check_spec(spec)
    out = Path(args.out)
    with output_folder(out, args.force) as work:
        reach = reach_map(
            spec,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=False if args.quiet else None,
        )
        with output_errors(out):
            files = write_reach(reach, work, html=not args.no_html)
    written = {kind: out / path.relative_to(work) for kind, path in files.items()}
    if not args.quiet:
        counts = reach.counts()
        line = (
            f"reach {spec.robot} {spec.frame}: {counts['reachable']}/{len(reach.points)} "
            f"points reachable ({100 * reach.reachable_fraction:.1f} %)"
        )
        if spec.scenario is not None:
            line += f", {counts['blocked']} blocked by the constraints"
        print(f"{line}, {counts['unreachable']} unreachable in {reach.wall_time_s:.1f} s")
        print("  wrote " + ", ".join(str(p) for p in written.values()))
    return 0


def _reach_spec(args: argparse.Namespace) -> ReachSpec:
    """The :class:`~clik.sweep.reach_data.ReachSpec` of ``clik reach``'s arguments.

    Raises:
        InputError: Neither or both of ROBOT and ``--scenario``, no frame, or a
            ``--scenario`` that is not a readable scenario file.
    """
    from clik.sweep.reach_data import ReachSpec

    robot, frame = args.robot, args.frame
    scenario_file, scenario_data = None, None
    if args.scenario is not None:
        if robot is not None:
            raise InputError("--scenario", "no ROBOT argument with it (its [robot] is used)", robot)
        scenario = _reach_scenario(args.scenario)
        robot, frame = scenario.robot["source"], frame or scenario.task["frame"]
        scenario_file, scenario_data = str(scenario.file.resolve()), scenario.raw
    elif robot is None:
        raise InputError("ROBOT", "a robot name or URDF path (or --scenario SCENARIO.toml)")
    if frame is None:
        raise InputError("--frame", "the frame to place (taken from --scenario's task if given)")
    return ReachSpec(
        robot=robot,
        frame=frame,
        box=tuple(args.box),
        step=args.step,
        orientation_rpy=None if args.orientation is None else _radians3(args.orientation),
        lock=dict(args.lock or []),
        axes=tuple(args.axes) if args.axes else None,
        restarts=args.restarts,
        scenario=scenario_file,
        scenario_data=scenario_data,
        tracking_attempts=args.tracking_attempts,
    )


def _reach_scenario(path: Path) -> Scenario:
    """The scenario of ``clik reach --scenario``; any problem with it names the flag."""
    from clik.scenarios.scenario import load_scenario

    try:
        return load_scenario(path)
    except ClikError as exc:
        raise InputError("--scenario", f"a scenario file ({exc})") from None


def _add_solve(sub: Any) -> None:
    """The ``clik solve`` subcommand."""
    s = sub.add_parser("solve", help="run a scenario file")
    s.add_argument("scenario", type=Path)
    s.add_argument("--out", required=True, help="output folder")
    s.add_argument("--force", action="store_true", help="write into an existing output folder")
    s.add_argument("--html", action="store_true", help="also write DIR/scene.html")
    s.add_argument("--plots", action="store_true", help="also write PNG plots")
    s.add_argument(
        "--engine",
        choices=("compiled", "python"),
        help="compiled (default: the scenario's [solver] engine) or python (the reference loop)",
    )
    s.add_argument(
        "--export",
        nargs="+",
        choices=FORMATS,
        metavar="FORMAT",
        help="also write the joint trajectory for a controller: csv (DIR/trajectory.csv), "
        "json (DIR/trajectory.json, a ROS JointTrajectory), or both",
    )
    s.add_argument(
        "--export-every",
        type=_export_every,
        metavar="K",
        help="export every K-th recorded sample and the last (default 1: all)",
    )
    s.add_argument("--quiet", action="store_true")
    s.set_defaults(func=cmd_solve)


def _add_demo(sub: Any) -> None:
    """The ``clik demo`` subcommand."""
    d = sub.add_parser("demo", help="run the paper's case study")
    d.add_argument("--out", default="out/demo")
    d.add_argument("--force", action="store_true")
    d.add_argument("--no-html", action="store_true", help="skip the HTML scenes")
    figures = d.add_mutually_exclusive_group()
    figures.add_argument(
        "--plots", action="store_true", help="(default) the paper's figures as PNG"
    )
    figures.add_argument("--no-plots", action="store_true", help="skip the figures")
    d.add_argument("--quiet", action="store_true")
    d.set_defaults(func=cmd_demo)


def _add_show(sub: Any) -> None:
    """The ``clik show`` subcommand."""
    v = sub.add_parser("show", help="open the live 3-D view of a scenario or an output folder")
    v.add_argument("target")
    v.add_argument("--no-block", action="store_true", help="return once the scene is shown")
    v.set_defaults(func=cmd_show)


def _add_robots(sub: Any) -> None:
    """The ``clik robots`` subcommand."""
    r = sub.add_parser("robots", help="list the robots known by name")
    r.set_defaults(func=cmd_robots)


def _add_bench(sub: Any) -> None:
    """The ``clik bench`` subcommand."""
    b = sub.add_parser("bench", help="run the benchmark suite (writes bench.json, bench.md)")
    b.add_argument("--out", default="out/bench", help="output folder")
    b.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    b.add_argument("--quiet", action="store_true")
    b.set_defaults(func=cmd_bench)


def _add_sweep(sub: Any) -> None:
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


def _add_reach(sub: Any) -> None:
    """The ``clik reach`` subcommand."""
    a = sub.add_parser("reach", help="reachability map: single-pose IK over a grid of points")
    a.add_argument("robot", nargs="?", help="robot name or URDF path (or give --scenario)")
    a.add_argument(
        "--scenario",
        type=Path,
        metavar="SCENARIO.toml",
        help="take the robot, its obstacles and constraints (and the frame, without "
        "--frame) from a scenario file; points they block are counted apart",
    )
    a.add_argument("--frame", help="the frame to place (default: the scenario's task frame)")
    a.add_argument(
        "--box",
        nargs=6,
        type=float,
        required=True,
        metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
        help="the box of target points [m]",
    )
    a.add_argument("--step", type=float, required=True, help="grid spacing [m]")
    a.add_argument(
        "--orientation",
        nargs=3,
        type=float,
        metavar=("ROLL", "PITCH", "YAW"),
        help="fixed orientation [deg] (a pose task; default: a position task)",
    )
    a.add_argument(
        "--lock",
        nargs="+",
        action="extend",
        type=_lock_item,
        metavar="JOINT=VALUE",
        help="lock joints, values in the joint's unit [rad or m]",
    )
    a.add_argument("--axes", nargs="+", help="task components kept, e.g. x y (planar arm)")
    a.add_argument("--restarts", type=int, default=20, help="random restarts per point")
    a.add_argument(
        "--tracking-attempts",
        type=int,
        default=4,
        help="with --scenario: starts of the constrained law per blocked point",
    )
    a.add_argument("--out", required=True, help="output folder")
    where = a.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="local worker processes (default: one per CPU)")
    where.add_argument("--scheduler", help="an existing Dask scheduler, tcp://HOST:PORT")
    a.add_argument("--force", action="store_true", help="write into an existing output folder")
    a.add_argument("--no-html", action="store_true", help="skip DIR/reach.html")
    a.add_argument("--quiet", action="store_true")
    a.set_defaults(func=cmd_reach)


def parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    p = argparse.ArgumentParser(prog="clik", description=__doc__.splitlines()[0].replace("``", ""))
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = p.add_subparsers(dest="command", required=True)
    _add_solve(sub)
    _add_demo(sub)
    _add_show(sub)
    _add_robots(sub)
    _add_bench(sub)
    _add_sweep(sub)
    _add_reach(sub)
    return p


def _silence_stdout() -> None:
    """Point stdout at ``os.devnull``: its reader is gone, and a last flush would fail."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (AttributeError, OSError, ValueError):  # no file descriptor (a test's capture)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``clik`` command (exit codes: see the module's docstring)."""
    args = parser().parse_args(argv)
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # here, not at exit: a closed pipe is then a BrokenPipeError below
        return code
    except ClikError as exc:
        if args.debug:
            raise
        print(f"clik: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM during a run (out_folder.Terminated)
        code = getattr(exc, "exit_code", 130)
        print("clik: " + ("interrupted" if code == 130 else "terminated"), file=sys.stderr)
        return int(code)
    except BrokenPipeError:
        _silence_stdout()
        return BROKEN_PIPE
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
