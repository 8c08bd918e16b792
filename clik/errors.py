"""The one exception hierarchy of clik, and the root of its warnings.

Every error clik raises on bad input is a :class:`ClikError` subclass. Each
subclass keeps the data it was built from as attributes and builds its message
from them, so a caller can either show the message or react to the fields.

The command line maps each family to an exit code (see :data:`EXIT_CODES`).

Every warning clik emits is a :class:`ClikWarning` subclass, defined beside the code
that emits it (``ReachWarning`` in :mod:`clik.loop.tracker`, ...) and exported by
``clik``; ``warnings.filterwarnings("error", category=clik.ClikWarning)`` escalates
them all, ``"ignore"`` silences them all.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path

SHOWN_CHARACTERS = 200
"""Characters of a long name or value shown in a message (the rest is counted)."""


def shown(value: object, limit: int = SHOWN_CHARACTERS) -> str:
    """A value as messages show it: its ``repr``, cut to ``limit`` characters when longer.

    A cut string shows its first ``limit`` characters, quoted, and its length; any other
    value the first ``limit`` characters of its ``repr`` and that repr's length.
    """
    if isinstance(value, str):
        if len(value) <= limit:
            return repr(value)
        return f"{value[:limit]!r}... ({len(value)} characters)"
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def shown_path(path: str, limit: int = SHOWN_CHARACTERS) -> str:
    """A file path or URI as messages show it: whole, quoted, unless longer than ``limit``.

    A longer one is cut in its middle: its first characters and its last component (the
    file name, itself cut in its middle past ``limit // 2``) are kept, and its length given,
    so the file can still be found.
    """
    if len(path) <= limit:
        return repr(path)
    name = path.rpartition("/")[2]
    half = limit // 2
    if len(name) > half:
        name = f"{name[: half // 2]}...{name[-(half - half // 2) :]}"
    head = path[: max(limit - len(name), 0)]
    return f"{head + '...' + name!r} ({len(path)} characters)"


def user_stacklevel() -> int:
    """The ``stacklevel`` of ``warnings.warn`` that points at the first caller outside clik.

    Call it in the function that calls ``warnings.warn`` (``stacklevel=user_stacklevel()``):
    the warning then names the user's line (the ``Robot.load(...)`` call), however deep in
    clik it was raised.
    """
    level, frame = 2, sys._getframe(2)  # 1: the function warning; 2: its caller
    while frame.f_back is not None and _in_clik(frame.f_globals.get("__name__", "")):
        level, frame = level + 1, frame.f_back
    return level


def _in_clik(module: str) -> bool:
    return module == "clik" or module.startswith("clik.")


def _listing(names: Iterable[str], limit: int = 40) -> str:
    """Comma-separated list of names, shortened past ``limit`` entries."""
    names = list(names)
    text = ", ".join(shown(n) for n in names[:limit])
    if len(names) > limit:
        text += f", ... ({len(names) - limit} more)"
    return text


class ClikError(Exception):
    """Root of every error clik raises on purpose."""

    exit_code: int = 2


class ClikWarning(UserWarning):
    """Root of every warning clik emits: a legal input that will likely not do what was meant.

    A :class:`UserWarning`, so Python shows it once per place by default. Filter on it to
    treat every clik warning alike (``warnings.filterwarnings("error",
    category=clik.ClikWarning)``), or on a subclass for one kind.
    """


class InputError(ClikError, ValueError):
    """A value given by the user is not what was expected.

    Attributes:
        field: Name of the bad field (a parameter or a key path).
        expected: What was expected, in words.
        got: What was given (shown in the message when not None).
    """

    def __init__(self, field: str, expected: str, got: object = None) -> None:
        self.field = field
        self.expected = expected
        self.got = got
        message = f"{field}: expected {expected}"
        if got is not None:
            message += f", got {shown(got)}"
        super().__init__(message)


class RobotLoadError(ClikError):
    """A robot could not be loaded.

    Attributes:
        source: The file path or robot name that was asked for.
        problem: What is wrong, in words.
        line: Line number in the file, when known.
    """

    def __init__(self, source: str | Path, problem: str, line: int | None = None) -> None:
        self.source = str(source)
        self.problem = problem
        self.line = line
        where = f"{self.source}, line {line}" if line is not None else self.source
        super().__init__(f"cannot load robot {where}: {problem}")


class UnknownRobotError(RobotLoadError):
    """A robot name that is neither a file, one of ours, nor in example-robot-data."""

    def __init__(self, name: str, available: Iterable[str]) -> None:
        self.available = sorted(available)
        super().__init__(
            name,
            "no such file and no robot of that name; available robot names: "
            + _listing(self.available, limit=200),
        )


class FrameNotFound(ClikError, KeyError):
    """A frame name that the model does not have.

    Attributes:
        name: The name asked for.
        frames: The model's frame names.
    """

    def __init__(self, name: str, frames: Iterable[str]) -> None:
        self.name = name
        self.frames = list(frames)
        super().__init__(
            f"frame {shown(name)} not found; available frames: {_listing(self.frames)}"
        )

    def __str__(self) -> str:  # KeyError quotes its message otherwise
        return str(self.args[0])


class JointNotFound(ClikError, KeyError):
    """A joint name that the model does not have.

    Attributes:
        name: The name asked for.
        joints: The model's joint names.
    """

    def __init__(self, name: str, joints: Iterable[str]) -> None:
        self.name = name
        self.joints = list(joints)
        super().__init__(
            f"joint {shown(name)} not found; available joints: {_listing(self.joints)}"
        )

    def __str__(self) -> str:
        return str(self.args[0])


class ScenarioError(ClikError):
    """A scenario (or sweep) file is malformed.

    Attributes:
        file: The scenario file.
        key: The key path, e.g. ``trajectory.duration`` (empty for the file itself).
        expected: What was expected there, in words.
    """

    def __init__(self, file: str | Path, key: str, expected: str) -> None:
        self.file = str(file)
        self.key = key
        self.expected = expected
        where = f"{self.file}: {key}" if key else self.file
        super().__init__(f"{where}: {expected}")


class OutputExistsError(ClikError, FileExistsError):
    """An output folder exists already and ``force`` was not given."""

    def __init__(self, path: str | Path) -> None:
        self.path = str(path)
        super().__init__(f"output folder {self.path} exists already; pass --force to overwrite it")


class OutputError(ClikError, OSError):
    """An output folder or file that cannot be written: the OS reason, with the path.

    Attributes:
        path: The output folder (or file) concerned.
        reason: Why, in words (e.g. ``No space left on device (ENOSPC)``).
    """

    def __init__(self, path: str | Path, reason: str) -> None:
        self.path = str(path)
        self.reason = reason
        Exception.__init__(self, f"cannot write output {self.path}: {reason}")

    def __str__(self) -> str:  # OSError formats its arguments otherwise
        return str(self.args[0])


class OutputLockedError(OutputError):
    """Another clik run is writing into the same output folder (it holds its lock).

    Attributes:
        lock: The lock file the other run holds.
    """

    def __init__(self, path: str | Path, lock: str | Path) -> None:
        self.lock = str(lock)
        super().__init__(
            path,
            f"another clik run is writing there (it holds {self.lock}); wait for it to "
            "finish or choose another --out",
        )


class GeometryError(ClikError, ValueError):
    """An obstacle or link geometry is degenerate or cannot be read."""


class InfeasibleError(ClikError):
    """A request that is well-formed but cannot be met (e.g. an impossible start).

    Attributes:
        field: The input that cannot be met (a parameter or a key path).
        problem: Why, in words.
    """

    exit_code = 3

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


def native_message(error: BaseException) -> str:
    """The useful part of an error raised by Pinocchio's or coal's C++ code.

    Their messages start with the C++ file, function and line ("From file: ...
    at line: 91 message: ..."); keep what follows ``message:``, on one line.
    """
    text = str(error)
    if "message:" in text:
        text = text.split("message:", 1)[1]
    return " ".join(text.split())


class EngineError(ClikError):
    """The compiled engine cannot be used: not built, or built against other versions.

    Attributes:
        problem: What is wrong, with the versions involved and the fix.
    """

    exit_code = 4

    def __init__(self, problem: str) -> None:
        self.problem = problem
        super().__init__(f"compiled engine: {problem}")


class ExportError(ClikError):
    """A trajectory that cannot be exported (a joint of a kind with no single angle, ...).

    Attributes:
        problem: What is wrong, in words.
    """

    def __init__(self, problem: str) -> None:
        self.problem = problem
        super().__init__(f"cannot export the trajectory: {problem}")


EXIT_CODES = {"bad_input": 2, "infeasible": 3, "internal": 4}
"""Exit codes of the command line: bad input, infeasible problem, internal error."""
