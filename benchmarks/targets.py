"""The suite's targets, data in ``targets.toml``: each a figure of ``bench.json`` and a bound.

The file is read when the suite runs (:func:`load_targets`); every target is
then checked against the report (:func:`evaluate_targets`). The file's own
header says what each field means.
"""

from __future__ import annotations

import operator
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from benchmarks.stats import ratio
from clik.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

OPS: dict[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}
"""The comparisons a target may use: ``figure op bound``."""

_TEXT_FIELDS = ("name", "measure", "op", "wanted")


def default_targets_path() -> Path:
    """The shipped ``targets.toml`` (beside this module)."""
    return Path(str(resources.files("benchmarks").joinpath("targets.toml")))


def lookup(report: Mapping[str, Any], dotted: str) -> Any:
    """The value at a dotted key path of the report, e.g. ``"step_us.panda_pose"``.

    Args:
        report: The report (``bench.json``'s content).
        dotted: Keys joined by dots.

    Raises:
        KeyError: A key of the path is missing.
    """
    node: Any = report
    for part in dotted.split("."):
        if not isinstance(node, Mapping) or part not in node:
            raise KeyError(dotted)
        node = node[part]
    return node


@dataclass(frozen=True)
class Target:
    """One target: ``figure op bound``, the figure read from the report.

    Attributes:
        name: Row name in ``bench.md`` and ``name`` in ``bench.json``.
        measure: Dotted key path of the figure.
        op: Comparison, a key of :data:`OPS`.
        bound: The number the figure is compared with.
        wanted: The target in words.
        over: Dotted key path of a divisor (the figure is then a ratio), or None.
    """

    name: str
    measure: str
    op: str
    bound: float
    wanted: str
    over: str | None = None

    def value(self, report: Mapping[str, Any]) -> float | None:
        """The figure in ``report`` (None when missing, e.g. pink's without pink).

        Args:
            report: The report.

        Raises:
            InputError: A key path of this target is not in the report.
        """
        try:
            value = lookup(report, self.measure)
            if self.over is not None:
                return ratio(value, lookup(report, self.over))
        except KeyError as exc:
            raise InputError(
                f"targets: {self.name!r}", "key paths of bench.json", exc.args[0]
            ) from None
        return value

    def evaluate(self, report: Mapping[str, Any]) -> dict[str, Any]:
        """``{"name", "target", "value", "met"}``; ``met`` is None when the figure is missing.

        Args:
            report: The report.
        """
        value = self.value(report)
        met = None if value is None else OPS[self.op](value, self.bound)
        return {"name": self.name, "target": self.wanted, "value": value, "met": met}


def _parse_target(entry: Any, where: str) -> Target:
    """One ``[[target]]`` table, checked."""
    if not isinstance(entry, dict):
        raise InputError(where, "a table")
    unknown = set(entry) - {*_TEXT_FIELDS, "bound", "over"}
    if unknown:
        raise InputError(where, "only name, measure, over, op, bound, wanted", sorted(unknown))
    for key in _TEXT_FIELDS:
        if not isinstance(entry.get(key), str):
            raise InputError(f"{where}.{key}", "a string", entry.get(key))
    if entry["op"] not in OPS:
        raise InputError(f"{where}.op", "one of " + ", ".join(OPS), entry["op"])
    bound = entry.get("bound")
    if not isinstance(bound, int | float) or isinstance(bound, bool):
        raise InputError(f"{where}.bound", "a number", bound)
    over = entry.get("over")
    if over is not None and not isinstance(over, str):
        raise InputError(f"{where}.over", "a key path (string)", over)
    return Target(entry["name"], entry["measure"], entry["op"], float(bound), entry["wanted"], over)


def load_targets(path: Path | None = None) -> list[Target]:
    """Read and check a targets file.

    Args:
        path: The file; default the shipped one (:func:`default_targets_path`).

    Raises:
        InputError: Not valid TOML, or a target with a missing or bad field.
    """
    path = default_targets_path() if path is None else Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(str(path), "a valid TOML file", str(exc)) from None
    entries = data.get("target")
    if not isinstance(entries, list) or not entries:
        raise InputError(f"{path}: target", "one or more [[target]] tables")
    return [_parse_target(entry, f"{path}: target[{i}]") for i, entry in enumerate(entries)]


def evaluate_targets(report: Mapping[str, Any], targets: list[Target]) -> list[dict[str, Any]]:
    """Every target with the measured figure and whether it is met, in file order.

    Args:
        report: The report.
        targets: As read by :func:`load_targets`.
    """
    return [target.evaluate(report) for target in targets]
