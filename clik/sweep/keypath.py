"""Key paths: one scenario key named as a dotted string, read and written in the TOML dict.

A key path joins table keys with dots: ``solver.gain``, ``initial.q``,
``trajectory.goal``, ``constraints.joint_limits.override.joint3.upper``.
Obstacles (an array of tables in the file) are addressed by their ``name``:
``obstacles.pin.position`` is the ``position`` of the obstacle named ``pin``.

Values are those of the scenario file, in its units (``initial.q`` in the
``[initial]`` table's ``unit``, lengths in metres). Paths work on the raw dict
read from TOML, before validation; :func:`clik.scenarios.scenario.parse_scenario`
validates the result.
"""

from __future__ import annotations

import copy
from typing import Any

OBSTACLES = "obstacles"
"""The one array of tables of a scenario; its entries are addressed by name."""


class KeyPathError(LookupError):
    """A key path that does not address a key of the scenario.

    Attributes:
        path: The key path.
        problem: What is wrong, in words.
    """

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: {problem}")


def split(path: str) -> list[str]:
    """The parts of a key path; raises :class:`KeyPathError` on an empty part."""
    if not isinstance(path, str):
        raise KeyPathError(str(path), "expected a string like 'solver.gain'")
    parts = path.split(".")
    if not path or any(not p.strip() for p in parts):
        raise KeyPathError(path, "expected dot-separated key names like 'solver.gain'")
    return parts


def _obstacle(data: dict[str, Any], path: str, name: str) -> dict[str, Any]:
    obstacles = data.get(OBSTACLES)
    if not isinstance(obstacles, list):
        raise KeyPathError(path, "the base scenario has no [[obstacles]]")
    for entry in obstacles:
        if isinstance(entry, dict) and entry.get("name") == name:
            return entry
    names = [e.get("name") for e in obstacles if isinstance(e, dict)]
    raise KeyPathError(path, f"no obstacle named {name!r}; obstacles: {names}")


def get(data: dict[str, Any], path: str) -> Any:
    """The value at ``path``; raises :class:`KeyPathError` when absent."""
    node: Any = data
    parts = split(path)
    i = 0
    while i < len(parts):
        key = parts[i]
        if node is data and key == OBSTACLES and len(parts) > 1:
            node, i = _obstacle(data, path, parts[1]), i + 2
            continue
        if not isinstance(node, dict) or key not in node:
            raise KeyPathError(path, "not in the base scenario")
        node, i = node[key], i + 1
    return node


def substitute(data: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    """A deep copy of ``data`` with each key path of ``values`` set.

    Missing tables along a path are created (``solver.damping`` works when the
    base has no ``damping``); obstacles must exist by name. Whether the result
    is a valid scenario is for :func:`clik.scenarios.scenario.parse_scenario` to say.

    Raises:
        KeyPathError: A path goes through a value that is not a table, or names
            an obstacle that does not exist.
    """
    out = copy.deepcopy(data)
    for path, value in values.items():
        parts = split(path)
        node: dict[str, Any] = out
        i = 0
        while i < len(parts) - 1:
            key = parts[i]
            if node is out and key == OBSTACLES:
                if len(parts) < 3:
                    raise KeyPathError(path, "expected obstacles.<name>.<key>")
                node, i = _obstacle(out, path, parts[1]), i + 2
                continue
            child = node.setdefault(key, {})
            if not isinstance(child, dict):
                raise KeyPathError(path, f"{'.'.join(parts[: i + 1])} is a value, not a table")
            node, i = child, i + 1
        if i != len(parts) - 1:
            raise KeyPathError(path, "expected obstacles.<name>.<key>")
        node[parts[-1]] = copy.deepcopy(value)
    return out


def leaves(data: dict[str, Any]) -> list[str]:
    """Key paths of every value of a scenario dict (obstacles by name), in file order."""
    out: list[str] = []

    def walk(node: dict[str, Any], prefix: str) -> None:
        for key, value in node.items():
            path = f"{prefix}{key}"
            if not prefix and key == OBSTACLES and isinstance(value, list):
                for entry in value:
                    if isinstance(entry, dict) and isinstance(entry.get("name"), str):
                        walk(entry, f"{OBSTACLES}.{entry['name']}.")
            elif isinstance(value, dict):
                walk(value, f"{path}.")
            else:
                out.append(path)

    walk(data, "")
    return out


def from_scenario_key(data: dict[str, Any], key: str) -> str:
    """A :class:`~clik.errors.ScenarioError` key (``obstacles[0].radius``) as a key path."""
    if key.startswith(f"{OBSTACLES}["):
        index, _, rest = key[len(OBSTACLES) + 1 :].partition("]")
        obstacles = data.get(OBSTACLES)
        if index.isdigit() and isinstance(obstacles, list) and int(index) < len(obstacles):
            name = obstacles[int(index)].get("name")
            if isinstance(name, str):
                return f"{OBSTACLES}.{name}{rest}"
    return key
