"""``clik simulate OUT``: replay a run of ``clik solve`` in MuJoCo (the physics check).

Writes ``simulation.json`` and ``simulation.png`` into the output folder (or ``--out``)
and prints the same in words; an existing ``simulation.json`` is replaced only with
``--force``. Exit code 3 when the replayed robot touches an obstacle (a clearance below
zero), else 0.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from clik.errors import EXIT_CODES, InputError
from clik.outputs.io import output_errors
from clik.sim.report import SIMULATION_FILE
from clik.sim.servo import KP, KV, TIMESTEP


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run ``clik simulate`` (see the module docstring)."""
    from clik.sim import simulate
    from clik.viz.target import load_target

    target = Path(args.target)
    if args.out is None and not target.is_dir():
        raise InputError("--out", f"a folder to write into (OUT {target} is not a folder)")
    folder = target if args.out is None else Path(args.out)
    path = folder / SIMULATION_FILE
    if path.exists() and not args.force:
        raise InputError(
            str(path), "a new file (it exists: pass --force to replace it, or --out DIR)"
        )
    result = load_target(target)
    simulation = simulate(
        result, feedforward=not args.no_feedforward, kp=args.kp, kv=args.kv,
        timestep=args.timestep,
    )  # fmt: skip
    with output_errors(folder):
        folder.mkdir(parents=True, exist_ok=True)
        written = simulation.write(folder, force=args.force)
    print(simulation.words())
    print("  wrote " + " and ".join(str(p) for p in written))
    clearance = simulation.summary()["min_clearance_m"]
    return EXIT_CODES["infeasible"] if clearance is not None and clearance < 0 else 0


def add_simulate(sub: Any) -> None:
    """The ``clik simulate`` subcommand."""
    s = sub.add_parser(
        "simulate", help="replay an output folder of clik solve in MuJoCo (a physics check)"
    )
    s.add_argument(
        "target",
        metavar="OUT",
        help="an output folder of clik solve (or, with --out, its .npz or a scenario file)",
    )
    s.add_argument("--out", help="write simulation.json and simulation.png here (default: OUT)")
    s.add_argument("--force", action="store_true", help="replace an existing simulation.json")
    s.add_argument(
        "--no-feedforward",
        action="store_true",
        help="position servos only (default: the run's joint velocities fed forward)",
    )
    s.add_argument("--kp", type=float, default=KP, help=f"servo stiffness (default {KP:g})")
    s.add_argument("--kv", type=float, default=KV, help=f"servo damping (default {KV:g})")
    s.add_argument(
        "--timestep",
        type=float,
        default=TIMESTEP,
        help=f"largest simulation step [s] (default {TIMESTEP:g})",
    )
    s.set_defaults(func=cmd_simulate)
