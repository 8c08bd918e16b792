"""``clik demo``, ``clik show`` and ``clik robots``: each hands over to one room.

The case study (:mod:`clik.demo`), the live 3-D view (:mod:`clik.viz`) and the robots
known by name (:class:`~clik.model.robot.Robot`) or found in a ROS workspace
(:mod:`clik.model.descriptions`); these commands only read their flags. ``clik bench``
is :mod:`clik.commands.bench`.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


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


def cmd_robots(args: argparse.Namespace) -> int:
    """``clik robots``: the robots known by name; with ``--path WS``, those in a workspace."""
    if args.path is not None:
        return _workspace_robots(Path(args.path))
    from clik.model.robot import Robot

    for name, where in Robot.available().items():
        print(f"{name:32s} {where}")
    return 0


def _workspace_robots(folder: Path) -> int:
    """``clik robots --path WS``: each robot description in the workspace, and how to load it.

    Exit code 0 when some are found, 1 when none (said in words).
    """
    from clik.model.descriptions import robot_descriptions

    found, skipped = robot_descriptions(folder)  # InputError: not a folder, budgets
    for bad in skipped:
        print(f"skipped {bad.path}: {bad.problem}")
    if not found:
        print(
            f"no robot description (a *.urdf or *.xacro file with a <robot> root, inside a "
            f"ROS package: a folder with a package.xml) found under {folder}"
        )
        return 1
    width = max(len("package"), *(len(item.package) for item in found))
    print(f"{'package':{width}s} file")
    for item in found:
        print(f"{item.package:{width}s} {item.path}")
    from clik.model.packages import PackageDirs

    for name, same in sorted(PackageDirs([folder]).packages_under(folder).items()):
        if len(same) > 1:  # colcon refuses the pair; so does Robot.load, when it is used
            print(
                f"\nnote: {len(same)} packages named {name!r} ("
                + ", ".join(str(p.manifest) for p in same)
                + "): a robot using it will not load from this folder; put a COLCON_IGNORE "
                "file in the folder of the one not to use"
            )
    print(f"\nload one with Robot.load(path, package_dirs=[{str(folder)!r}])")
    print(f'or in a scenario: [robot] source = "path", package_dirs = ["{folder}"]')
    return 0


def add_demo(sub: Any) -> None:
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


def add_show(sub: Any) -> None:
    """The ``clik show`` subcommand."""
    v = sub.add_parser("show", help="open the live 3-D view of a scenario or an output folder")
    v.add_argument("target")
    v.add_argument("--no-block", action="store_true", help="return once the scene is shown")
    v.set_defaults(func=cmd_show)


def add_robots(sub: Any) -> None:
    """The ``clik robots`` subcommand."""
    r = sub.add_parser("robots", help="list the robots known by name, or in a ROS workspace")
    r.add_argument(
        "--path",
        metavar="WS",
        help="list the robot descriptions (URDF, xacro) in the ROS packages under this folder",
    )
    r.set_defaults(func=cmd_robots)
