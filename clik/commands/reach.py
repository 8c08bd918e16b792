"""``clik reach``: a reachability map, single-pose IK over a grid of target points.

With ``--scenario``, the robot, its obstacles and its constraints come from the
scenario file (and the frame, unless ``--frame`` is given); angles are given in
degrees on the command line and converted to radians here, once.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from clik.errors import ClikError, InputError
from clik.outputs.io import output_errors
from clik.outputs.out_folder import output_folder

if TYPE_CHECKING:
    from clik.scenarios.scenario import Scenario
    from clik.sweep.reach_data import ReachSpec


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


def add_reach(sub: Any) -> None:
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
