"""A small validator for TOML tables: typed reads that name the key path on error.

Every read goes through a :class:`Table`, which remembers the file and the key
path, so an error says e.g. ``case.toml: trajectory.duration: expected a
positive number [s], got -1``. :meth:`Table.done` rejects keys that were
never read (unknown keys), listing the valid ones.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from clik.bounds import MAX_COORDINATE
from clik.errors import ScenarioError, shown

_MISSING = object()

# Physical ranges of scenario numbers (README, "Ranges"): a number beyond its range is a
# typo or a probe, refused naming its key before anything is computed.
MAX_LENGTH = MAX_COORDINATE
"""Largest position coordinate, size, distance or threshold [m] (1 km)."""
MAX_SPEED = 1000.0
"""Largest obstacle velocity component or cruise speed [m/s]."""
MAX_ANGLE = 8.0 * math.pi
"""Largest angle magnitude [rad] (four turns): circle arcs, rpy angles, thresholds."""
MAX_JOINT_VALUE = 1000.0
"""Largest joint value magnitude [rad or m] (initial.q, robot.lock, overrides)."""
MAX_GAIN_DT = 1e4
"""Largest ``gain * dt`` (any gain [1/s] times ``solver.dt`` [s]): law (10) is stable only
below 2, laws (9) and (8) below ``2 / lambda_max(J J^T)``; beyond this no robot tracks."""
MIN_DURATION = 1e-6
"""Shortest trajectory duration [s] (a hold may last 0 s)."""
MIN_SAMPLES = 2
"""Fewest samples a trajectory must span: ``solver.dt <= duration / (MIN_SAMPLES)``."""


def _finite(value: int | float) -> bool:
    """``math.isfinite`` that says no, not OverflowError, to a huge TOML integer."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


class Table:
    """A TOML table being validated.

    Args:
        data: The table's dict.
        file: The file it came from (for messages).
        path: Its key path (``""`` for the top level).
    """

    def __init__(self, data: dict[str, Any], file: str | Path, path: str = "") -> None:
        self.data = data
        self.file = file
        self.path = path
        self._read: set[str] = set()

    def key(self, name: str) -> str:
        """Full key path of ``name`` in this table."""
        return f"{self.path}.{name}" if self.path else name

    def error(self, name: str, expected: str, got: Any = _MISSING) -> ScenarioError:
        """A :class:`ScenarioError` for key ``name``."""
        message = f"expected {expected}"
        if got is not _MISSING:
            message += f", got {shown(got)}"
        elif name not in self.data:  # a key needed here and absent: maybe misspelt
            return self._typo(name) or ScenarioError(self.file, self.key(name), message)
        return ScenarioError(self.file, self.key(name), message)

    def _typo(self, name: str) -> ScenarioError | None:
        """The error naming an unread key of the file that looks like the absent ``name``."""
        typo = _closest(name, [k for k in self.data if k not in self._read])
        if typo is None:
            return None
        return ScenarioError(
            self.file, self.key(typo), f"unknown key; did you mean `{name}`? (`{name}` is needed)"
        )

    def has(self, name: str) -> bool:
        """Whether the key is present."""
        return name in self.data

    def raw(self, name: str, default: Any = _MISSING) -> Any:
        """The value of ``name``; a missing required key raises."""
        self._read.add(name)
        if name not in self.data:
            if default is _MISSING:
                missing = ScenarioError(self.file, self.key(name), "required key is missing")
                raise self._typo(name) or missing
            return default
        return self.data[name]

    def table(self, name: str, required: bool = False) -> Table:
        """The sub-table ``name`` (an empty one when absent and not required)."""
        value = self.raw(name, _MISSING if required else {})
        if not isinstance(value, dict):
            raise self.error(name, "a table", value)
        return Table(value, self.file, self.key(name))

    def tables(self, name: str) -> list[Table]:
        """An array of tables (``[[name]]``); empty when absent."""
        value = self.raw(name, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(name, "an array of tables ([[...]])", value)
        return [Table(v, self.file, f"{self.key(name)}[{i}]") for i, v in enumerate(value)]

    def string(
        self, name: str, default: Any = _MISSING, choices: Sequence[str] | None = None
    ) -> Any:
        """A string, optionally one of ``choices``."""
        value = self.raw(name, default)
        if value is default and default is not _MISSING:
            return value
        if not isinstance(value, str):
            raise self.error(name, "a string", value)
        if choices is not None and value not in choices:
            raise self.error(name, "one of " + ", ".join(repr(c) for c in choices), value)
        return value

    def boolean(self, name: str, default: Any = _MISSING) -> Any:
        """A boolean."""
        value = self.raw(name, default)
        if not isinstance(value, bool):
            raise self.error(name, "true or false", value)
        return value

    def number(
        self,
        name: str,
        default: Any = _MISSING,
        minimum: float | None = None,
        strict: bool = False,
        unit: str = "",
        integer: bool = False,
        bound: float | None = None,
    ) -> Any:
        """A finite number, ``>= minimum`` (``> minimum`` when ``strict``), ``|x| <= bound``."""
        value = self.raw(name, default)
        if value is default and default is not _MISSING:
            return value
        kind = "an integer" if integer else "a number"
        if minimum is not None:
            kind = f"{kind} {'>' if strict else '>='} {minimum:g}"
        if unit:
            kind += f" {unit}"
        ok_type = isinstance(value, int) if integer else isinstance(value, int | float)
        if isinstance(value, bool) or not ok_type or not _finite(value):
            raise self.error(name, kind, value)
        if minimum is not None and (value <= minimum if strict else value < minimum):
            raise self.error(name, kind, value)
        if bound is not None and abs(value) > bound:
            raise self.error(name, f"{kind} of magnitude at most {bound:g}", value)
        return value

    def vector(
        self,
        name: str,
        size: int | None = None,
        default: Any = _MISSING,
        unit: str = "",
        bound: float | None = None,
    ) -> Any:
        """A list of finite numbers (of length ``size`` when given), each ``|x| <= bound``."""
        value = self.raw(name, default)
        if value is default and default is not _MISSING:
            return value
        expected = f"a list of {size if size else 'N'} numbers{(' ' + unit) if unit else ''}"
        if not isinstance(value, list) or (size is not None and len(value) != size):
            raise self.error(name, expected, value)
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and _finite(v) for v in value
        ):
            raise self.error(name, expected + " (finite)", value)
        if bound is not None and any(abs(v) > bound for v in value):
            raise self.error(name, f"{expected} of magnitude at most {bound:g}", value)
        return [float(v) for v in value]

    def matrix(
        self,
        name: str,
        columns: int,
        default: Any = _MISSING,
        unit: str = "",
        bound: float | None = None,
    ) -> Any:
        """A list of lists of ``columns`` finite numbers."""
        value = self.raw(name, default)
        if value is default and default is not _MISSING:
            return value
        expected = f"a list of [{', '.join(['x', 'y', 'z'][:columns])}] points {unit}".rstrip()
        if not isinstance(value, list) or not value:
            raise self.error(name, expected, value)
        out = []
        for i, row in enumerate(value):
            sub = Table({"row": row}, self.file, f"{self.key(name)}[{i}]")
            out.append(sub.vector("row", columns, unit=unit, bound=bound))
        return out

    def mapping(self, name: str, check: Callable[[Table, str], Any]) -> dict[str, Any]:
        """A table of arbitrary keys, each value read by ``check(table, key)``."""
        sub = self.table(name)
        return {k: check(sub, k) for k in list(sub.data)}

    def done(self) -> None:
        """Raise on any key that was not read (an unknown key)."""
        unknown = sorted(set(self.data) - self._read)
        if unknown:
            valid = ", ".join(sorted(self._read))
            guess = _closest(unknown[0], sorted(self._read))
            hint = f"did you mean `{guess}`? " if guess is not None else ""
            raise ScenarioError(
                self.file, self.key(unknown[0]), f"unknown key; {hint}valid keys here: {valid}"
            )


TYPO_CUTOFF = 0.8
"""Similarity (:class:`difflib.SequenceMatcher` ratio) from which a key is taken for a typo
of another (``duraton``/``duration`` 0.93, ``centre``/``center`` 0.83)."""


def _closest(name: str, keys: Sequence[str]) -> str | None:
    """The key of ``keys`` closest to ``name`` (one a typo of the other), or None.

    Args:
        name: A key (the schema's required key, or the file's unknown key).
        keys: The keys to compare it with (the file's unread keys, or the schema's).
    """
    found = difflib.get_close_matches(name, list(keys), n=1, cutoff=TYPO_CUTOFF)
    return found[0] if found else None
