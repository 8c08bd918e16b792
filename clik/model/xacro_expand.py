"""Xacro robot descriptions: expanded to URDF text, reading only the robot's own folders.

:func:`expand_xacro` runs the ``xacro`` package (PyPI) on a ``.xacro`` file and
returns the URDF text, which :meth:`clik.Robot.load` then checks like any URDF
(:func:`clik.model.urdf_check.check_urdf`); an SRDF with xacro markup is expanded
by the same function, with the same arguments and packages
(:mod:`clik.model.srdf_xacro`). Without ROS, xacro cannot resolve
``$(find pkg)``; here the package ``pkg`` is found as for ``package://pkg/...``
meshes, by the name in its ``package.xml`` under the ``package_dirs`` (or a folder
``pkg`` directly in one of them; see :mod:`clik.model.packages`).

Xacro reads files (``<xacro:include>``, ``xacro.load_yaml``) and keeps its state in
module globals. For the length of one call, under a lock, clik replaces:

- ``substitution_args._eval_find`` (and ``find`` in ``$(eval ...)``): the
  package lookup above;
- ``xacro.parse`` and xacro's ``open``: every file xacro reads must resolve
  (symlinks followed) inside a *root*: the xacro file's folder, the package
  that holds it (its nearest folder with a ``package.xml``, up to the package
  folder holding the file; else the folder directly in that package folder), or
  a package found by ``$(find)``; XML files are read strictly first
  (:func:`clik.model.urdf_check.parse_xml`: no entities, no external DTD, no
  XInclude). Xacro never fetches anything over the network.

Everything is put back when the call returns or raises, and xacro's messages
on stderr become :class:`XacroWarning` warnings.

Errors: a ``$(arg name)`` that is neither given nor declared with a default,
or a given argument the file never declares nor uses (an SRDF expanded with
its URDF's arguments may leave some unused), is an
:class:`~clik.errors.InputError` on ``xacro_args``; an unknown package (or two of
one name under a package folder) an :class:`~clik.errors.InputError` on
``package_dirs``; a file outside the roots
or any xacro error (syntax, undefined property, ...) a
:class:`~clik.errors.RobotLoadError` naming the file.
"""

from __future__ import annotations

import contextlib
import difflib
import io
import re
import threading
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clik.errors import (
    SHOWN_CHARACTERS,
    ClikError,
    ClikWarning,
    InputError,
    RobotLoadError,
    user_stacklevel,
)
from clik.model.packages import MANIFEST, PackageDirs, package_dirs_of
from clik.model.urdf_check import parse_xml

XACRO_SUFFIX = ".xacro"
"""Files whose name ends with this (``arm.urdf.xacro``) are expanded by xacro."""

_LOCK = threading.Lock()
"""Xacro keeps its state in module globals: one expansion at a time per process."""


class XacroWarning(ClikWarning):
    """Xacro printed a message (e.g. a redefined property) while expanding a file."""


def is_xacro(path: str | Path) -> bool:
    """Whether ``path`` names a xacro file (its name ends with ``.xacro``)."""
    return Path(path).name.endswith(XACRO_SUFFIX)


def check_xacro_args(xacro_args: object) -> dict[str, str]:
    """``xacro_args`` as a dict of strings (argument name -> value).

    Raises:
        InputError: It is not a mapping of strings to strings.
    """
    if xacro_args is None:
        return {}
    if not isinstance(xacro_args, Mapping) or not all(
        isinstance(k, str) and isinstance(v, str) for k, v in xacro_args.items()
    ):
        raise InputError(
            "xacro_args", "a table of strings, argument name -> value (quote numbers)", xacro_args
        )
    return dict(xacro_args)


def expand_xacro(
    path: str | Path,
    xacro_args: Mapping[str, str] | None = None,
    package_dirs: Sequence[str | Path] = (),
    *,
    extra_args: bool = False,
) -> str:
    """Expand a xacro file into URDF text (or SRDF text: :mod:`clik.model.srdf_xacro`).

    Args:
        path: The ``.xacro`` file.
        xacro_args: Values of its ``<xacro:arg>`` / ``$(arg ...)`` arguments.
        package_dirs: Folders holding the packages named by ``$(find pkg)``
            (a :class:`~clik.model.packages.PackageDirs` keeps its searches).
        extra_args: Whether ``xacro_args`` may hold arguments the file neither
            declares nor uses (an SRDF expanded with its URDF's arguments, which
            the URDF's expansion checked).

    Returns:
        The expanded XML (a URDF or an SRDF, not yet checked).

    Raises:
        InputError: A bad ``xacro_args`` (not strings; an argument missing, or
            unknown unless ``extra_args``); a ``$(find pkg)`` with no package
            ``pkg`` in ``package_dirs``, or two of them under one folder.
        RobotLoadError: The file (or a file it reads) is missing, outside its
            roots, not strict XML, or xacro cannot expand it.
    """
    args = check_xacro_args(xacro_args)
    file = Path(path)
    if not file.is_file():
        raise RobotLoadError(file, "is a folder, not a file" if file.is_dir() else "file not found")
    scope = _Scope(file.resolve(), package_dirs_of(package_dirs))
    given = _TrackedArgs(args, extra_args)
    messages = io.StringIO()
    with _LOCK, _patched_xacro(scope) as xacro, contextlib.redirect_stderr(messages):
        try:
            document = xacro.process_file(str(scope.file), mappings=given, verbosity=0)
            text: str = document.toprettyxml(indent="  ")
        except Exception as error:  # xacro raises many kinds: all become clik errors
            files, macros = list(xacro.filestack or []), _macro_stack(xacro)
            raise _clik_error(error, scope, given, files, macros) from None
    if messages.getvalue().strip():
        warnings.warn(
            XacroWarning(f"xacro, expanding {file}: {' '.join(messages.getvalue().split())}"),
            stacklevel=user_stacklevel(),
        )
    unknown = [] if given.extra else sorted(set(args) - given.asked)
    if unknown:
        known = ", ".join(repr(a) for a in sorted(given.asked)) or "none"
        guess = _did_you_mean(unknown, given.asked)
        raise InputError(
            "xacro_args",
            f"arguments that {file} declares or uses ({known}){guess}",
            got={k: args[k] for k in unknown},
        )
    return text


class _TrackedArgs(dict[str, str]):
    """Xacro's argument table, remembering which names xacro asked for.

    Xacro asks ``name in args`` for each ``<xacro:arg>`` and reads ``args[name]``
    for each ``$(arg name)`` or ``xacro.arg(name)``: a given name never asked for
    is unknown to the file, and a name read but absent (``missing``) is an
    argument the file needs when the expansion then fails on it. With ``extra``,
    names never asked for are not errors (:func:`expand_xacro`'s ``extra_args``).
    """

    def __init__(self, given: Mapping[str, str], extra: bool = False) -> None:
        super().__init__(given)
        self.extra = extra
        self.asked: set[str] = set()
        self.missing: set[str] = set()

    def __contains__(self, name: object) -> bool:
        if isinstance(name, str):
            self.asked.add(name)
        return super().__contains__(name)

    def __getitem__(self, name: str) -> str:
        self.asked.add(name)
        if not super().__contains__(name):
            self.missing.add(name)
        return super().__getitem__(name)


@dataclass
class _Scope:
    """What one expansion may read: its file, the package folders, the roots found.

    Attributes:
        file: The xacro file (symlinks resolved).
        package_dirs: Folders holding packages, with their searches.
        roots: Folders (resolved) whose files xacro may read.
    """

    file: Path
    package_dirs: PackageDirs
    roots: list[Path] = field(default_factory=list)
    read: list[Path] = field(default_factory=list)
    """The files xacro opened so far (the file itself first)."""

    def __post_init__(self) -> None:
        self.read.append(self.file)
        self._add_root(self.file.parent)
        dirs = self.package_dirs
        bases = [*dirs.folders, *dirs.ros_folders, *(p / "share" for p in dirs.ament_prefixes)]
        for folder in bases:  # the package holding the file, if any
            package = _package_holding(self.file, folder.resolve())
            if package is not None:
                self._add_root(package)

    def _add_root(self, folder: Path) -> None:
        """Let xacro read the files under ``folder`` (resolved), unless already allowed."""
        if not any(folder.is_relative_to(root) for root in self.roots):
            self.roots[:] = [r for r in self.roots if not r.is_relative_to(folder)] + [folder]

    def find(self, package: str) -> str:
        """The folder of ``package`` (``$(find package)``), now a root too.

        Raises:
            InputError: No package ``package`` in ``package_dirs`` (or a name with a path
                in it), or two under one folder.
        """
        found = self.package_dirs.find(package)
        if found is not None:
            self._add_root(found.folder)
            return str(found.folder)
        raise InputError(
            "package_dirs",
            f"a folder holding the package {package!r} (a package.xml naming it, or a "
            f"folder of that name) named by $(find {package}) in {self.file} (package "
            f"folders searched: {self.package_dirs.searched()})",
        )

    def readable(self, name: str) -> Path:
        """The file ``name`` (symlinks resolved) when it lies inside a root.

        Raises:
            RobotLoadError: It lies outside every root.
        """
        resolved = Path(name).resolve()
        if not any(resolved.is_relative_to(root) for root in self.roots):
            roots = ", ".join(str(r) for r in self.roots)
            raise RobotLoadError(
                self.file,
                f"xacro would read {name} (resolved: {resolved}), which leaves the "
                f"folders a xacro file may read from ({roots}): its own folder, its "
                "package and the packages found by $(find)",
            )
        if resolved not in self.read:
            self.read.append(resolved)
        return resolved


def _package_holding(file: Path, base: Path) -> Path | None:
    """The package folder holding ``file`` under the package folder ``base`` (both resolved).

    Its nearest folder with a ``package.xml``, ``base`` included; else, as before
    workspaces were searched, the folder directly in ``base`` that holds it; None
    outside ``base``.
    """
    if not file.is_relative_to(base):
        return None
    for folder in file.parents:
        if (folder / MANIFEST).is_file():
            return folder
        if folder == base:
            break
    legacy = base / file.relative_to(base).parts[0]
    return legacy if legacy.is_dir() else None


@contextlib.contextmanager
def _patched_xacro(scope: _Scope) -> Iterator[Any]:
    """Xacro with ``$(find)``, file reading and its state scoped to ``scope``.

    Yields the ``xacro`` module; everything changed is put back on exit.
    """
    import builtins

    import xacro
    from xacro import substitution_args

    original_parse = xacro.parse

    def parse(inp: Any, filename: str | None = None) -> Any:
        if inp is None and filename is not None:
            file = scope.readable(filename)
            try:
                parse_xml(file)  # strict XML first (no entities, ...)
            except RobotLoadError as error:
                if file == scope.file:
                    raise
                raise RobotLoadError(
                    filename, f"{error.problem} (included by {scope.file})", error.line
                ) from None
        return original_parse(inp, filename)

    def guarded_open(name: Any, *args: Any, **kwargs: Any) -> Any:
        return builtins.open(scope.readable(str(name)), *args, **kwargs)

    saved = {
        "parse": xacro.parse,
        "filestack": xacro.filestack,
        "macrostack": xacro.macrostack,
        "all_includes": xacro.all_includes,
        "verbosity": xacro.verbosity,
    }
    saved_find = (substitution_args._eval_find, substitution_args._eval_dict["find"])
    xacro.parse = parse
    xacro.open = guarded_open  # shadows the builtin inside xacro only
    xacro.all_includes = []
    substitution_args._eval_find = substitution_args._eval_dict["find"] = scope.find
    try:
        yield xacro
    finally:
        for name, value in saved.items():
            setattr(xacro, name, value)
        del xacro.open
        substitution_args._eval_find, substitution_args._eval_dict["find"] = saved_find
        xacro.substitution_args_context["arg"] = {}


def _causes(error: BaseException) -> Iterator[BaseException]:
    """``error`` and what it wraps (xacro's ``exc``, Python's cause and context)."""
    seen: set[int] = set()
    todo: list[BaseException | None] = [error]
    while todo:
        current = todo.pop(0)
        if current is None or id(current) in seen:
            continue
        seen.add(id(current))
        yield current
        wrapped = getattr(current, "exc", None)
        todo += [wrapped if isinstance(wrapped, BaseException) else None]
        todo += [current.__cause__, current.__context__]


def _macro_stack(xacro: Any) -> list[tuple[str, str]]:
    """The macros xacro was expanding, innermost first: (name, file defining it).

    What ``xacro`` itself prints as "when instantiating macro: ... instantiated from:".
    """
    stack: list[tuple[str, str]] = []
    for macro in reversed(getattr(xacro, "macrostack", None) or []):
        try:
            name = str(macro.body.getAttribute("name"))
            defined = str((macro.history[-1] if macro.history else [None])[-1] or "?")
        except (AttributeError, IndexError, TypeError):  # another xacro version: said less
            continue
        stack.append((name, defined))
    return stack


def _clik_error(
    error: Exception,
    scope: _Scope,
    given: _TrackedArgs,
    files: list[str],
    macros: Sequence[tuple[str, str]] = (),
) -> ClikError:
    """The clik error for an exception raised while xacro expanded ``scope.file``.

    ``files`` is xacro's stack of files being read, ``macros`` its stack of macros
    being expanded (innermost first, :func:`_macro_stack`): both are named in a
    :class:`~clik.errors.RobotLoadError`, as the ``xacro`` command names them.
    """
    from xacro.substitution_args import ArgException

    declared = _declared_args(scope.read)
    unknown = [] if given.extra else sorted(set(given) - given.asked - set(declared))
    if unknown:  # a misspelt argument: said, not the failure it causes further on
        names = given.asked | set(declared)
        known = ", ".join(repr(a) for a in sorted(names)) or "none"
        return InputError(
            "xacro_args",
            f"arguments that {scope.file} declares or uses ({known})"
            f"{_did_you_mean(unknown, names)}; the expansion then "
            f"failed: {' '.join(str(error).split())[:SHOWN_CHARACTERS]}",
            got={k: given[k] for k in unknown},
        )
    for cause in _causes(error):
        if isinstance(cause, ClikError):
            return cause
        is_key = isinstance(cause, KeyError) and cause.args and cause.args[0] in given.missing
        if isinstance(cause, ArgException) or is_key:
            name = str(cause.args[0])
            return InputError("xacro_args", _missing_arg(name, scope.file, declared), dict(given))
    message = " ".join(str(error).split()) or type(error).__name__
    where = [f for f in files if f and Path(f).resolve() != scope.file]
    inside = f" (in {where[-1]}, included from {scope.file})" if where else ""
    if macros:
        chain = ", instantiated from ".join(
            f"{name!r} (defined in {file})" for name, file in macros
        )
        message += f"; when instantiating the macro {chain}"
    return RobotLoadError(scope.file, f"xacro cannot expand it{inside}: {message}")


def _did_you_mean(unknown: list[str], known: set[str]) -> str:
    """``"; did you mean 'ur_type' for 'ur_typ'?"``: the closest known name of each unknown."""
    guesses = [
        f"{close[0]!r} for {name!r}"
        for name in unknown
        if (close := difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6))
    ]
    return f"; did you mean {', '.join(guesses)}?" if guesses else ""


_ARG = re.compile(r"""<xacro:arg\s[^>]*?name\s*=\s*["']([^"']+)["']([^>]*)>""")
"""An ``<xacro:arg name=...>`` declaration (its attributes after the name: a default?)."""


def _declared_args(files: list[Path]) -> dict[str, tuple[Path, int, bool]]:
    """Each ``<xacro:arg>`` the files declare: its file, line and whether it has a default."""
    out: dict[str, tuple[Path, int, bool]] = {}
    for file in files:
        try:
            text = file.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        for match in _ARG.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            out.setdefault(match.group(1), (file, line, "default" in match.group(0)))
    return out


def _missing_arg(name: str, file: Path, declared: dict[str, tuple[Path, int, bool]]) -> str:
    """What a missing xacro argument needs: a value, or its declaration moved up."""
    where = declared.get(name)
    if where is not None and where[2]:
        return (
            f"a value for the xacro argument {name!r}, or its declaration moved up: {file} "
            f"uses it before {where[0]}, line {where[1]} declares it with a default (xacro "
            "reads a file in order)"
        )
    return (
        f"a value for the xacro argument {name!r}: {file} uses it and declares no default "
        f'(<xacro:arg name="{name}" default="..."/>)'
    )
