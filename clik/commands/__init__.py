"""The subcommands of the ``clik`` command line, one module per command.

Each module holds a command's flags (``add_<name>(sub)``, given the
subparsers of :func:`clik.cli.parser`) and its handler (``cmd_<name>(args)``,
returning the exit code); :mod:`clik.cli` builds the parser from them and runs
the handler. A new command is a new module here and one line in
:func:`clik.cli.parser`. Like :mod:`clik.cli`, these are applications: they may
import any room of ``clik``, and no core module imports them.
"""
