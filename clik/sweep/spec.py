"""Sweep files: a base scenario, the keys to vary, and the runs they expand into.

A sweep file is TOML::

    base = "case_study_both.toml"      # relative to the sweep file, or a shipped name
    seed = 1                           # for uniform samples (default 0)

    [vary."obstacles.pin.position"]    # any scenario key path (clik.sweep.keypath)
    grid = { start = [0.65, -0.32, 0.0], stop = [0.75, -0.24, 0.0], num = [5, 5, 1] }

    [vary."solver.gain"]
    values = [500.0, 1000.0]

Each ``[vary."<key path>"]`` table holds exactly one of (a plain list,
``"solver.gain" = [500.0, 1000.0]`` under ``[vary]``, is read as ``values``):

- ``values = [...]``: the values, as the scenario file would hold them;
- ``grid = { start, stop, num }``: evenly spaced values from ``start`` to
  ``stop`` (both included); numbers, or lists with one ``num`` per component
  (the values are then the product of the components' points);
- ``uniform = { low, high, samples }``: ``samples`` values drawn uniformly in
  ``[low, high]`` (per component), from a generator seeded by ``seed`` and the
  key path (adding a table does not change the others' samples).

``values`` and ``grid`` tables combine as a product (every combination);
``uniform`` tables vary jointly (sample ``i`` of each, so they must have the
same ``samples``), and that joint block is one more factor of the product.

Every run gets a stable id: a hash of its parameters (the key paths and
values), so the same run has the same id in any sweep. Its scenario is the
base scenario's dict with the parameters substituted, validated by
:func:`clik.scenarios.scenario.parse_scenario` against the base file (relative paths
still resolve there). Every run is validated when the sweep is loaded.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import sys
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from clik.errors import ScenarioError
from clik.scenarios.scenario import Scenario, parse_scenario
from clik.schema import Table
from clik.sweep.keypath import KeyPathError, from_scenario_key, leaves, split, substitute

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

KINDS = ("values", "grid", "uniform")
"""How a ``[vary.*]`` table gives its values."""

MAX_RUNS = 1_000_000
"""Most runs one sweep file may expand into (a guard against a typo in ``num``)."""

FORMAT = "clik-sweep-1"
"""Version tag hashed into every sweep fingerprint."""


@dataclass(frozen=True)
class Vary:
    """One ``[vary."<key path>"]`` table, expanded.

    Attributes:
        path: The scenario key path.
        kind: ``"values"``, ``"grid"`` or ``"uniform"``.
        values: The values it takes, in order.
    """

    path: str
    kind: str
    values: list[Any]


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep.

    Attributes:
        run_id: Stable id, a hash of ``params`` (:func:`run_id`).
        params: Key path -> value substituted into the base scenario.
        index: Position in the sweep's expansion order.
    """

    run_id: str
    params: dict[str, Any]
    index: int


@dataclass
class Sweep:
    """A validated sweep file and its runs.

    Attributes:
        file: The sweep file.
        name: Its ``name`` key, or the file's stem.
        base_file: The base scenario file (relative paths of runs resolve against it).
        base_data: The base scenario as read from TOML.
        seed: Seed of the uniform samples.
        vary: The vary tables, in file order.
        runs: Every run, in expansion order (first tables vary slowest).
        fingerprint: Hash of the base scenario and the run ids: equal fingerprints,
            same sweep (used to resume into an output folder).
    """

    file: Path
    name: str
    base_file: Path
    base_data: dict[str, Any]
    seed: int
    vary: list[Vary]
    runs: list[RunSpec] = field(repr=False)
    fingerprint: str = ""

    @property
    def parameters(self) -> list[str]:
        """The key paths varied, in file order."""
        return [v.path for v in self.vary]

    def scenario_data(self, run: RunSpec) -> dict[str, Any]:
        """The run's scenario as a TOML dict (base with the parameters substituted)."""
        return substitute(self.base_data, run.params)

    def scenario(self, run: RunSpec) -> Scenario:
        """The run's validated scenario."""
        return parse_scenario(self.scenario_data(run), self.base_file)


def canonical(value: Any) -> str:
    """Compact JSON with sorted keys: the text that ids and fingerprints hash."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, default=str)


def run_id(params: dict[str, Any]) -> str:
    """The stable id of a run: 16 hex digits of the SHA-256 of its canonical parameters."""
    return hashlib.sha256(canonical(params).encode()).hexdigest()[:16]


def load_sweep(path: str | Path) -> Sweep:
    """Read, expand and validate a sweep file.

    Raises:
        ScenarioError: Naming the sweep file (or the base scenario file) and the key path.
    """
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(path, "", "no such sweep file")
    return parse_sweep(_read_toml(path), path)


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(path, "", f"not valid TOML ({exc})") from None


def locate_scenario(text: str, folder: Path) -> Path | None:
    """A scenario file named on the command line or by a sweep's ``base``, or None.

    The one lookup ``clik solve NAME`` and a sweep's ``base`` share: a file
    (relative to ``folder``), else a shipped scenario (``clik/scenarios/NAME.toml``;
    ``NAME`` with or without ``.toml``, no ``/``).

    Args:
        text: The path or name as written.
        folder: The folder a relative path is relative to.
    """
    from clik.scenarios import scenario_path

    candidate = Path(text).expanduser()
    if not candidate.is_absolute():
        candidate = folder / candidate
    if candidate.is_file():
        return candidate
    shipped = scenario_path(text[:-5] if text.endswith(".toml") else text)
    if "/" not in text and shipped.is_file():
        return shipped
    return None


def shipped_scenarios() -> list[str]:
    """The names of the shipped scenarios (``clik/scenarios/*.toml``, without ``.toml``)."""
    from clik.scenarios import scenario_path

    return sorted(p.stem for p in scenario_path("x").parent.glob("*.toml"))


def resolve_base(file: Path, base: str) -> Path:
    """The base scenario file: relative to the sweep file's folder, else a shipped scenario."""
    found = locate_scenario(base, file.parent)
    if found is not None:
        return found
    candidate = file.parent / Path(base).expanduser()
    raise ScenarioError(
        file,
        "base",
        f"no scenario file {str(candidate)!r} and no shipped scenario {base!r}; "
        f"shipped: {', '.join(shipped_scenarios())}",
    )


def parse_sweep(data: dict[str, Any], file: str | Path) -> Sweep:
    """Validate a sweep given as a dict (as read from TOML) and expand it into runs."""
    file = Path(file)
    top = Table(data, file)
    name = top.string("name", file.stem)
    base_file = resolve_base(file, top.string("base"))
    seed = top.number("seed", 0, minimum=0, integer=True)
    vary_data = top.table("vary", required=True)
    top.done()
    if not vary_data.data:
        raise ScenarioError(file, "vary", 'expected at least one [vary."<key path>"] table')
    base_data = _read_toml(base_file)
    parse_scenario(base_data, base_file)  # the base itself must be valid (names its own file)

    vary = [_vary(file, path, value, seed) for path, value in vary_data.data.items()]
    for v in vary:
        _check_path(file, base_file, base_data, v)
    runs = expand(file, vary)
    for run in runs:
        _check_run(file, base_file, base_data, run)
    fingerprint = hashlib.sha256(
        canonical(
            {"format": FORMAT, "base": base_data, "runs": sorted(r.run_id for r in runs)}
        ).encode()
    ).hexdigest()[:16]
    return Sweep(file, name, base_file, base_data, seed, vary, runs, fingerprint)


def expand(file: Path, vary: list[Vary]) -> list[RunSpec]:
    """Runs of the vary tables: ``values``/``grid`` as a product, ``uniform`` jointly."""
    product = [v for v in vary if v.kind != "uniform"]
    joint = [v for v in vary if v.kind == "uniform"]
    sizes = {len(v.values) for v in joint}
    if len(sizes) > 1:
        listing = ", ".join(f'"{v.path}": {len(v.values)}' for v in joint)
        raise ScenarioError(
            file, "vary", f"uniform tables vary jointly: expected equal samples, got {listing}"
        )
    factors: list[list[dict[str, Any]]] = [[{v.path: x} for x in v.values] for v in product]
    if joint:
        factors.append([{v.path: v.values[i] for v in joint} for i in range(len(joint[0].values))])
    total = math.prod(len(f) for f in factors)
    if total > MAX_RUNS:
        raise ScenarioError(file, "vary", f"expected at most {MAX_RUNS} runs, got {total}")
    order = [v.path for v in vary]
    runs = []
    for index, combination in enumerate(itertools.product(*factors)):
        merged = {k: v for part in combination for k, v in part.items()}
        params = {path: merged[path] for path in order}
        runs.append(RunSpec(run_id(params), params, index))
    return runs


def _tidy(value: float) -> float:
    """A float rounded to 12 significant digits (0.7000000000000001 -> 0.7)."""
    return float(f"{value:.12g}")


def _vary(file: Path, path: str, value: Any, seed: int) -> Vary:
    where = f'vary."{path}"'
    if isinstance(value, list):  # `"solver.gain" = [500.0, 1000.0]`: the values themselves
        value = {"values": value}
    if not isinstance(value, dict):
        raise ScenarioError(
            file,
            where,
            f"expected a list of values, or a table with one of {', '.join(KINDS)} "
            "(values = [...] lists them)",
        )
    table = Table(value, file, where)
    given = [k for k in KINDS if k in value]
    if len(given) != 1:
        raise ScenarioError(
            file, where, f"expected exactly one of {', '.join(KINDS)}, got {given or 'none'}"
        )
    kind = given[0]
    if kind == "values":
        values = table.raw("values")
        if not isinstance(values, list) or not values:
            raise table.error("values", "a non-empty list of values", values)
    elif kind == "grid":
        values = _grid(table.table("grid"))
    else:
        values = _uniform(table.table("uniform"), np.random.default_rng([seed, _crc(path)]))
    table.done()
    return Vary(path, kind, values)


def _crc(text: str) -> int:
    return zlib.crc32(text.encode())


def _components(table: Table, name: str) -> tuple[list[float], bool]:
    """A number or a list of numbers; returns the list and whether it was a scalar."""
    value = table.raw(name)
    if isinstance(value, list):
        return table.vector(name), False
    return [table.number(name)], True


def _grid(table: Table) -> list[Any]:
    start, scalar = _components(table, "start")
    stop, scalar_stop = _components(table, "stop")
    if scalar != scalar_stop or len(stop) != len(start):
        raise table.error("stop", f"the same shape as start ({len(start)} numbers)", stop)
    num_raw = table.raw("num")
    if isinstance(num_raw, list):
        num = num_raw
    else:
        num = [num_raw] * len(start)
    ok = len(num) == len(start) and all(
        isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in num
    )
    if not ok:
        raise table.error("num", f"an integer >= 1 or a list of {len(start)} of them", num_raw)
    table.done()
    raw_start, raw_stop = table.data["start"], table.data["stop"]
    integers = all(
        isinstance(v, int) for v in (raw_start if isinstance(raw_start, list) else [raw_start])
    ) and all(isinstance(v, int) for v in (raw_stop if isinstance(raw_stop, list) else [raw_stop]))
    axes = []
    for a, b, n in zip(start, stop, num, strict=True):
        points = [_tidy(x) for x in np.linspace(a, b, n)]
        if integers and all(x.is_integer() for x in points):
            points = [int(x) for x in points]
        axes.append(points)
    if scalar:
        return list(axes[0])
    return [list(p) for p in itertools.product(*axes)]


def _uniform(table: Table, rng: np.random.Generator) -> list[Any]:
    low, scalar = _components(table, "low")
    high, scalar_high = _components(table, "high")
    if scalar != scalar_high or len(high) != len(low):
        raise table.error("high", f"the same shape as low ({len(low)} numbers)", high)
    if any(h < lo for lo, h in zip(low, high, strict=True)):
        raise table.error("high", "values >= low", high)
    samples = table.number("samples", minimum=1, integer=True)
    table.done()
    draws = rng.uniform(np.asarray(low), np.asarray(high), size=(samples, len(low)))
    if scalar:
        return [_tidy(x) for x in draws[:, 0]]
    return [[_tidy(x) for x in row] for row in draws]


def _check_path(file: Path, base_file: Path, base: dict[str, Any], vary: Vary) -> None:
    """A key path must address a base key, or a key the scenario format accepts."""
    where = f'vary."{vary.path}"'
    valid = leaves(base)
    listing = f"valid key paths of {base_file.name}: {', '.join(valid)}"
    try:
        split(vary.path)
        if vary.path in valid:
            return
        data = substitute(base, {vary.path: vary.values[0]})
    except KeyPathError as exc:
        raise ScenarioError(file, where, f"{exc.problem}; {listing}") from None
    try:
        parse_scenario(data, base_file)
    except ScenarioError as exc:
        key = from_scenario_key(data, exc.key)
        if "unknown key" in exc.expected and (key == vary.path or vary.path.startswith(f"{key}.")):
            raise ScenarioError(
                file, where, f"unknown key path; {listing} (or another scenario key)"
            ) from None


def _check_run(file: Path, base_file: Path, base: dict[str, Any], run: RunSpec) -> None:
    """Validate one run's scenario; an error names the vary table responsible."""
    try:
        data = substitute(base, run.params)
        parse_scenario(data, base_file)
    except KeyPathError as exc:
        raise ScenarioError(file, f'vary."{exc.path}"', exc.problem) from None
    except ScenarioError as exc:
        key = from_scenario_key(data, exc.key)
        blamed = [
            p for p in run.params if key == p or key.startswith(f"{p}.") or p.startswith(f"{key}.")
        ]
        where = f'vary."{blamed[0]}"' if blamed else "vary"
        shown = ", ".join(f"{p} = {v!r}" for p, v in run.params.items())
        raise ScenarioError(
            file, where, f"the run with {shown} is not a valid scenario: {key}: {exc.expected}"
        ) from None
