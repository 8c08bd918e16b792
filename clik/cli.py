"""The ``clik`` command line: solve, demo, show, robots, sweep, reach, simulate, ros and bench.

Errors are printed without a traceback (``--debug`` shows it) and the exit
code tells the kind: 0 success, 1 a sweep with failed runs (``clik sweep``:
a run raised, or ended ``violated``, ``velocity_limit``, ``off_track`` or
``diverged``; every row is still written), 2 bad input, 3 infeasible (the run ended
``violated``, ``velocity_limit``, ``off_track``, ``deadlock`` or ``diverged``; its
outputs are still written; ``clik simulate``: the replayed robot touches an obstacle),
4 internal; 130 after Ctrl-C, 143 after SIGTERM (the output folder is
then left as it was: :mod:`clik.outputs.out_folder`), 141 when stdout is closed early
(``clik robots | head -1``: quietly, like a process stopped by SIGPIPE).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from clik.commands.bench import add_bench
from clik.commands.launch import add_demo, add_robots, add_show
from clik.commands.reach import add_reach
from clik.commands.ros import add_ros
from clik.commands.simulate import add_simulate
from clik.commands.solve import add_solve
from clik.commands.sweep import add_sweep
from clik.commands.warning_lines import cli_warnings
from clik.errors import EXIT_CODES, ClikError

BROKEN_PIPE = 141
"""Exit code when stdout was closed by its reader (``| head``): 128 + SIGPIPE, as a shell says."""


def parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    p = argparse.ArgumentParser(prog="clik", description=__doc__.splitlines()[0].replace("``", ""))
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = p.add_subparsers(dest="command", required=True)
    add_solve(sub)
    add_demo(sub)
    add_show(sub)
    add_robots(sub)
    add_bench(sub)
    add_sweep(sub)
    add_reach(sub)
    add_simulate(sub)
    add_ros(sub)
    return p


def _silence_stdout() -> None:
    """Point stdout at ``os.devnull``: its reader is gone, and a last flush would fail."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (AttributeError, OSError, ValueError):  # no file descriptor (a test's capture)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``clik`` command (exit codes: see the module's docstring).

    Warnings raised while the command runs are printed as one line each,
    ``clik: warning: <message> [<category>]``, each distinct message once
    (:mod:`clik.commands.warning_lines`); Python's own warning settings come back after.
    """
    args = parser().parse_args(argv)
    with cli_warnings():
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command; errors become a line on stderr and an exit code."""
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
