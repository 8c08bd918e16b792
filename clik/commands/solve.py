"""``clik solve``: run a scenario file, write its outputs, say how it went.

Export options are checked before the run and before the output folder is
touched; the exit code is 3 (``infeasible``) when the run failed (its outputs
are still written).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tqdm import tqdm

from clik.errors import EXIT_CODES, InputError
from clik.outputs.export import check_exportable
from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_folder
from clik.outputs.result import FAILED_STATUSES, TrackingResult, write_outputs
from clik.outputs.rosbag_export import (
    BAG_FORMAT,
    BAG_NAME,
    EXPORT_CHOICES,
    check_rosbags,
    export_rosbag,
)
from clik.outputs.velocity_report import speed_line

if TYPE_CHECKING:
    from clik.tasks.goal import Goal


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
    primary = next(iter((summary.get("task_errors") or {"": {}}).values()))
    unit = primary.get("unit", "m")  # the primary task's, as its kind says
    print(f"{name}: {summary['status']} ({summary['reason']})")
    print(
        f"  steps {summary['steps']}, wall time {_number(summary['wall_time_s'], '.3f')} s, "
        f"max tracking error {_number(summary['max_task_error'], '.3e')} {unit}, "
        f"final {_number(summary['final_task_error'], '.3e')} {unit}"
    )
    print_task_errors(summary)
    obstacles = obstacle_line(summary)
    if obstacles is not None:
        print(f"  {obstacles}")
    speeds = speed_line(summary)
    if speeds is not None:
        print(f"  {speeds}")
    if summary["events"]:
        print(
            "  events: "
            + ", ".join(
                f"{e['action']} {e['constraint']} @ {e['t']:.3f}s" for e in summary["events"]
            )
        )


def obstacle_line(summary: dict) -> str | None:
    """``min link-obstacle distance 0.0298 m (clouds: scan 0.0298 m)``, or None: no obstacle.

    A cloud no link came within its search reach of (``threshold +``
    :data:`~clik.constraints.cloud_avoidance.SEARCH_MARGIN`; its distance is ``null``) is
    said to be farther than that reach.
    """
    from clik.constraints.cloud_avoidance import SEARCH_MARGIN

    nearest = summary.get("min_obstacle_distance")
    by_cloud = summary.get("min_cloud_distance_by_cloud") or {}
    if nearest is None and not by_cloud:
        return None
    reach = {
        c["name"]: float(c["threshold"]) + SEARCH_MARGIN
        for c in summary.get("info", {}).get("clouds", [])
    }
    clouds = [
        f"{name} {d:.4f} m" if d is not None else f"{name} > {reach.get(name, 0.0):.4f} m"
        for name, d in by_cloud.items()
    ]
    line = "min link-obstacle distance " + (
        f"{nearest:.4f} m" if nearest is not None else f"> {min(reach.values(), default=0.0):.4f} m"
    )
    return line + (f" (clouds: {', '.join(clouds)})" if clouds else "")


def print_task_errors(summary: dict) -> None:
    """One line per task of a several-task run: name, kind, priority, max and final errors.

    A run of one task (``task_errors`` is ``{"task": ...}``) says nothing more. Each
    entry's unit is what its kind says (``unit``; a second norm, a pose task's orientation
    errors, its ``second_unit``).
    """
    errors = summary.get("task_errors") or {}
    if list(errors) in ([], ["task"]):
        return
    units = summary["info"].get("task_units", {})
    width = max(len(name) for name in errors)
    for name, e in errors.items():
        unit = e.get("unit", units.get(name, "m"))
        line = (
            f"  task {name:<{width}}  {e.get('kind', '?'):<11} priority {e.get('priority', '?')}"
            f"  max {_number(e['max'], '.3e')} {unit}, final {_number(e['final'], '.3e')} {unit}"
        )
        if "max_orientation" in e:
            second = e.get("second_unit", "rad")
            line += (
                f"; {e.get('second_error', 'orientation error').split()[0]} max "
                f"{_number(e['max_orientation'], '.3e')} {second}, "
                f"final {_number(e['final_orientation'], '.3e')} {second}"
            )
        print(line)


def cmd_solve(args: argparse.Namespace) -> int:
    """``clik solve``: run a scenario file, write its outputs; 3 when the run failed.

    Export options are checked before the run and before the output folder is touched.
    """
    from clik.scenarios.runner import build
    from clik.tasks.goal import Goal

    if args.export_every is not None and not args.export:
        raise InputError("--export-every", "to be given with --export", args.export_every)
    run = build(scenario_file(args.scenario))
    if args.engine is not None:
        run.tracker.engine = args.engine
    if args.export:
        check_exportable(run.robot.model)
    if args.export and BAG_FORMAT in args.export:
        check_rosbags()  # before the run: without rosbags, say how to get it
    out = Path(args.out)
    with output_folder(out, args.force) as work:
        result = run.execute(ProgressBar(run.scenario.name, None if not args.quiet else False))
        with output_errors(out):
            summary = write_outputs(result, work)
            targets = run.goals or [Goal(run.task, run.trajectory, name="task")]
            written = write_extras(args, result, work, run.scenario.name, run.goals, targets)
    extras = [out / p.relative_to(work) for p in written]
    if not args.quiet:
        print_summary(run.scenario.name, summary)
        print("  " + wrote_line([out / "summary.json", out / "trajectory.npz", *extras]))
    return EXIT_CODES["infeasible"] if result.status in FAILED_STATUSES else 0


def wrote_line(files: Sequence[Path]) -> str:
    """``wrote DIR/a, DIR/b and DIR/c``: every file a command wrote, in one line."""
    names = [str(p) for p in files]
    if len(names) < 2:
        return "wrote " + "".join(names)
    return f"wrote {', '.join(names[:-1])} and {names[-1]}"


def scenario_file(text: str | Path) -> Path:
    """The scenario ``clik solve`` runs: a file, else a shipped scenario's name.

    Shipped names are those a sweep's ``base`` accepts (:func:`clik.sweep.spec.locate_scenario`).

    Raises:
        InputError: Neither a file nor a shipped name; the message lists the shipped names.
    """
    from clik.sweep.spec import locate_scenario, shipped_scenarios

    found = locate_scenario(str(text), Path.cwd())
    if found is None and ("/" in str(text) or str(text).endswith(".toml")):
        raise InputError("scenario", "an existing scenario file (no such scenario file)", str(text))
    if found is None:
        raise InputError(
            "scenario",
            "a scenario file or a shipped scenario name: " + ", ".join(shipped_scenarios()),
            str(text),
        )
    return found


def write_extras(
    args: argparse.Namespace, result: TrackingResult, out: Path, name: str,
    goals: Sequence[Goal] = (), targets: Sequence[Goal] | None = None,
) -> list[Path]:  # fmt: skip
    """``--export``, ``--html`` and ``--plots`` of ``clik solve``; the exported files.

    ``goals``: a several-task scenario's tasks, whose references and trails the view draws.
    ``targets``: the run's tasks (its goals, or its one task as a goal), for a bag's
    target topics (:func:`clik.outputs.rosbag_export.export_rosbag`).
    """
    written: list[Path] = []
    if args.export:
        every = 1 if args.export_every is None else args.export_every
        files = [f for f in args.export if f != BAG_FORMAT]
        if files:
            written += result.export(out, files, every).values()
        if BAG_FORMAT in args.export:
            written.append(export_rosbag(result, out, every, goals=targets))
    if args.html:
        from clik.viz import export_html

        several = list(goals) if len(goals) > 1 else None
        written.append(export_html(result, out / "scene.html", tasks=several))
    if args.plots:
        from clik.plot import save_result_plots

        written += save_result_plots([result], out, [name])
    return written


def _shipped() -> list[str]:
    """The shipped scenarios' names, for the help text."""
    from clik.sweep.spec import shipped_scenarios

    return shipped_scenarios()


def _export_every(text: str) -> int:
    """The ``K`` of ``clik solve --export-every K``: an integer >= 1."""
    try:
        every = int(text)
    except ValueError:
        every = 0
    if every < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return every


def add_solve(sub: Any) -> None:
    """The ``clik solve`` subcommand."""
    s = sub.add_parser(
        "solve",
        help="run a scenario file (or a shipped scenario by name)",
        description="Run a scenario: a TOML file, or the name of a shipped scenario "
        "(clik/scenarios/NAME.toml, as a sweep's base accepts). Shipped: "
        + ", ".join(_shipped())
        + ". Exit code 3 (infeasible) when the run ends "
        + ", ".join(FAILED_STATUSES[:-1])
        + f" or {FAILED_STATUSES[-1]} (its outputs are still written), 2 on bad input.",
    )
    s.add_argument(
        "scenario",
        metavar="SCENARIO",
        help="a scenario file (.toml) or a shipped scenario's name (panda_circle, ...)",
    )
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
        action="extend",  # repeatable: --export csv --export json is --export csv json
        nargs="+",
        choices=EXPORT_CHOICES,
        metavar="FORMAT",
        help="also write the joint trajectory for a controller: csv (DIR/trajectory.csv), "
        "json (DIR/trajectory.json, a ROS JointTrajectory), rosbag (DIR/"
        f"{BAG_NAME}/, a ROS 2 MCAP bag of joint states, commands and task targets; "
        "pip install 'clik[ros]'), or several (repeatable)",
    )
    s.add_argument(
        "--export-every",
        type=_export_every,
        metavar="K",
        help="export every K-th recorded sample and the last (default 1: all)",
    )
    s.add_argument("--quiet", action="store_true")
    s.set_defaults(func=cmd_solve)
