"""``clik bench``: the benchmark suite of a clik checkout (``bench.json``, ``bench.md``).

The suite is not part of the package: it lives in the repository's ``benchmarks/``
folder, beside ``clik/``, with its pink, mink and MuJoCo harnesses, so that clik never
imports them. This command finds that folder in a checkout (:func:`find_checkout`): the
one the running clik was imported from (an editable install, ``pip install -e .``),
else the working folder. There it loads ``benchmarks.suite`` by name, at run time, and
hands over to its ``run_bench``. A clik installed without a checkout has no suite; the
command then says how to get one (a :class:`~clik.errors.ClikError`, exit code 2).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from clik.errors import ClikError

SUITE = "benchmarks"
"""The suite's package: the ``benchmarks/`` folder at a checkout's root."""


def is_checkout(folder: Path) -> bool:
    """Whether ``folder`` is a clik checkout with its suite: ``clik/`` beside ``benchmarks/``.

    Args:
        folder: A candidate root.
    """
    return (folder / "clik" / "__init__.py").is_file() and (folder / SUITE / "suite.py").is_file()


def candidates() -> list[Path]:
    """Where a checkout is looked for, in order.

    First the root of the running clik's source tree (the folder above its package: a
    checkout when clik is an editable install or run from one), then the working folder.
    """
    import clik

    package_root = Path(clik.__file__).resolve().parents[1]
    return list(dict.fromkeys([package_root, Path.cwd().resolve()]))


def find_checkout() -> Path:
    """The first of :func:`candidates` that :func:`is_checkout`.

    Raises:
        ClikError: None is (clik installed without a checkout); the message says where it
            looked and how to get the suite.
    """
    looked = candidates()
    for folder in looked:
        if is_checkout(folder):
            return folder
    raise ClikError(
        "clik bench runs the benchmark suite of a clik checkout (its benchmarks/ folder, "
        "beside clik/), which an installed clik does not include; none found in "
        + " nor in ".join(str(folder) for folder in looked)
        + ". Get clik's source (its repository), install it from there with "
        "`pip install -e '.[bench]'` (or `make bench`), and run `clik bench` "
        "(or `python -m benchmarks`) there"
    )


def load_suite(checkout: Path) -> ModuleType:
    """``benchmarks.suite`` of ``checkout``, its root put last on the import path.

    Args:
        checkout: A folder that :func:`is_checkout`.

    Raises:
        ClikError: Another package named ``benchmarks`` comes first on the import path.
    """
    if str(checkout) not in sys.path:
        sys.path.append(str(checkout))
    suite = importlib.import_module(f"{SUITE}.suite")
    found = Path(suite.__file__ or "").resolve().parent
    if found != checkout / SUITE:
        raise ClikError(
            f"clik bench: the package {SUITE!r} imported from {found} is not the checkout's "
            f"suite ({checkout / SUITE}); run it from the checkout's root instead: "
            f"python -m {SUITE}"
        )
    return suite


def cmd_bench(args: argparse.Namespace) -> int:
    """``clik bench``: the checkout's benchmark suite (``bench.json``, ``bench.md``)."""
    suite = load_suite(find_checkout())
    suite.run_bench(Path(args.out), quick=args.quick, log=None if args.quiet else print)
    return 0


def add_bench(sub: Any) -> None:
    """The ``clik bench`` subcommand."""
    b = sub.add_parser(
        "bench",
        help="run the benchmark suite of a clik checkout (writes bench.json, bench.md)",
        description="Run the benchmark suite (the benchmarks/ folder of a clik checkout: "
        "the one this clik is installed from, else the working folder) and write "
        "bench.json and bench.md.",
    )
    b.add_argument("--out", default="out/bench", help="output folder")
    b.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    b.add_argument("--quiet", action="store_true")
    b.set_defaults(func=cmd_bench)
